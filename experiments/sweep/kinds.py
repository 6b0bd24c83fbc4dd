"""The built-in cell kinds: an extractor scored against ground truth, and the SLAM against truth.

Parameters (flat, as in the sweep file): ``method``, ``world`` (default office), ``seed``,
``duration`` (s of simulated time), ``rate_hz`` (scans per second kept), ``sensor.*`` (fields of
``sim.SensorConfig``; ``sensor_file`` names a sensor YAML, e.g. from ``lmsbench calibrate``, that
they override), ``extractor.*`` (the extractor's config fields), ``slam.*`` (fields of
``slam.SlamConfig``; ``extractor.FIELD``, or the older ``slam.extractor_params.FIELD``, a field of the SLAM's extractor). Each returns a dict of scalar metrics.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import warnings
from pathlib import Path
from typing import Any, Iterable

import numpy as np

from experiments.compare import Source, compare, summarise
from experiments.evaluate import sensor_config, simulate_run, split_params, truths_for
from experiments.overrides import OverrideError, extractor_overrides
from lms200 import LmsbenchError
from lms200.errors import LmsbenchWarning

from .cells import INPUTS_KEY

EXTRACT_DEFAULTS = {"method": "sensor", "world": "office", "duration": 5.0, "rate_hz": 4.0}
SLAM_DEFAULTS = {"world": "office", "duration": 30.0, "rate_hz": None}


class _Content:
    """A file's bytes as read once by a cell, equal to another by its path and digest alone (an
    ``lru_cache`` key that does not hash the bytes)."""

    def __init__(self, path: str, data: bytes) -> None:
        self.path, self.data = path, data
        self.digest = _digest(data)  # as input_digests makes it

    def _key(self) -> tuple[str, str]:
        return (self.path, self.digest)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _Content) and self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())


def _read_inputs(params: dict[str, Any]) -> dict[str, _Content]:
    """The files a built-in cell reads (the parameters :func:`input_digests` names), each read once:
    the cell's digests and its computation come from the same bytes."""
    return {name: _Content(path, Path(path).read_bytes()) for name, path in _input_files(params).items()}


def _input_files(params: dict[str, Any]) -> dict[str, str]:
    """The files a built-in cell reads, by parameter name: its ``sensor_file`` and a ``world`` that is a
    world.json (one rule for the key's digests, :func:`input_digests`, and the cell's read, :func:`_read_inputs`:
    were they to differ, every such cell would count as changed while it ran and never be stored)."""
    files = {"sensor_file": params.get("sensor_file"), "world": params.get("world")}
    return {name: str(path) for name, path in files.items()
            if path is not None and (name != "world" or str(path).endswith(".json"))}


def _digest(data: bytes) -> str:
    """A file's digest in a cell's key: the first 16 hex digits of its SHA-256."""
    import hashlib

    return hashlib.sha256(data).hexdigest()[:16]


@functools.lru_cache(maxsize=4)
def _run(world: str, seed: int, duration: float, rate_hz: float | None, sensor_items: tuple, with_truth: bool,
         sensor_file: _Content | None = None, world_file: _Content | None = None):
    """The world, the sensor, the simulated records and their visible truths, cached per worker: a
    grid over extractor parameters simulates each (world, seed, sensor) once per worker process.
    ``sensor_file`` and ``world_file`` (a world.json) are the files' bytes as the cell read them
    (:func:`_read_inputs`), keying the cache by path and digest: by path alone, a worker that outlives a sweep (a
    ``--scheduler``'s, or this process for ``run_sweep``) ran the next sweep's cells on the old
    content of an edited sensor file or world.json; and the files were read twice, for the
    digest and for the run, so an edit between the two computed the new content under the old digest
    (a row stored under the key of the content it did not read, and cached for later cells)."""
    with warnings.catch_warnings():  # an old degree field (sensor.resolution_deg, a sensor file's) was said once,
        warnings.simplefilter("ignore", LmsbenchWarning)  # when the sweep was read and checked, not in every worker
        sensor = sensor_config(dict(sensor_items), sensor_file.path if sensor_file else None,
                               sensor_file.data if sensor_file else None)
    world_obj, records = simulate_run(world, seed, duration, sensor, rate_hz, world_file.data if world_file else None)
    truths = truths_for(world_obj, records, sensor) if with_truth else None
    return world_obj, sensor, records, truths


