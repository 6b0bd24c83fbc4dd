"""Cell kinds: what one sweep cell computes from its parameters.

A cell kind is a function ``fn(params: dict) -> dict`` of metric name to scalar. It must be
deterministic in its parameters (all randomness seeded from ``params["seed"]``), so that any
executor gives the same table. Built-in kinds are registered by name here and imported lazily
(``extract``, ``slam``: see :mod:`experiments.sweep.kinds`); any importable function may also be
named as ``"package.module:function"``. A cell function may carry ``fn.check_params(cells)``,
which the runner calls on the whole list before any cell runs (raising ``SweepSpecError``), so
a misspelled parameter fails at once rather than in every cell.
"""

from __future__ import annotations

import importlib
import threading
import time
import traceback
import warnings
from typing import Any, Callable

from lms200.errors import LmsbenchWarning
from lms200.finite import printable

from .spec import RUNNER_COLUMNS, Scalar, SweepSpecError

CellFn = Callable[[dict[str, Scalar]], dict[str, Any]]

#: Built-in cell kinds: name -> "module:function", imported on first use.
BUILTIN_KINDS: dict[str, str] = {
    "extract": "experiments.sweep.kinds:extract_cell",
    "slam": "experiments.sweep.kinds:slam_cell",
}

_registry: dict[str, CellFn] = {}


def register_cell(name: str, fn: CellFn) -> CellFn:
    """Register ``fn`` as cell kind ``name`` in this process (workers resolve "module:function" names)."""
    _registry[name] = fn
    return fn


def available_kinds() -> list[str]:
    return sorted(set(BUILTIN_KINDS) | set(_registry))


def resolve_kind(kind: str) -> CellFn:
    """The cell function for ``kind``: a registered name, a built-in, or ``"module:function"``."""
    if kind in _registry:
        return _registry[kind]
    target = BUILTIN_KINDS.get(kind, kind)
    if ":" not in target:
        raise SweepSpecError(f"unknown cell kind {kind!r}; known: {available_kinds()} or 'package.module:function'")
    module_name, _, attr = target.partition(":")
    if kind in BUILTIN_KINDS:  # lmsbench's own
        return getattr(importlib.import_module(module_name), attr)
    from experiments.user_methods import import_named

    # the current folder first on the path, as for a user's extractor (compare --methods myext:lines):
    # `kind: mysw:cell` beside the sweep file needed PYTHONPATH=.
    return UserKind(kind, import_named(target, f"cell kind {kind!r}", SweepSpecError))


class UserKind:
    """A user's ``MODULE:FUNCTION`` cell kind: called as its function; sent to a Dask worker by
    name and imported there, at its first call, by :func:`resolve_kind` (the worker's current
    folder, the driver's on a local cluster, first on the path). Pickled by reference, the
    function was imported by the worker's unpickler without the current folder: "No module named
    'mysw'", and the sweep hung; a module a worker cannot import is now each cell's error row."""

    def __init__(self, kind: str, fn: CellFn | None) -> None:
        self.kind, self._fn = kind, fn
        self.check_params = getattr(fn, "check_params", None)  # the runner's check before any cell

    def __call__(self, params: dict[str, Scalar]) -> dict[str, Any]:
        if self._fn is None:  # in a worker
            fn = resolve_kind(self.kind)
            self._fn = fn._fn if isinstance(fn, UserKind) else fn
        assert self._fn is not None
        return self._fn(params)

    def __reduce__(self) -> tuple[Any, tuple[str, None]]:
        return UserKind, (self.kind, None)


#: the row's key of the cell's lmsbench warnings (not a metric: a metric of this name is refused)
WARNINGS_KEY = "_warnings"
#: a built-in cell's result: the digests of the files it read (parameter name -> digest of the bytes it computed
#: with), for the runner to store the row only under a key made with the same (``runner._changed_inputs``)
INPUTS_KEY = "_inputs"
_COLLECTING = threading.local()  # .said: the list the current thread's cell collects into, else None


def _cell_hook(previous: Callable[..., None]) -> Callable[..., None]:
    """``warnings.showwarning`` that hands an ``LmsbenchWarning`` shown in a thread running a cell to
    that cell's list, and shows every other warning with ``previous``. Per thread (cells may run in
    threads of one worker); no filter is changed."""

    def show(message: Warning | str, category: type[Warning], filename: str, lineno: int, file: Any = None,
             line: str | None = None) -> None:
        said = getattr(_COLLECTING, "said", None)
        if said is not None and issubclass(category, LmsbenchWarning):
            if (category, str(message)) not in said:
                said.append((category, str(message)))
            return
        previous(message, category, filename, lineno, file, line)

    show.lmsbench_cell_hook = True  # type: ignore[attr-defined]
    return show


