"""The one public call, ``extract(scan, method=..., **params)``, and the table of methods behind it.

Each method module registers a typed config dataclass and a pure function ``(scan, config) ->
FeatureSet``; ``**params`` override fields of that method's config.
"""

from __future__ import annotations

import dataclasses
import importlib
import importlib.util
import math
import warnings
from dataclasses import dataclass
from collections.abc import Sequence
from typing import Any, Callable

import numpy as np

from lms200 import Scan
from lms200.errors import InputError, LmsbenchWarning
from lms200.finite import is_one_of

from .baselines.checks import MAX_BEAMS
from .batch import check_threads, common_geometry, run_pieces, scan_list
from .errors import ConfigError, ScanGeometryError, ScanTypeError, not_a_scan
from .types import FeatureSet, check_feature_set

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
    run_many: Callable[[Sequence[Scan], Any], list[FeatureSet]] | None = None
    thread_safe: bool = False  # run_many may run on several threads at once (and releases the GIL)


_REGISTRY: dict[str, Method] = {}
BACKENDS = ("numba", "numpy", "python")  # compiled, vectorised, a user's plain Python (experiments.user_methods)


class UnknownMethodError(ConfigError):
    """The method name or one of its parameters does not exist."""


def register(name: str, config_type: type, run: Callable[[Scan, Any], FeatureSet], backend: str = "numpy",
             run_many: Callable[[Sequence[Scan], Any], list[FeatureSet]] | None = None, thread_safe: bool = False) -> None:
    """Register an extractor under ``name`` (called by the method's module on import); ``run_many``
    extracts from a batch of scans of one geometry at once (else ``extract_many`` calls ``run``
    per scan); ``thread_safe``: ``extract_many`` may call ``run_many`` on pieces of a batch from
    several threads at once (it shares no state it writes and its compiled code releases the GIL).

    Raises:
        ConfigError: naming the argument: a ``name`` that is not a non-empty str or is a built-in
            method's (whose module alone registers it), a ``config_type`` that is not a dataclass, a
            ``run`` / ``run_many`` that is not callable, a ``backend`` other than "numba", "numpy" or
            "python", a ``thread_safe`` that is not a bool. (Each was taken, and failed at the first
            extract, or silently replaced the built-in method.)
    """
    if not isinstance(name, str) or not name.strip():
        raise ConfigError(f"name: must be a non-empty str, got {name!r}")
    if name in _METHOD_MODULES and getattr(run, "__module__", None) != _METHOD_MODULES[name]:
        raise ConfigError(f"name: {name!r} is a built-in method (registered by {_METHOD_MODULES[name]}); "
                          "register yours under another name")
    if not (isinstance(config_type, type) and dataclasses.is_dataclass(config_type)):
        raise ConfigError(f"config_type: must be a dataclass type, got {config_type!r}")
    if not callable(run):
        raise ConfigError(f"run: must be callable (scan, config) -> FeatureSet, got {run!r}")
    if run_many is not None and not callable(run_many):
        raise ConfigError(f"run_many: must be None or callable (scans, config) -> list of FeatureSet, got {run_many!r}")
    if not is_one_of(backend, BACKENDS):
        raise ConfigError(f"backend: must be one of {', '.join(BACKENDS)}, got {backend!r}")
    if not isinstance(thread_safe, (bool, np.bool_)):
        raise ConfigError(f"thread_safe: must be True or False, got {thread_safe!r}")
    try:
        default = config_type()
    except TypeError as exc:  # a field without a default
        raise ConfigError(f"config_type: {config_type.__name__}() must build the default config ({exc})") from None
    _REGISTRY[name] = Method(name, config_type, run, default, backend, run_many, bool(thread_safe))


def get_method(name: str) -> Method:
    """The registered method ``name``; raises UnknownMethodError listing the known ones."""
    if not isinstance(name, str):
        raise UnknownMethodError(f"method: must be a method name (str), got {name!r}; available: "
                                 f"{', '.join(available_methods())}")
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


def is_method(name: object) -> bool:
    """``name`` is a registered method or a built-in one (whose module is not imported here: the
    SLAM config checks its extractor's name at construction, cheaply)."""
    return isinstance(name, str) and (name in _REGISTRY or name in _METHOD_MODULES)


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
    _check_names(m, params)
    return m.config_type(**params)


