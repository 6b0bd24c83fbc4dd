"""YAML read the way numbers are written: PyYAML follows YAML 1.1, in which ``1e9``, ``5e-3`` or
``1E6`` (no dot, or no sign in the exponent) are strings, so a config value ``noise_sigma: 5e-3``
reached the code as text. :func:`load` reads them as floats, as YAML 1.2 and Python do.

Two more departures from PyYAML's safe loader, both refusals of what it took silently or crashed
on: a key given twice in one mapping (PyYAML kept the last, so ``noise_sigma: 0.005`` followed
further down by ``noise_sigma: 0.5`` simulated the second without a word; YAML 1.2 forbids it)
and nesting too deep for Python's recursion limit (a RecursionError, not a YAML error). Both
raise ``yaml.YAMLError`` with the line, as any malformed YAML does."""

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


class DuplicateKey(yaml.YAMLError):
    """A mapping that gives one key twice (PyYAML keeps the last silently)."""


def _construct_mapping(loader: Loader, node: yaml.MappingNode, deep: bool = False) -> Any:
    """SafeLoader's mapping, refusing a key written twice (merge keys ``<<`` may be overridden)."""
    if isinstance(node, yaml.MappingNode):
        seen: set[Any] = set()
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                continue
            key = loader.construct_object(key_node, deep=True)
            try:
                duplicate = key in seen
                seen.add(key)
            except TypeError:  # an unhashable key: the base constructor says so
                continue
            if duplicate:
                raise DuplicateKey(f"key {key!r} given twice (again at line {key_node.start_mark.line + 1})")
    return yaml.SafeLoader.construct_mapping(loader, node, deep=deep)


Loader.construct_mapping = _construct_mapping  # type: ignore[method-assign,assignment]


class TooDeep(yaml.YAMLError):
    """YAML nested deeper than the parser's recursion allows."""


def load(text: str) -> Any:
    """Parse YAML text with :class:`Loader` (raises ``yaml.YAMLError`` as ``yaml.safe_load`` does,
    and for a duplicate key or nesting too deep to parse)."""
    try:
        return yaml.load(text, Loader=Loader)  # noqa: S506 - Loader is a SafeLoader
    except RecursionError:
        raise TooDeep("nested too deeply to parse") from None