def _records(params: dict[str, Any], defaults: dict[str, Any], with_truth: bool):
    """The cell's run (:func:`_run`: world, sensor, records, truths) and the digests of the files it
    read (parameter name -> digest)."""
    p = {**defaults, **params}
    rate = p.get("rate_hz")
    rate = None if rate is None or (isinstance(rate, float) and math.isnan(rate)) else float(rate)
    sensor_items = tuple(sorted(split_params(p, "sensor").items()))
    files = _read_inputs(p)
    run = _run(str(p["world"]), int(p.get("seed", 0)), float(p["duration"]), rate, sensor_items, with_truth,
               files.get("sensor_file"), files.get("world"))
    return run, {name: content.digest for name, content in files.items()}


def extract_cell(params: dict[str, Any]) -> dict[str, Any]:
    """One extractor over a simulated run, scored scan by scan against the visible ground truth
    (``experiments.compare``): the pooled summary row (f1, precision, recall, rho_rms_mm,
    alpha_rms_deg, corner_*, explained, us_median, time_ms_median, lines_per_scan, ...)."""
    p = {**EXTRACT_DEFAULTS, **params}
    (_, sensor, records, truths), used = _records(p, EXTRACT_DEFAULTS, with_truth=True)
    method = str(p["method"])
    noise = float(sensor.noise_sigma)
    source = Source.from_records(records, truths, name=str(p["world"]), seed=int(p.get("seed", 0)))  # named in errors
    params = extractor_overrides(p, [method], other_methods=True)
    table = compare([source], [method], params=params, sigma=max(noise, 0.001))
    row = summarise(table, reference=method).iloc[0]
    # the speed ratios are against the cell's own method (one method a cell): 1.0 in every row
    skip = {"source", "method", "kind", "seeds", "speed_vs_sensor", "cpu_speed_vs_sensor"}
    metrics: dict[str, Any] = {k: float(v) for k, v in row.items() if k not in skip and isinstance(v, (int, float, np.number))}
    return {**metrics, INPUTS_KEY: used}


def slam_cell(params: dict[str, Any]) -> dict[str, Any]:
    """The odometry-free SLAM over a simulated run: trajectory error against the true poses."""
    from experiments.slamrun import deskew_for_sensor
    from slam import SlamConfig, run_slam

    from experiments.user_methods import ensure_method, scans_of

    p = {**SLAM_DEFAULTS, **params}
    (_, sensor, records, _), used = _records(p, SLAM_DEFAULTS, with_truth=False)
    nested = slam_config_dict(p)
    ensure_method(str(nested.get("extractor", "")))  # a MODULE:FUNCTION extractor, registered in this worker
    config = deskew_for_sensor(SlamConfig.from_dict(nested), bool(sensor.interlaced))
    with scans_of(f"{p['world']}:{int(p.get('seed', 0))}", records):  # a failing MODULE:FUNCTION names its scan
        result = run_slam(records, config)
    return {**slam_metrics(result, records), INPUTS_KEY: used}


