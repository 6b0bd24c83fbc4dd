"""YAML read the way numbers are written: PyYAML follows YAML 1.1, in which ``1e9``, ``5e-3`` or
``1E6`` (no dot, or no sign in the exponent) are strings, so a config value ``noise_sigma: 5e-3``
reached the code as text. :func:`load` reads them as floats, as YAML 1.2 and Python do; everything
else is PyYAML's safe loader unchanged."""

from __future__ import annotations

import re
from typing import Any

import yaml


class Loader(yaml.SafeLoader):
    """The safe loader with YAML 1.2 floats (``1e9``, ``5e-3``)."""


Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                   |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                   |[-+]?\.[0-9_]+(?:[eE][-+]?[0-9]+)?)$""", re.X),
    list("-+0123456789."),
)


def load(text: str) -> Any:
    """Parse YAML text with :class:`Loader` (raises ``yaml.YAMLError`` as ``yaml.safe_load`` does)."""
    return yaml.load(text, Loader=Loader)  # noqa: S506 - Loader is a SafeLoader
