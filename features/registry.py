"""The one public call, ``extract(scan, method=..., **params)``, and the table of methods behind it.

Each method module registers a typed config dataclass and a pure function ``(scan, config) ->
FeatureSet``; ``**params`` override fields of that method's config.
"""

from __future__ import annotations

import dataclasses
import importlib
import importlib.util
from dataclasses import dataclass
from typing import Any, Callable

from lms200 import Scan

from .errors import ConfigError
from .types import FeatureSet

# name -> module that registers it on import (kept lazy so `import features` stays cheap)
_METHOD_MODULES: dict[str, str] = {
    "sensor": "features.sensor",
    "split_merge": "features.baselines.split_merge",
    "iepf": "features.baselines.iepf",
    "hough": "features.baselines.hough",
    "ransac": "features.baselines.ransac",
}


@dataclass(frozen=True)
class Method:
    """A registered extractor: its typed config, its default config (built and checked once), the
    run function and the implementation it runs on ("numba": compiled, "numpy": vectorised)."""

    name: str
    config_type: type
    run: Callable[[Scan, Any], FeatureSet]
    default: Any
    backend: str


_REGISTRY: dict[str, Method] = {}


class UnknownMethodError(ConfigError):
    """The method name or one of its parameters does not exist."""


def register(name: str, config_type: type, run: Callable[[Scan, Any], FeatureSet], backend: str = "numpy") -> None:
    """Register an extractor under ``name`` (called by the method's module on import)."""
    _REGISTRY[name] = Method(name, config_type, run, config_type(), backend)


def get_method(name: str) -> Method:
    """The registered method ``name``; raises UnknownMethodError listing the known ones."""
    if name not in _REGISTRY and name in _METHOD_MODULES:
        try:
            importlib.import_module(_METHOD_MODULES[name])
        except ModuleNotFoundError as exc:
            if exc.name != _METHOD_MODULES[name]:
                raise
    if name not in _REGISTRY:
        raise UnknownMethodError(
            f"unknown extraction method {name!r}; available: {', '.join(available_methods())}"
        )
    return _REGISTRY[name]


def available_methods() -> list[str]:
    """Names of the methods whose modules are installed."""
    names = []
    for name, module in _METHOD_MODULES.items():
        if name in _REGISTRY:
            names.append(name)
            continue
        try:
            importlib.import_module(module)
        except ModuleNotFoundError as exc:
            if exc.name != module:
                raise
        if name in _REGISTRY:
            names.append(name)
    return names + sorted(n for n in _REGISTRY if n not in _METHOD_MODULES)


def make_config(method: str, **params: Any) -> Any:
    """The method's default config with ``params`` overriding fields; unknown names raise."""
    m = get_method(method)
    known = {f.name for f in dataclasses.fields(m.config_type) if f.init}
    unknown = sorted(set(params) - known)
    if unknown:
        raise UnknownMethodError(
            f"unknown parameter(s) {unknown} for method {method!r}; known: {sorted(known)}"
        )
    return m.config_type(**params)


def backend_of(method: str, config: Any = None) -> str:
    """The implementation ``method`` runs on: "numba" (compiled: sensor, split_merge, iepf) or
    "numpy" (vectorised: hough, ransac). Speed comparisons report it per method; ``config`` is
    accepted for callers that pass one (every config of a method runs on the same one)."""
    return get_method(method).backend


def extract(scan: Scan, method: str = "sensor", config: Any = None, **params: Any) -> FeatureSet:
    """Extract lines and corners from ``scan`` with ``method``.

    Args:
        scan: the laser scan (``lms200.Scan``).
        method: extractor name: "sensor" (the paper's), "split_merge", "iepf", "hough", "ransac".
        config: a ready config object of that method (then ``params`` must be empty).
        **params: overrides of the method's config defaults.

    Returns:
        The FeatureSet, geometry in the scan's sensor frame.
    """
    m = _REGISTRY.get(method) or get_method(method)
    if config is None:
        config = make_config(method, **params) if params else m.default
    elif params:
        config = dataclasses.replace(config, **params)
    return m.run(scan, config)