def slam_config_dict(params: dict[str, Any]) -> dict[str, Any]:
    """The nested dict of ``SlamConfig.from_dict`` from a cell's flat ``slam.*`` parameters
    (``slam.SECTION.FIELD`` -> ``{SECTION: {FIELD: value}}``) and the SLAM extractor's fields,
    ``extractor.[METHOD.]FIELD`` as compare --set and extraction sweeps spell them (or the older
    ``slam.extractor_params.NAME``; one field set both ways is refused).

    Raises:
        OverrideError: an ``extractor.*`` field the SLAM's extractor does not have, or set twice."""
    from slam import SlamConfig

    slam_params = split_params(params, "slam")
    extractor_params = split_params(slam_params, "extractor_params")  # slam.extractor_params.NAME
    slam_params = {k: v for k, v in slam_params.items() if not k.startswith("extractor_params.")}
    flat = {k: v for k, v in params.items() if k.startswith("extractor.")}
    if flat:  # the one spelling: into the SLAM's extractor_params
        method = str(slam_params.get("extractor", SlamConfig().extractor))
        more = extractor_overrides(flat, [method])[method]
        both = sorted(set(more) & set(extractor_params))
        if both:
            raise OverrideError(f"extractor.{both[0]} and slam.extractor_params.{both[0]} both set one field of the "
                                "SLAM's extractor; give it once (extractor.FIELD)")
        extractor_params = {**extractor_params, **more}
    if extractor_params:
        slam_params["extractor_params"] = extractor_params
    nested: dict[str, Any] = {}
    for key, value in slam_params.items():  # slam.SECTION.FIELD -> {"SECTION": {"FIELD": value}}
        section, _, name = key.partition(".")
        if name:
            nested.setdefault(section, {})[name] = value
        else:
            nested[key] = value
    return nested


def slam_metrics(result, records) -> dict[str, float]:
    """Trajectory error against the true poses after 2-D alignment (``slam.metrics.ate``, m and
    rad), final position error after that alignment (m), confirmed map lines, scans, divergence."""
    from slam import metrics

    truth = true_trajectory(records)
    est = np.asarray(result.trajectory, dtype=float)
    ate = metrics.ate(est, truth)
    aligned = align(est[:, 1:3], ate.rotation, ate.translation)
    final = float(np.hypot(*(aligned[-1] - truth[-1, 1:3])))
    diag = getattr(result, "diagnostics", {}) or {}
    return {"ate_rms": float(ate.rmse), "ate_max": float(ate.max), "heading_rms": float(ate.heading_rmse),
            "final_error_m": final, "n_map_lines": float(len(result.map_lines)),
            "diverged": float(bool(diag.get("diverged", False))), "scans": float(len(records))}


def true_trajectory(records) -> np.ndarray:
    """(n, 4) t, x, y, theta of the records' true poses."""
    return np.array([[r.scan.stamp, *r.truth] for r in records if r.truth is not None], dtype=float).reshape(-1, 4)


def align(xy: np.ndarray, rotation: float, translation) -> np.ndarray:
    """Points (n, 2) rotated by ``rotation`` (rad) about the origin, then shifted by ``translation`` (m)."""
    c, s = np.cos(rotation), np.sin(rotation)
    xy = np.asarray(xy, float).reshape(-1, 2)
    return np.column_stack((c * xy[:, 0] - s * xy[:, 1], s * xy[:, 0] + c * xy[:, 1])) + np.asarray(translation, float)


def _fields(config_type: type) -> set[str]:
    return {f.name for f in dataclasses.fields(config_type)}


def _unknown(cells: Iterable[dict[str, Any]], prefix: str, known_for) -> None:
    """Raise SweepSpecError for the first ``prefix.NAME`` parameter whose NAME is not in
    ``known_for(cell)`` (a set of field names, and what they are the fields of)."""
    from .spec import SweepSpecError

    for cell in cells:
        names = split_params(cell, prefix)
        if not names:
            continue
        known, owner = known_for(cell)
        bad = sorted(set(names) - known, key=str)
        if bad:
            raise SweepSpecError(f"unknown parameter(s) {[f'{prefix}.{n}' for n in bad]}: not fields of {owner}; "
                                 f"known {prefix}.* names: {sorted(known)}")


def _sensor_fields(cell: dict[str, Any]) -> tuple[set[str], str]:
    from sim import SensorConfig
    from sim.sensor import DEGREE_FIELDS

    return _fields(SensorConfig) | set(DEGREE_FIELDS), "sim.SensorConfig"  # the old degree names: read, converted


def _extractor_fields(method: str) -> tuple[set[str], str]:
    from features.registry import UnknownMethodError, get_method

    from experiments.user_methods import ensure_method

    from .spec import SweepSpecError

    from lms200 import LmsbenchError

    try:
        ensure_method(method)
        m = get_method(method)
    except (UnknownMethodError, LmsbenchError) as exc:
        raise SweepSpecError(str(exc)) from None
    return _fields(m.config_type), f"the {method!r} extractor's {m.config_type.__name__}"


