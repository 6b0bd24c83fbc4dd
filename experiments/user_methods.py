"""A user's own extractor in the comparison: ``lmsbench compare office --methods sensor
mypkg.lines:extract`` runs ``extract(scan) -> features.FeatureSet`` beside the built-in methods,
timed and scored the same way.

A name ``MODULE:FUNCTION`` is imported (the current folder first on the path, so a file
``./myext.py`` is ``myext:FUNCTION``) and registered in ``features.registry`` under that name, with
an empty config; the function receives the ``lms200.Scan`` and returns a ``FeatureSet`` (lines and
corners in the sensor frame). A function with a ``config_type`` attribute (a dataclass) is called
``fn(scan, config)`` and its config's fields can be set with ``--set extractor.MODULE:FUNCTION.FIELD=V``.
"""

from __future__ import annotations

import dataclasses
import importlib
import os
import sys
from typing import Any, Callable

from lms200 import LmsbenchError


class UserMethodError(LmsbenchError, ValueError):
    """A ``MODULE:FUNCTION`` extractor that cannot be loaded or returns the wrong thing."""


@dataclasses.dataclass(frozen=True)
class NoConfig:
    """The config of a user extractor that takes none."""


def is_user_method(name: str) -> bool:
    return ":" in name


def ensure_method(name: str) -> None:
    """Register the user extractor ``MODULE:FUNCTION`` (once per process); built-in names pass."""
    from features import registry

    if not is_user_method(name) or name in registry._REGISTRY:  # noqa: SLF001 - the registry's own table
        return
    fn = _load(name)
    config_type = getattr(fn, "config_type", None)
    takes_config = config_type is not None
    if takes_config and not dataclasses.is_dataclass(config_type):
        raise UserMethodError(f"{name}: its config_type must be a dataclass, got {config_type!r}")
    registry.register(name, config_type or NoConfig, _checked(name, fn, takes_config), backend="python")


def _load(name: str) -> Callable[..., Any]:
    module_name, _, attr = name.partition(":")
    if not module_name or not attr:
        raise UserMethodError(f"{name!r}: a user extractor is named MODULE:FUNCTION (e.g. myext:extract)")
    cwd = os.getcwd()
    added = cwd not in sys.path
    if added:
        sys.path.insert(0, cwd)
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise UserMethodError(f"{name}: cannot import module {module_name!r} ({exc}); it must be importable "
                              "from the current folder or PYTHONPATH") from None
    except Exception as exc:  # noqa: BLE001 - the user's module failed while importing
        raise UserMethodError(f"{name}: importing {module_name!r} failed: {type(exc).__name__}: {exc}") from None
    finally:
        if added:
            sys.path.remove(cwd)
    fn = module
    for part in attr.split("."):
        if not hasattr(fn, part):
            raise UserMethodError(f"{name}: module {module_name!r} has no {attr!r}")
        fn = getattr(fn, part)
    if not callable(fn):
        raise UserMethodError(f"{name}: {attr!r} is not callable")
    return fn


def _checked(name: str, fn: Callable[..., Any], takes_config: bool) -> Callable[[Any, Any], Any]:
    """``fn`` as a registry run function whose result must be a FeatureSet."""
    from features import FeatureSet

    def run(scan: Any, config: Any) -> Any:
        out = fn(scan, config) if takes_config else fn(scan)
        if not isinstance(out, FeatureSet):
            raise UserMethodError(f"{name} returned {type(out).__name__}, not a features.FeatureSet")
        return out

    run.__name__ = getattr(fn, "__name__", "run")
    return run
