"""The one spelling of extractor overrides, for ``lmsbench compare --set`` and ``lmsbench slam
--set``, sweep files (extraction and SLAM sweeps) and the library: flat names ``extractor.FIELD``
(that field of every extractor of the run that has it) or ``extractor.METHOD.FIELD`` (one
extractor's field), resolved to ``{method: {field: value}}``, the ``params`` argument of
``experiments.compare.compare`` (a SLAM run's ``extractor_params`` is its one method's entry).
"""

from __future__ import annotations

import argparse
import dataclasses
import re
from typing import Any, Mapping, Sequence

import yaml

from features.registry import MODE_FIELDS, mode_fields_read
from lms200 import LmsbenchError
from lms200.yamlio import load as load_yaml

PREFIX = "extractor"
SLAM_SECTIONS = ("motion", "observations", "alignment", "keyframes", "loop_closure", "association", "landmarks",
                 "prealign", "consistency")
"""The sections of ``slam.SlamConfig`` (its nested dataclasses), named in ``--set``'s hint."""


class OverrideError(LmsbenchError, ValueError):
    """An override names no field of the extractors that run (the message lists the known ones)."""


def set_option(text: str) -> tuple[str, Any]:
    """One ``--set extractor.[METHOD.]FIELD=VALUE`` of the command line: (key, value read as YAML)."""
    key, eq, value = text.partition("=")
    if eq and key != key.strip():  # ' extractor.k=3' (a quoted word's space) was told "(write extractor. extractor.k)"
        raise argparse.ArgumentTypeError(f"--set {text!r}: a space around the field's name; write "
                                         f"{key.strip()}={value.strip()}")
    if not eq or not key.startswith(PREFIX + ".") or len(key) <= len(PREFIX + "."):
        hint = f" (write extractor.{key})" if eq and "." in key and not key.startswith(PREFIX + ".") else ""
        section = key.split(".", 1)[0]
        if eq and "." in key and section in SLAM_SECTIONS:  # 'prealign.scan_velocity=false' was told
            # "(write extractor.prealign.scan_velocity)", a name no extractor has
            field = key.split(".", 1)[1]
            hint = (f" ({key} is a SLAM setting, not an extractor's: give it to lmsbench slam in --config FILE.yaml "
                    f"as '{section}: {{{field}: {value.strip() or '...'}}}')")
        raise argparse.ArgumentTypeError(f"--set takes extractor.FIELD=VALUE or extractor.METHOD.FIELD=VALUE, "
                                         f"got {text!r}{hint}")
    if not value.strip():  # YAML reads nothing as null: "sensor: k must be a whole number (default 3), got None"
        raise argparse.ArgumentTypeError(f"--set {key}: no value after '='; give {key}=VALUE")
    try:
        return key, load_yaml(value)
    except yaml.YAMLError as exc:  # yamlio's reason: '1_0 is read as 10: YAML 1.1 drops ...' was 'is not a value'
        reason = re.sub(r"^line \d+, column \d+: ", "", str(exc))  # the position within one value says nothing
        raise argparse.ArgumentTypeError(f"--set {key}: {value!r} is not a value ({reason})") from None


def check_set_once(params: list[tuple[str, Any]]) -> None:
    """A field set twice (``--set extractor.k=2 ... --set extractor.k=5``) ran the last value alone,
    as an option given twice did (``--seed 1 ... --seed 2``); ``extractor.k`` beside
    ``extractor.sensor.k`` is two fields (the method's own wins for it)."""
    seen: dict[str, Any] = {}
    for key, value in params:
        if key in seen:
            raise OverrideError(f"--set {key} is given twice ({key}={seen[key]!r} and {key}={value!r}); "
                                "set each field once")
        seen[key] = value


def _fields(method: str) -> list[str]:
    from features.registry import get_method

    from experiments.user_methods import ensure_method

    ensure_method(method)
    return [f.name for f in dataclasses.fields(get_method(method).config_type)]


def _corner_fields(method: str) -> list[str] | None:
    """The fields of ``method``'s corner step (its config's ``corners``, a dataclass: the baselines'
    CornerConfig), or None where ``corners`` is no such config (the sensor method's flag)."""
    from features.registry import get_method

    for f in dataclasses.fields(get_method(method).config_type):
        if f.name == "corners":
            default = f.default_factory() if f.default_factory is not dataclasses.MISSING else f.default
            if dataclasses.is_dataclass(default):
                return [g.name for g in dataclasses.fields(default)]
    return None