def _read_sensor_files(cells: Iterable[dict[str, Any]]) -> dict[str, Any]:
    """Every ``sensor_file`` of the cells, each read once: path -> its ``sim.SensorConfig``
    (raises LmsbenchError naming a file that does not read as one)."""
    from sim import SensorConfig

    from experiments.options import check_sim2real_finished

    from .spec import SweepSpecError

    paths = sorted({str(c["sensor_file"]) for c in cells if c.get("sensor_file") is not None})
    files = {}
    for path in paths:
        try:
            check_sim2real_finished(path)
            files[path] = SensorConfig.from_yaml(path)
        except LmsbenchError as exc:
            raise SweepSpecError(f"sensor_file: {exc}{_relative_hint(path)}") from None
    return files


def _relative_hint(path: str) -> str:
    """For a relative path that is not there: where it was looked for (a sweep file's sensor_file
    or world.json beside it, run from another folder, was 'no such file' and no more)."""

    if Path(path).is_absolute() or Path(path).exists():
        return ""
    return f" (a sweep's relative paths are read from the current folder, {Path.cwd()}, not the sweep file's)"


def _check_plain(cells: list[dict[str, Any]], defaults: dict[str, Any], extra: set[str],
                 prefixes: tuple[str, ...]) -> None:
    """Plain (unprefixed) names are known ones, dotted names start with one of ``prefixes`` (the
    configs the kind reads), and world, duration and rate_hz have usable values."""
    from experiments.options import MAX_DURATION_S, MIN_DURATION_S, check_world_file, known_worlds

    from .spec import SweepSpecError

    known = set(defaults) | extra | {"seed", "sensor_file"}
    read = ", ".join(f"{prefix}.*" for prefix in prefixes)
    for cell in cells:
        plain = {k for k in cell if "." not in k}
        bad = sorted(plain - known, key=str)
        if bad:
            raise SweepSpecError(f"unknown parameter(s) {bad}; known plain names: {sorted(known)} "
                                 f"(and {read} fields)")
        # a misspelt or foreign prefix (sensorr.noise_sigma, extractors.k; slam.* in an extract sweep) was
        # taken as a column and read by nothing: the cells ran the defaults, exit 0
        other = sorted(k for k in cell if "." in k and k.partition(".")[0] not in prefixes)
        if other:
            raise SweepSpecError(f"unknown parameter(s) {other}: these cells read {read} fields and the plain "
                                 f"names {sorted(known)}, so they would set nothing")
        p = {**defaults, **cell}
        world = str(p["world"])
        if world not in known_worlds() and not world.endswith(".json"):
            raise SweepSpecError(f"world: unknown world {world!r}; known worlds: {', '.join(known_worlds())} "
                                 "or a world.json")
        try:  # a missing one failed in every cell
            check_world_file(world)
        except LmsbenchError as exc:
            raise SweepSpecError(f"world: {exc}{_relative_hint(world)}") from None
        duration = p["duration"]
        if isinstance(duration, bool) or not isinstance(duration, (int, float)) \
                or not MIN_DURATION_S <= duration <= MAX_DURATION_S:  # shorter: no scan in the cell's run
            raise SweepSpecError(f"duration: must be a number of seconds in [{MIN_DURATION_S:g}, {MAX_DURATION_S:g}], "
                                 f"got {duration!r}")
        rate = p.get("rate_hz")
        from lms200.timing import MIN_RATE_HZ, RATE_FLOOR_TEXT

        if rate is not None and (isinstance(rate, bool) or not isinstance(rate, (int, float))
                                 or not MIN_RATE_HZ <= rate < math.inf):  # a cell's run lasts at most an hour
            raise SweepSpecError(f"rate_hz: must be a number of scans/s of at least {RATE_FLOOR_TEXT}, or null, "
                                 f"got {rate!r}")