def _check_names(m: Method, params: dict[str, Any]) -> None:
    """UnknownMethodError for a name in ``params`` that is no field of ``m``'s config."""
    known = {f.name for f in dataclasses.fields(m.config_type) if f.init}
    unknown = sorted(set(params) - known)
    if unknown:
        raise UnknownMethodError(
            f"unknown parameter(s) {unknown} for method {m.name!r}; known: {sorted(known)}"
        )


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

    Raises:
        ScanTypeError: ``scan`` is not an ``lms200.Scan`` (an ``LmsbenchError`` and a ``TypeError``).
        ConfigError: a baseline's ``breakpoint_lambda`` not above the scan's beam step
            (:func:`step_problem`: it would find no line, silently).
    """
    m = (_REGISTRY.get(method) if type(method) is str else None) or get_method(method)
    cfg = _config(m, config, params)
    if not isinstance(scan, Scan):
        raise not_a_scan(scan, "extract")
    if len(scan) > MAX_BEAMS:
        raise ScanGeometryError(too_many_beams(len(scan)))
    check_step(cfg, scan.angle_increment, m.name)
    if params:
        warn_unread_noise(m, cfg, params, scan.range_max, "extract")
    return _returned(m, m.run(scan, cfg), len(scan))


class UnreadNoiseWarning(LmsbenchWarning):
    """A range-noise field was set that the run's scans do not read (``sigma_r`` for cm-mode scans,
    ``sigma_r_cm`` for mm-mode ones): it changed nothing. Said by ``extract`` / ``extract_many``
    per call, by ``experiments.compare.compare`` and ``slam.run_slam`` once per run."""


#: the scans each mode-bound range-noise field of the sensor method is read for
#: (``features.sensor.config.SensorMethodConfig.noise_field``)
MODE_FIELDS = {"sigma_r": ("mm", "range_max <= 10 m"), "sigma_r_cm": ("cm", "range_max > 10 m")}


def mode_fields_read(config: Any, range_maxes: Sequence[float] | set[float],
                     given: Any) -> tuple[set[str], list[str]]:
    """The mode-bound range-noise fields of ``config`` that scans of these ``range_maxes`` (m)
    read, and those of ``given`` (the user's fields, in their order) that none reads; both empty
    for a config without ``noise_field`` or a run of no scan."""
    noise_field = getattr(config, "noise_field", None)
    if not range_maxes or not callable(noise_field):
        return set(), []
    read = {noise_field(r) for r in range_maxes}
    return read, [f for f in given if f in MODE_FIELDS and f not in read]


def unread_fields(params: Any, configs: Any, range_maxes: Sequence[float], scans: str) -> list[str]:
    """One line (no prefix) per field a user set (``params``: ``{method: {field: value}}``) that
    no scan of the run reads: the sensor method reads ``sigma_r`` for mm-mode scans and
    ``sigma_r_cm`` for cm-mode ones (range_max > 10 m; any config with a ``noise_field`` method),
    so ``--set extractor.sensor.sigma_r=5`` on the cm-mode CARMEN logs changed nothing, silently.
    ``configs``: each method's config as it ran; ``range_maxes``: those of the run's scans (m);
    ``scans``: how the line names them ("the scans of mit-csail.clf.gz")."""
    out: list[str] = []
    shown = ", ".join(f"{r:g}" for r in sorted(set(range_maxes))[:3]) + (", ..." if len(set(range_maxes)) > 3 else "")
    for method, given in params.items():
        read, unread = mode_fields_read(configs.get(method), range_maxes, given)
        for field in unread:
            other = next(iter(read))
            mode, rule = MODE_FIELDS[field]
            out.append(f"{method}: {field}={given[field]!r} is not used: {field} applies to {mode}-mode scans ({rule}); "
                       f"{scans} are {MODE_FIELDS[other][0]} mode (range_max {shown} m): set {other}")
    return out


def warn_unread_fields(params: Any, configs: Any, range_maxes: Sequence[float], scans: str, stacklevel: int = 3) -> None:
    """An :class:`UnreadNoiseWarning` per line of :func:`unread_fields`: what a run (``compare``,
    ``run_slam``) says once, at its end, over every scan it read (``stacklevel`` 3: its caller's line)."""
    for line in unread_fields(params, configs, range_maxes, scans):
        warnings.warn(line, UnreadNoiseWarning, stacklevel=stacklevel)


def warn_unread_noise(m: Method, cfg: Any, params: dict[str, Any], range_max: float, where: str) -> None:
    """An ``LmsbenchWarning`` when ``params`` set a range-noise field that a scan of this
    ``range_max`` does not read (the sensor method reads ``sigma_r`` at range_max <= 10 m and
    ``sigma_r_cm`` above: ``noise_field``), and not the one it reads: ``extract(scan, sigma_r=0.01)``
    on a scanner with a 30 m range ran with "auto", silently (a library walkthrough)."""
    noise_field = getattr(m.config_type, "noise_field", None)
    if noise_field is None:
        return
    read = noise_field(range_max)
    given = [f for f in ("sigma_r", "sigma_r_cm") if f in params]
    if not given or read in given:
        return
    when = "above 10 m (SICK cm codes)" if read == "sigma_r_cm" else "of 10 m or less (SICK mm codes)"
    warnings.warn(f"{where}: {given[0]}={params[given[0]]!r} is not read: a scan whose range_max is {when}, as "
                  f"this one's {range_max:g} m, reads {read} (now {getattr(cfg, read)!r}); set {read} for it",
                  UnreadNoiseWarning, stacklevel=3)




def too_many_beams(n: int, where: str = "scan") -> str:
    """The message of a scan with more than MAX_BEAMS beams; ``where`` names it ("scan", or a log's
    file and the scan's index)."""
    return (f"{where}: {n} beams is more than the extractors handle ({MAX_BEAMS}, a 0.022 deg step over 360 deg); "
            "split the scan into sectors")


def check_beams(scan: Scan, where: str = "scan") -> None:
    """ScanGeometryError (:func:`too_many_beams`, naming ``where``) for a scan of more than MAX_BEAMS
    beams: what ``extract`` refuses, for the drivers that call a method's ``run`` directly to time it
    (``compare``, ``sim2real``, the benchmarks), which ran 20,000-beam scans unchecked."""
    if len(scan) > MAX_BEAMS:
        raise ScanGeometryError(too_many_beams(len(scan), where))


#: rad: the breakpoint_lambda a step problem suggests at least (the baselines' default, Borges & Aldon's 10 deg)
SUGGESTED_LAMBDA = math.radians(10.0)


def step_problem(cfg: Any, increment: float, method: str, where: str = "scan") -> str | None:
    """Why a baseline config (its ``breakpoint_lambda``) cannot segment scans whose beam step is
    ``increment`` (rad), as a message beginning with ``where``; None when it can, or for a config
    without the field (the sensor method's; one comparison in the common case).

    The adaptive breakpoint distance r sin(step) / sin(lambda - step) (Borges & Aldon 2004) has no
    meaning for a step at or above lambda: at it the distance is infinite (every beam connects, no
    occlusion cuts a line), above it negative (no two neighbouring beams connect: no line is ever
    found, silently: a 2-deg scan at breakpoint_lambda 1 deg). A step of 90 deg or
    more, which no breakpoint_lambda (at most 90 deg) fits, is no mismatch of the config: None.

    The baselines' corner step (``config.corners``, a ``CornerConfig``) has a ``breakpoint_lambda``
    of its own, of the same meaning: two lines' facing end points, one beam step apart, connect
    within that distance. Not above the step, no corner was found, silently (split_merge on a 2-deg
    scan at corners.breakpoint_lambda 1.5 deg: its 3 walls, 0 corners), or every facing end
    connected; it is checked after the lines' and named ``corners.breakpoint_lambda``."""
    if increment >= math.pi / 2:
        return None
    for field, owner in (("breakpoint_lambda", cfg), ("corners.breakpoint_lambda", getattr(cfg, "corners", None))):
        lam = getattr(owner, "breakpoint_lambda", None) if owner is not None else None
        if lam is None or increment < lam:
            continue
        fit = min(max(SUGGESTED_LAMBDA, 10 * increment), math.pi / 2)
        what = "no line" if field == "breakpoint_lambda" else "no corner"
        return (f"{where}: the beam step {math.degrees(increment):.6g} deg is not below {method}'s {field} "
                f"{math.degrees(lam):.6g} deg ({lam:.6g} rad): the adaptive breakpoint distance r sin(step) / "
                f"sin(breakpoint_lambda - step) (Borges & Aldon) has no meaning there (at the step every beam connects, "
                f"beyond it none: {what}); set {field} above the step, e.g. {fit:.6g} rad ({math.degrees(fit):.6g} deg)")
    return None


def check_step(cfg: Any, increment: float, method: str, where: str = "scan") -> None:
    """ConfigError (:func:`step_problem`) for a baseline config that cannot segment scans of this
    beam step (rad): what ``extract`` and ``extract_many`` refuse, for the drivers that call a
    method's ``run`` directly (``compare``)."""
    problem = step_problem(cfg, increment, method, where)
    if problem is not None:
        raise ConfigError(problem)


#: scans per compiled batch call: the call stacks its scans' ranges into one array, which for a
#: 50,000-scan batch was a second 144 MB copy of them (peak RSS +166 MB); chunks of this many
#: bound that copy to 12 MB at 361 beams (results identical, scan by scan).
BATCH_CHUNK = 4096


def extract_many(scans: Sequence[Scan], method: str = "sensor", config: Any = None, *, threads: int | None = None,
                 **params: Any) -> list[FeatureSet]:
    """``extract`` of every scan in ``scans`` (a sequence of ``lms200.Scan`` of one geometry: beam
    count, angle_min, angle_increment, range_min, range_max), in compiled calls of up to
    BATCH_CHUNK scans for the compiled methods (sensor, split_merge, iepf); the result equals
    calling ``extract`` on each, whatever the thread count. A list or tuple (any sized collection)
    is taken whole; an iterator or generator is read up to ``features.batch.MAX_ITERATOR_BEAMS``
    beams (371,794 scans of 361 beams), and one that yields more, or never ends, is refused.

    ``threads``: pieces of the batch run on this many threads at once (each thread at least
    MIN_SCANS_PER_THREAD scans) for the compiled methods (registered ``thread_safe``); None:
    ``$LMSBENCH_THREADS``, else 1 (``features.batch.available_cpus()`` counts the CPUs that may
    help). The other methods run scan by scan in the calling thread.

    Raises:
        ValueError: naming the first scan whose geometry differs from the first's.
        ScanTypeError: naming the first item that is not an ``lms200.Scan``.
        BatchSizeError: an iterator of more than MAX_ITERATOR_BEAMS beams, or one that never ends.
        ConfigError: a ``threads`` that is not a whole number >= 1; a baseline's ``breakpoint_lambda``
            not above the scans' beam step (as ``extract``).
    """
    m = (_REGISTRY.get(method) if type(method) is str else None) or get_method(method)
    cfg = _config(m, config, params)
    n_threads = check_threads(threads)
    if isinstance(scans, Scan):
        raise ScanTypeError("extract_many: expected a sequence of lms200.Scan, got one Scan (use extract, or [scan])")
    try:
        scans = scan_list(scans)  # an endless iterator (itertools.repeat(scan)) ran until memory ran out
    except TypeError as exc:
        if isinstance(exc, ScanTypeError):
            raise
        raise ScanTypeError(f"extract_many: expected a sequence of lms200.Scan, got {type(scans).__name__}") from None  # its items are checked to be Scans by common_geometry, on every path below
    if scans and isinstance(scans[0], Scan) and len(scans[0]) > MAX_BEAMS:
        raise ScanGeometryError(too_many_beams(len(scans[0])))
    if scans and isinstance(scans[0], Scan):  # one geometry: the first scan's step is every scan's
        check_step(cfg, scans[0].angle_increment, m.name)
    if params and scans and isinstance(scans[0], Scan):  # one geometry: the first scan's range_max is every scan's
        warn_unread_noise(m, cfg, params, scans[0].range_max, "extract_many")
    if m.run_many is not None:
        use = n_threads if m.thread_safe else 1
        if not scans:  # threads=2 (or $LMSBENCH_THREADS=2) made an empty batch an IndexError
            return []
        run_many = m.run_many

        def checked(piece: Sequence[Scan], c: Any) -> list[FeatureSet]:
            # each piece's return, before run_pieces joins them: joined, a None was 'NoneType' object is
            # not iterable and a tuple was taken (threads > 1 or > BATCH_CHUNK scans), refused on one piece
            return _returned_many(m, run_many(piece, c), piece)

        if len(scans) <= BATCH_CHUNK and use == 1 and m.name in _METHOD_MODULES:
            return checked(scans, cfg)  # a built-in run_many checks the geometry itself (common_geometry)
        # the whole batch first: an error names the scan's index in it, not in a piece; and a user's run_many is
        # given scans of one geometry, as split in pieces (a batch of one piece was handed on unchecked: scans of two
        # range_max, a str or None among them, which its run_many could not tell apart or failed on, a raw TypeError)
        common_geometry(scans)
        if len(scans) <= BATCH_CHUNK and use == 1:
            return checked(scans, cfg)
        return run_pieces(checked, scans, cfg, use, BATCH_CHUNK)
    if scans:
        common_geometry(scans)
    return [_returned(m, m.run(s, cfg), len(s)) for s in scans]


def _returned(m: Method, out: object, beams: int | None = None) -> FeatureSet:
    """``out`` when a FeatureSet: a registered method returning anything else (None, a list) was
    handed on as the features without a word, to fail later in the caller's code (fuzz round)."""
    if not isinstance(out, FeatureSet):
        raise ConfigError(f"method {m.name!r}: its run returned {type(out).__name__}, not a features.FeatureSet")
    problem = returned_problem(m, out, beams)
    if problem:
        raise ConfigError(f"method {m.name!r}: its run returned {problem}")
    return out


def returned_problem(m: Method, fs: FeatureSet, beams: int | None = None) -> str:
    """What is wrong with the rows of ``fs``, method ``m``'s result on a scan of ``beams`` beams ("" when
    nothing, and for a built-in method, whose rows are right by construction): :func:`features.types.check_feature_set`'s
    message, or features that reach past the scan's last beam. Run outside any timed span (``compare`` times the
    method alone): a user's extractor's ``Lines.from_arrays`` with a nan rho or first > last was scored nan,
    silently (fuzzing); lines past the scan's beams were said by the scoring as "fs: its lines span beams 0..411",
    naming neither the extractor nor the scan (fuzz4)."""
    if m.name in _METHOD_MODULES:
        return ""
    if not isinstance(fs, FeatureSet):  # compare calls a registered method's run itself
        return f"{type(fs).__name__}, not a features.FeatureSet"
    try:
        check_feature_set(fs)
    except InputError as exc:
        return f"features out of their meaning: {exc}"
    if beams is not None:
        reach = np.concatenate((fs.lines.beams[:, :2].ravel(), fs.corners.beams[:, 0]))
        if reach.size and int(reach.max()) >= beams:
            return f"features that reach beam {int(reach.max())} of a {beams}-beam scan (features of another scan?)"
    return ""


def _returned_many(m: Method, out: object, scans: Sequence[Scan]) -> list[FeatureSet]:
    """``out`` when a list of one FeatureSet for each of ``scans``: a run_many returning fewer (or
    another type) gave a batch of 2 scans [] features, exit 0 (fuzz round). A built-in method's
    items are FeatureSets whose rows are right by construction (``returned_problem``): only the
    list is checked, not each item (~0.2 us a scan of a 7-20 us batch)."""
    n = len(scans)
    if not isinstance(out, list) or len(out) != n:
        got = f"{len(out)} items" if isinstance(out, list) else type(out).__name__
        raise ConfigError(f"method {m.name!r}: its run_many returned {got} for {n} scans, not a list of one features.FeatureSet a scan")
    if m.name in _METHOD_MODULES:
        return out
    for i, fs in enumerate(out):  # named as run_many's: 'its run returned NoneType' sent the reader to run
        if not isinstance(fs, FeatureSet):
            raise ConfigError(f"method {m.name!r}: its run_many returned {type(fs).__name__} at item {i} of {n}, "
                              "not a features.FeatureSet")
        problem = returned_problem(m, fs, len(scans[i]))
        if problem:
            raise ConfigError(f"method {m.name!r}: its run_many returned, at item {i} of {n}, {problem}")
    return out


def _config(m: Method, config: Any, params: dict[str, Any]) -> Any:
    """The config a call runs with: ``config`` (or the method's default) with ``params`` applied."""
    if config is None:
        return make_config(m.name, **params) if params else m.default
    if not isinstance(config, m.config_type):
        raise ConfigError(f"config: must be a {m.config_type.__name__} for method {m.name!r}, got {type(config).__name__}")
    if not params:
        return config
    try:
        return dataclasses.replace(config, **params)
    except TypeError:  # a name the config lacks (dataclasses.replace's TypeError): named, with the known ones
        _check_names(m, params)
        raise