def _check_field(key: str, method: str, field: str, fields: list[str]) -> None:
    """OverrideError naming ``key`` and ``method`` for a ``field`` (``FIELD`` or ``corners.FIELD``) that
    ``method``'s config (of ``fields``) or its corner step does not have. An unknown corner field was
    left to the config's check, which names no method: `--set extractor.iepf.corners.bogus=1` said
    "corners: has no field 'bogus' (its fields: ...)"."""
    outer, _, inner = field.partition(".")
    if inner and outer == "corners" and outer in fields:
        known = _corner_fields(method)
        if known is not None and inner not in known:
            raise OverrideError(f"{key}: {method}'s corner step (corners) has no field {inner!r}; its fields: "
                                f"{', '.join(known)}")
        return  # the sensor method's corners, a flag: its config says so ("sensor: corners must be true or false")
    if field not in fields:
        raise OverrideError(f"{key}: {method} has no field {field!r}; its fields: {', '.join(fields)}")


def extractor_overrides(flat: Mapping[str, Any], methods: Sequence[str], *,
                        other_methods: bool = False) -> dict[str, dict[str, Any]]:
    """``{method: {field: value}}`` from the ``extractor.*`` entries of ``flat`` (others ignored).

    ``extractor.FIELD`` goes to every method in ``methods`` whose config has FIELD;
    ``extractor.METHOD.FIELD`` to METHOD alone. Raises :class:`OverrideError` for a method not in
    ``methods`` or a field no such method has; with ``other_methods`` (a sweep cell of one method
    in a grid over several), ``extractor.METHOD.FIELD`` of another known method is ignored."""
    from features.registry import available_methods

    fields = {m: _fields(m) for m in methods}
    out: dict[str, dict[str, Any]] = {m: {} for m in methods}
    head = PREFIX + "."
    for key, value in flat.items():
        if not key.startswith(head):
            continue
        name = key[len(head):]
        method, _, field = name.partition(".")
        if field:
            if method not in fields and other_methods and method in available_methods():
                _check_field(key, method, field, _fields(method))
                continue
            if method not in fields:
                known = methods if method in available_methods() else available_methods()
                raise OverrideError(f"{key}: {method!r} is not an extractor of this run; known: {', '.join(known)}")
            _check_field(key, method, field, fields[method])
            outer, _, inner = field.partition(".")
            if inner and outer == "corners" and outer in fields[method]:  # METHOD.corners.FIELD: the corner step's own
                corners = out[method].setdefault("corners", {})
                if isinstance(corners, dict):
                    corners[inner] = value
                    continue
            if field not in fields[method]:
                raise OverrideError(f"{key}: {method} has no field {field!r}; its fields: {', '.join(fields[method])}")
            out[method][field] = value
            continue
        targets = [m for m in methods if name in fields[m]]
        if not targets:
            known = sorted({f for fs in fields.values() for f in fs})
            raise OverrideError(f"{key}: no extractor of this run ({', '.join(methods)}) has a field {name!r}; "
                                f"fields: {', '.join(known)}")
        for m in targets:
            out[m].setdefault(name, value)  # an extractor.METHOD.FIELD entry wins, whatever the order
    return {m: p for m, p in out.items() if p}


def unread_marked(values: dict[str, Any], config: Any, range_maxes: Sequence[float] | set[float],
                  given: Mapping[str, Any]) -> dict[str, Any]:
    """``values`` (``config`` as plain data, for a run's config.yaml) with each mode-bound
    range-noise field the user set (``given``) that no scan of the run read (``range_maxes``, m)
    written as ``"V: not read (no MODE-mode scan)"``: the record said ``sigma_r: 0.02`` as if it
    had run. (A default the scans do not read stays: which one a scan reads is the method's rule.)"""
    _, unread = mode_fields_read(config, range_maxes, given)
    return {f: f"{v!r}: not read (no {MODE_FIELDS[f][0]}-mode scan)" if f in unread else v for f, v in values.items()}