def run_cell(kind: str, params: dict[str, Scalar], fn: CellFn | None = None) -> dict[str, Any]:
    """Run one cell and return its metrics plus status "ok", or status "error" with the error text.

    ``fn`` is the cell function when the caller resolved it already (else ``resolve_kind(kind)``).
    Exceptions from the cell become an error row (the sweep goes on), ``SystemExit`` too (a cell
    calling ``sys.exit()`` stopped an ``--inprocess`` sweep silently with its status, and killed the
    workers of a cluster, twice, for a ``KilledWorker`` row); ``KeyboardInterrupt`` propagates.
    ``elapsed_s`` is the wall time of the cell function (s). The ``LmsbenchWarning`` s the cell's
    thread shows (an extractor field no scan of the cell reads, ...; Python's filters decide which,
    as before) come back as ``WARNINGS_KEY`` (a list of (category, text), each once), for the runner
    to say once per sweep, not once per cell (two lines of Python's warning from every cell before);
    other warnings are shown as they were.
    """
    start = time.perf_counter()
    if not getattr(warnings.showwarning, "lmsbench_cell_hook", False):
        warnings.showwarning = _cell_hook(warnings.showwarning)
    _COLLECTING.said = said = []
    try:
        row = _run_cell(kind, params, fn)
    finally:
        _COLLECTING.said = None
    if said:
        row[WARNINGS_KEY] = said
    row["elapsed_s"] = time.perf_counter() - start
    return row


def _check_metrics(kind: str, metrics: dict[Any, Any]) -> None:
    """Raise (the cell fails, its error recorded) for a metric a sweep's table cannot hold: a name that
    is no plain name (:func:`metric_name_problem`), a value that is no scalar (a number, text, a
    bool or None; a list was kept in the table and plotted as "nan for every metric") or a whole number
    beyond int64."""
    import numpy as np

    from .spec import metric_name_problem, table_int_problem

    for name, value in metrics.items():
        if name == INPUTS_KEY:  # a built-in cell's record of its files (checked above for other kinds)
            continue
        problem = metric_name_problem(name)
        if problem:
            raise ValueError(f"cell kind {kind!r} returned {problem}")
        # numpy's complex, void and long double were taken, and the table's Parquet write ended the sweep
        if not isinstance(value, (bool, int, float, str, np.bool_, np.integer, np.floating, np.str_)) and value is not None:
            raise TypeError(f"cell kind {kind!r} returned metric {name!r} as {type(value).__name__}, not a scalar "
                            "(a number, text, a bool or None): a sweep's table holds one value a cell")
        if isinstance(value, np.floating) and value.dtype.itemsize > 8:
            raise TypeError(f"cell kind {kind!r} returned metric {name!r} as {type(value).__name__}, wider than the "
                            "float64 a sweep's table holds; return float(value)")
        if isinstance(value, str) and printable(value) != value:  # as spec._check_scalar tells a parameter's
            raise ValueError(f"cell kind {kind!r} returned metric {name!r} as text that is no UTF-8 (a lone surrogate, as "
                             "os.fsdecode gives for undecodable bytes): a sweep's table cannot hold it")
        if (beyond := table_int_problem(value)) is not None:
            raise ValueError(f"cell kind {kind!r} returned metric {name!r} as {beyond}")


def _run_cell(kind: str, params: dict[str, Scalar], fn: CellFn | None) -> dict[str, Any]:
    """:func:`run_cell`'s row without its time and warnings."""
    try:
        metrics = (fn or resolve_kind(kind))(dict(params))
        if not isinstance(metrics, dict):
            raise TypeError(f"cell kind {kind!r} returned {type(metrics).__name__}, expected a dict of metrics")
        if INPUTS_KEY in metrics and (kind not in BUILTIN_KINDS or kind in _registry):
            # the runner took it as the digests of the files the cell read (a built-in cell's own record)
            raise ValueError(f"cell kind {kind!r} returned a metric named {INPUTS_KEY!r}, the runner's record of the "
                             "files a built-in cell read (cells.INPUTS_KEY), not a metric a cell may return; name it "
                             "otherwise")
        clash = sorted(set(metrics) & (set(params) | {*RUNNER_COLUMNS, WARNINGS_KEY}))
        if clash:
            raise ValueError(f"cell kind {kind!r} returned metric(s) {clash} that clash with parameter/column names")
        _check_metrics(kind, metrics)
        row = {"status": "ok", "error": "", **metrics}
    except (Exception, SystemExit) as exc:  # noqa: BLE001 - a failing cell is recorded, not fatal
        from experiments.user_methods import UserMethodFailed, raised_text

        raised = exc.__cause__ if isinstance(exc, UserMethodFailed) and exc.raised else exc  # a user's extractor: its line
        last = traceback.extract_tb(raised.__traceback__)[-1:]
        where = f" ({last[0].filename.rsplit('/', 1)[-1]}:{last[0].lineno})" if last else ""
        said = raised_text(exc) if isinstance(exc, SystemExit) else f"{type(exc).__name__}: {exc}"
        row = {"status": "error", "error": f"{said}{where}"}
    return row