def _sensor_key(cell: dict[str, Any]) -> tuple:
    """What decides a cell's sensor: its ``sensor.*`` items and its ``sensor_file``."""
    return tuple(sorted(split_params(cell, "sensor").items())), cell.get("sensor_file")


def _sensor_words(key: tuple) -> str:
    """A cell's sensor as a message names it: ``the simulated scans (sensor {...}, FILE)``."""
    items, sensor_file = key
    said = [str(dict(items)) if items else "the default sensor"] + ([str(sensor_file)] if sensor_file is not None else [])
    return f"the simulated scans ({', '.join(said)})"


def _check_sensors(cells: list[dict[str, Any]], files: dict[str, Any], defaults: dict[str, Any]) -> dict[tuple, Any]:
    """Every distinct sensor of the cells builds (a bad value fails before any cell runs), and the
    cell's ``rate_hz`` is one it gives (``rate_hz: 1e300`` failed in every cell, "more than the
    sensor gives", exit 1); a cell's ``sensor_file`` is taken from ``files`` (read once, by
    :func:`_read_sensor_files`). Returns each distinct sensor by :func:`_sensor_key`."""
    from lms200 import LmsbenchError
    from lms200.timing import check_scan_rate

    from .spec import SweepSpecError

    seen = set()
    sensors: dict[tuple, Any] = {}
    for cell in cells:
        items = tuple(sorted(split_params(cell, "sensor").items()))
        rate = {**defaults, **cell}.get("rate_hz")
        key = (items, cell.get("sensor_file"), rate)
        if key in seen:
            continue
        seen.add(key)
        sensor_file = cell.get("sensor_file")
        try:
            with warnings.catch_warnings():  # an old degree name was said when the sweep was read (spec.py)
                warnings.simplefilter("ignore", LmsbenchWarning)
                if sensor_file is None:
                    sensor = sensor_config(dict(items))
                else:  # the file's config with the overrides on top, as sensor_config builds it
                    sensor = files[str(sensor_file)].replace(**dict(items))
        except (LmsbenchError, TypeError, ValueError) as exc:
            raise SweepSpecError(f"sensor {dict(items)}: {exc}") from None
        try:
            check_scan_rate(rate, sensor.resolution)
        except LmsbenchError as exc:
            raise SweepSpecError(str(exc)) from None
        sensors[_sensor_key(cell)] = sensor
    return sensors


def check_extract_params(cells: list[dict[str, Any]]) -> None:
    """Every ``sensor.*`` and ``extractor.*`` name of every cell is a field of its config, every
    distinct sensor and extractor config builds, and the plain names are known with usable values
    (checked before any cell runs, so a misspelled name or a bad value fails at once instead of in
    every cell)."""
    from features.registry import make_config

    from lms200 import LmsbenchError

    files = _read_sensor_files(cells)
    _unknown(cells, "sensor", _sensor_fields)
    _check_plain(cells, EXTRACT_DEFAULTS, set(), ("sensor", "extractor"))
    sensors = _check_sensors(cells, files, EXTRACT_DEFAULTS)
    from features.registry import step_problem

    from .spec import SweepSpecError

    seen = set()
    for cell in cells:
        method = str({**EXTRACT_DEFAULTS, **cell}["method"])
        _extractor_fields(method)  # an unknown method, listing the known ones
        try:
            overrides = extractor_overrides(cell, [method], other_methods=True).get(method, {})
        except OverrideError as exc:
            raise SweepSpecError(str(exc)) from None
        key = repr((method, sorted(overrides.items(), key=lambda kv: kv[0]), _sensor_key(cell)))  # corners: a dict
        if key in seen:
            continue
        seen.add(key)
        try:
            config = make_config(method, **overrides)
        except (LmsbenchError, TypeError, ValueError) as exc:
            raise SweepSpecError(f"extractor {method} {overrides}: {exc}") from None
        # a baseline's breakpoint_lambda (or its corners') not below the cell's beam step: every such cell failed
        # after its simulation, compare refusing its first scan (features.registry.check_step); said now, compare's words
        problem = step_problem(config, sensors[_sensor_key(cell)].angle_increment, method, _sensor_words(_sensor_key(cell)))
        if problem is not None:
            raise SweepSpecError(f"extractor {method} {overrides}: {problem}")


def check_slam_params(cells: list[dict[str, Any]]) -> None:
    """Every ``sensor.*``, ``slam.*`` (``slam.SECTION.FIELD`` for the nested sections),
    ``extractor.*`` and ``slam.extractor_params.*`` name is a field of its config."""
    from slam import SlamConfig

    files = _read_sensor_files(cells)
    _unknown(cells, "sensor", _sensor_fields)
    slam_cells = [{k: v for k, v in c.items() if not k.startswith("slam.extractor_params.")} for c in cells]
    from slam.config import SECTIONS

    known = (_fields(SlamConfig) - set(SECTIONS)) | {f"{sec}.{f}" for sec, cls in SECTIONS.items() for f in _fields(cls)}
    _unknown(slam_cells, "slam", lambda c: (known, "slam.SlamConfig"))
    default = SlamConfig().extractor
    _unknown(cells, "slam.extractor_params", lambda c: _extractor_fields(str(c.get("slam.extractor", default))))
    _check_plain(cells, SLAM_DEFAULTS, set(), ("sensor", "slam", "extractor"))
    sensors = _check_sensors(cells, files, SLAM_DEFAULTS)
    from types import SimpleNamespace

    from slam.run import check_first_scan
    from lms200 import LmsbenchError

    from experiments.user_methods import ensure_method

    from .spec import SweepSpecError

    seen = set()
    for cell in cells:
        try:
            nested = slam_config_dict(cell)
        except OverrideError as exc:  # an extractor.* field the SLAM's extractor lacks, or set both ways
            raise SweepSpecError(str(exc)) from None
        motion = nested.get("motion")
        if isinstance(motion, dict) and motion.get("use_odometry") is True:  # ran without it, the column saying True
            raise SweepSpecError("slam.motion.use_odometry: true, but the slam cells' simulated runs carry no "
                                 "odometry: the filter would run without it, as with false")
        key = repr((sorted(nested.items(), key=lambda kv: kv[0]), _sensor_key(cell)))
        if key in seen:
            continue
        seen.add(key)
        try:
            ensure_method(str(nested.get("extractor", "")))  # a MODULE:FUNCTION extractor: registered before the check
            config = SlamConfig.from_dict(nested)
        except (LmsbenchError, TypeError, ValueError, KeyError) as exc:
            raise SweepSpecError(f"slam {nested}: {exc}") from None
        # what run_slam refuses at its first scan (a stride or min_line_points beyond the sensor's beams, an
        # extractor's breakpoint_lambda not below its step): every such cell failed after its simulation
        sensor = sensors[_sensor_key(cell)]
        try:
            check_first_scan(SimpleNamespace(ranges=np.empty(sensor.n_beams), angle_increment=sensor.angle_increment),
                             config, _sensor_words(_sensor_key(cell)))
        except LmsbenchError as exc:
            raise SweepSpecError(f"slam {nested}: {exc}") from None


def input_digests(params: dict[str, Any], seen: dict[str, str]) -> dict[str, str]:
    """Digests of the files a built-in cell reads (its ``sensor_file``, a ``world`` that is a
    world.json), by parameter name, for its key (``spec.cell_key``); ``seen`` holds the digests of
    this run by path, so each file is read once. A resumed sweep took the cells it had computed
    with a sensor file or world since edited as done ("2 already done"), their rows those of the
    old file, silently."""
    out = {}
    for name, path in _input_files(params).items():
        if path not in seen:
            seen[path] = _digest(Path(path).read_bytes())
        out[name] = seen[path]
    return out


extract_cell.check_params = check_extract_params  # type: ignore[attr-defined]
slam_cell.check_params = check_slam_params  # type: ignore[attr-defined]
extract_cell.input_digests = input_digests  # type: ignore[attr-defined]
slam_cell.input_digests = input_digests  # type: ignore[attr-defined]
