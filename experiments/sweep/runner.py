"""Run a sweep on Dask (a local cluster, an existing scheduler) or in this process; resume for free.

Every finished cell is written at once (atomically) by this driver process as its result comes
back, so a killed sweep loses at most the cells in flight; run again, it computes only the cells
without a file. The rows are the same whichever executor computed them (cells are deterministic
in their parameters); only ``elapsed_s`` and any timing metric a cell reports differ.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import signal
import sys
import threading
import urllib.parse
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator

import pandas as pd
from tqdm import tqdm

from features.batch import THREADS_ENV
from lms200 import LmsbenchError
from lms200.errors import LmsbenchWarning
from lms200.finite import shown
from lms200.yamlio import dump as dump_yaml
from experiments.options import mid_sentence
from experiments.provenance import read_parquet

from .cells import INPUTS_KEY, WARNINGS_KEY, resolve_kind, run_cell
from .spec import Scalar, SweepSpec, SweepSpecError, cell_key
from .store import RESULT_TABLES, CellStore, write_atomic

#: Columns every row has besides its parameters and metrics.
BOOKKEEPING = ("status", "error", "elapsed_s", "cell", WARNINGS_KEY, INPUTS_KEY)


@dataclass
class SweepResult:
    """What a run did: the full table (finished cells, in sweep order) and the counts."""

    table: pd.DataFrame
    total: int
    computed: int
    skipped: int
    failed: int
    out: Path


@dataclass
class SweepPlan:
    """What a run of ``spec`` into the folder ``out`` has to compute, read from the folder's finished
    cells without writing anything (:func:`plan_sweep`): the command line counts the cells left within
    its checks, so that it reaches a ``--scheduler`` there only where cells remain, and hands the plan to
    :func:`run_sweep`, which then reads the cells once."""

    spec: SweepSpec
    out: Path
    retry_failed: bool
    keys: list[str]  # every cell's key, in the sweep's order (a repeated draw's key repeated)
    inputs_of: dict[str, Any]  # key -> the digests of the files the cell reads (None: a kind that reads none)
    todo: list[tuple[str, dict[str, Scalar]]]  # the cells to compute, each once

    @property
    def skipped(self) -> int:
        """Cells already finished in ``out``."""
        return len(set(self.keys)) - len(self.todo)


def plan_sweep(spec: SweepSpec, out: str | Path, fn: Any, retry_failed: bool = False) -> SweepPlan:
    """The cells of ``spec`` that a run into ``out`` computes (:class:`SweepPlan`): those without a
    finished cell file there (with ``retry_failed``, also those recorded as failed). Reads the digests
    of the files the cells read (``fn.input_digests``) and each cell file's footer; writes nothing
    (a folder without ``cells/`` has none finished).

    Raises:
        LmsbenchError: ``out/cells`` cannot be read, or cannot be written (or, absent, made) while cells remain;
            ``out`` cannot be written (or, absent, made).
    """
    out = _sweep_folder(out)
    cells = spec.cells()
    digests, seen = getattr(fn, "input_digests", None), {}  # the files a cell reads are part of its key
    inputs = [digests(params, seen) if digests else None for params in cells]
    keys = [cell_key(spec.kind, params, given) for params, given in zip(cells, inputs)]
    store = CellStore(out, create=False)
    done = store.done(dict(zip(keys, cells)))  # a cell file whose parameters were edited is computed again
    if retry_failed:
        done = {k for k in done if store.status(k) == "ok"}
    todo = list({key: params for key, params in zip(keys, cells) if key not in done}.items())  # identical cells once
    if todo:
        store.check_writable()  # before any cell is computed (or a scheduler reached); the folder as it is or as made
    store.check_root_writable()  # its sweep.yaml, versions.yaml and tables, written by every run, cells left or none
    return SweepPlan(spec, out, retry_failed, keys, dict(zip(keys, inputs)), todo)


def run_sweep(
    spec: SweepSpec,
    out: str | Path,
    executor: Any = "local",
    *,
    workers: int = 2,
    retry_failed: bool = False,
    progress: bool = True,
    checked: bool = False,
    plan: SweepPlan | None = None,
) -> SweepResult:
    """Compute every cell of ``spec`` not yet finished in ``out`` and write the tidy table.

    Args:
        spec: the sweep.
        out: the sweep folder (created); see :mod:`experiments.sweep.store` for its layout.
        executor: ``"local"`` (a Dask LocalCluster of ``workers`` processes, started and closed
            here), ``"inprocess"`` (a plain loop, no Dask), a scheduler address
            ``"tcp://HOST:PORT"``, or a ``distributed.Client`` to use as is.
        retry_failed: compute again the cells whose recorded status is "error".
        progress: show a tqdm bar (on stderr) with cells done, failed and the time left.
        checked: ``spec`` has passed :func:`check_spec` already (the CLI checks it before compiling
            the kernels), so it is not checked again: a second check read its sensor files again
            and said each old-spelling warning twice.
        plan: :func:`plan_sweep` of the same ``spec``, ``out`` and ``retry_failed``, made just before
            (the command line's checks make it); None: made here.

    Returns:
        A :class:`SweepResult`; ``out/results.parquet`` and ``out/results.csv`` hold its table.
    """
    if not isinstance(spec, SweepSpec):  # a mapping was an AttributeError ('dict' object has no attribute 'kind')
        raise SweepSpecError(f"spec: must be a SweepSpec (load_sweep(path), or SweepSpec.from_dict(mapping) for a "
                             f"mapping), got {type(spec).__name__}")
    out = _sweep_folder(out)
    for name, value in (("retry_failed", retry_failed), ("progress", progress), ("checked", checked)):
        if not isinstance(value, bool):
            raise LmsbenchError(f"{name}: must be True or False, got {shown(value, 60)}")
    check_executor(executor, workers)
    fn = resolve_kind(spec.kind) if checked else check_spec(spec)
    if plan is None:
        plan = plan_sweep(spec, out, fn, retry_failed)
    elif not isinstance(plan, SweepPlan) or plan.spec is not spec or plan.out != out or plan.retry_failed != retry_failed:
        raise LmsbenchError("plan: must be plan_sweep(spec, out, fn, retry_failed) of this run's spec, out and "
                            f"retry_failed, got {shown(plan, 60)}")
    fresh = not out.exists() and not out.is_symlink()
    before = set() if fresh or not out.is_dir() else {p.name for p in out.iterdir()}
    try:
        return _run_into(plan, CellStore(out), fn, executor, workers, progress)
    except Exception:
        _undo(out, fresh, before)
        raise


def _named_out(out: object) -> object:
    """``out`` unchanged when it is a path; else the error names the argument ``out`` (``path_of``'s said "path")."""
    if not isinstance(out, (str, os.PathLike)):
        raise LmsbenchError(f"out: must be a str or os.PathLike (the sweep's folder), got {type(out).__name__}")
    return out


def _sweep_folder(out: object) -> Path:
    """``out`` as the Path of a sweep folder, new or a folder: an empty path wrote the sweep's cells/ and
    tables into the current folder, a file was NotADirectoryError after the spec's checks, and None or a
    number a TypeError (found by the fuzz4 round). The current folder named relatively is refused however
    it is spelled (``""``, ``"."``, ``Path("")``, ``Path(".")``): pathlib reads ``Path("")`` as ``Path(".")``,
    so an unset ``Path(os.environ.get("OUT", ""))`` cannot be told from a meant ``Path(".")``, and the str ``""``
    was refused while ``Path("")`` wrote into the current folder; ``Path.cwd()`` names it on purpose (the
    command line's ``--out .`` passes it so)."""
    from lms200.logs import path_of

    if isinstance(out, str) and not out.strip():
        raise LmsbenchError(f"out: must name the sweep's folder, got {out!r} (an empty path is the current folder)")
    p = path_of(_named_out(out))
    if p == Path(".") or (not p.is_absolute() and os.path.abspath(p) == os.getcwd()):  # "sub/..", "../here" too
        raise LmsbenchError(f"out: must name the sweep's folder, got {out!r}, the current folder named relatively (pathlib "
                            "reads Path('') as Path('.'), so an empty path cannot be told from it); give "
                            "Path.cwd() to write the sweep into the current folder")
    if (p.exists() or p.is_symlink()) and not p.is_dir():
        raise LmsbenchError(f"out: {p} exists and is not a folder; give the sweep's folder (new, or one a sweep wrote)")
    return p


def _undo(out: Path, fresh: bool, before: set[str]) -> None:
    """After a run that failed before any cell finished (a ``--scheduler`` not reached, a local
    cluster that did not start: "Timed out trying to connect", exit 2), remove what it wrote into
    ``out`` (the folder itself when it made it): it left sweep.yaml, versions.yaml and an empty
    cells/ behind. A run with a finished cell, or stopped by Ctrl-C, keeps its folder to resume."""
    import shutil

    if not out.is_dir() or CellStore.finished(out):
        return
    if fresh:
        shutil.rmtree(out, ignore_errors=True)
        return
    for entry in out.iterdir():
        if entry.name not in before:
            shutil.rmtree(entry, ignore_errors=True) if entry.is_dir() and not entry.is_symlink() else entry.unlink(missing_ok=True)


def _run_into(plan: SweepPlan, store: CellStore, fn: Any, executor: Any, workers: int, progress: bool) -> SweepResult:
    """:func:`run_sweep` of ``plan`` into the folder of ``store``."""
    out, spec, keys, inputs_of, todo = store.root, plan.spec, plan.keys, plan.inputs_of, plan.todo
    digests = getattr(fn, "input_digests", None)
    from experiments.provenance import versions, write_record

    record = spec_record(spec)  # the folder and its cells folder were checked as writable by plan_sweep
    # every check first, then the first write: a run refused above (a cell folder not writable, a folder where a
    # cell's file goes, an input that cannot be read) rewrote sweep.yaml and versions.yaml and removed the
    # folder's table of the earlier sweep before it was refused
    if _recorded(out / "sweep.yaml") not in (None, record):  # the folder's table is another sweep file's: a run
        for name in RESULT_TABLES:  # killed before writing its own left it beside this
            (out / name).unlink(missing_ok=True)  # sweep.yaml, drawn by `figures --sweep` as this one's, exit 0
    write_record(out / "sweep.yaml", record)  # whole: it tells the folder as the sweep's (SWEEP_OWNER)
    write_record(out / "versions.yaml", dump_yaml(versions(), sort_keys=False))  # of the last run into `out`
    skipped = plan.skipped
    counts = {"computed": 0, "failed": 0}

    bar = tqdm(total=len(set(keys)), initial=skipped, desc=spec.name, unit="cell", file=sys.stderr,
               disable=True if not progress else None, dynamic_ncols=True)  # None: on a terminal only

    said: set[tuple[type[Warning], str]] = set()
    changed: dict[str, int] = {}  # a file a cell reads that changed during the run: cells not stored

    def record(key: str, params: dict[str, Scalar], result: dict[str, Any]) -> None:
        for category, text in result.get(WARNINGS_KEY, ()):  # each once per sweep (every cell had its two lines)
            if (category, text) not in said:
                said.add((category, text))
                warnings.warn(f"{text} (said once for the sweep's cells)", category, stacklevel=2)
        used = result.get(INPUTS_KEY)
        edited = _changed_inputs(digests, params, inputs_of.get(key), used if isinstance(used, dict) else None)
        if edited:  # the cell may have read the new content: its row is not the key's (the old content's)
            for path in edited:
                changed[path] = changed.get(path, 0) + 1
            bar.update(1)
            return
        store.write(key, _row(params, result, key))
        counts["computed"] += 1
        counts["failed"] += result["status"] != "ok"
        bar.set_postfix(done=skipped + counts["computed"], failed=counts["failed"], refresh=False)
        bar.update(1)

    try:
        if todo:
            if executor == "inprocess":
                for key, params in todo:
                    record(key, params, run_cell(spec.kind, params, fn))
            else:
                with sweep_client(executor, workers) as client:
                    _run_on_dask(client, spec.kind, fn, todo, record)
    finally:
        bar.close()
        for path, n in changed.items():
            warnings.warn(f"{path} changed while the sweep ran: {n} cell{'s' if n != 1 else ''} that finished after "
                          f"the change {'were' if n != 1 else 'was'} not stored (they may have read either content); "
                          "run the sweep again to compute them with the file as it is now", LmsbenchWarning, stacklevel=2)
        table = store.read(keys)
        if not table.empty:
            table = table.drop_duplicates("cell", ignore_index=True)
            for name in RESULT_TABLES:
                write_atomic(table, out / name)
    failed = int((table["status"] != "ok").sum()) if not table.empty else 0
    return SweepResult(table, len(set(keys)), counts["computed"], skipped, failed, out)


def _recorded(path: Path) -> str | None:
    """The text of an earlier run's sweep.yaml, None when there is none (or it cannot be read)."""
    try:
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None


def _changed_inputs(digests: Any, params: dict[str, Scalar], given: dict[str, str] | None,
                    used: dict[str, str] | None = None) -> list[str]:
    """The files (paths as the cell's parameters give them) whose digest differs from ``given``, the
    digests the cell's key was made with: ``used``, the digests of the bytes the cell computed with
    (a built-in cell reads each file once and says so, ``cells.INPUTS_KEY``), else the file's now (a
    file gone or unreadable counts as changed). Read now, a file edited and put back while the cell
    ran (or edited between the key's read and the cell's) passed, the row of the other content
    stored under the key."""
    if not digests or not given:
        return []
    if used is not None:
        now = used
    else:
        try:
            now = digests(params, {})
        except OSError:
            now = {}
    return [str(params[name]) for name in sorted(given) if now.get(name) != given[name]]


def load_results(out: str | Path) -> pd.DataFrame:
    """The table of a sweep folder (``results.parquet``).

    Raises:
        LmsbenchError: ``out`` is no folder holding a ``results.parquet`` (a missing one was a raw
            FileNotFoundError, a file a NotADirectoryError).
    """
    from lms200.logs import path_of

    table = path_of(_named_out(out)) / "results.parquet"
    if not table.is_file():
        raise LmsbenchError(f"{out}: no results.parquet there (not a sweep folder, or no run of its sweep has "
                            "written its table yet)")
    return read_parquet(table)


def _row(params: dict[str, Scalar], result: dict[str, Any], key: str) -> dict[str, Any]:
    metrics = {k: v for k, v in result.items() if k not in BOOKKEEPING}
    return {**params, **metrics, "status": result["status"], "error": result.get("error", ""),
            "elapsed_s": float(result.get("elapsed_s", float("nan"))), "cell": key}


def _run_on_dask(client, kind: str, fn, todo: list[tuple[str, dict]], record) -> None:
    """Run the cells on ``client``; record each as it finishes.

    A worker that dies takes down every cell queued on it, and Dask may blame an innocent one
    (``KilledWorker``). Such cells are run once more, one at a time, after the others: an innocent
    cell then succeeds and only the cell that really kills its worker is recorded as failed.
    """
    from distributed import as_completed

    futures = {}
    for key, params in todo:
        future = client.submit(run_cell, kind, params, fn, key=f"lmsbench-cell-{key}", pure=False)
        futures[future] = (key, params)
    killed: list[tuple[str, dict]] = []
    try:
        for future in as_completed(futures):
            key, params = futures[future]
            result = _future_result(future)
            if result is None:
                killed.append((key, params))
            else:
                record(key, params, result)
            future.release()
        for key, params in killed:  # alone on the cluster this time
            future = client.submit(run_cell, kind, params, fn, key=f"lmsbench-cell-{key}-alone", pure=False)
            futures[future] = (key, params)
            result = _future_result(future)
            record(key, params, result if result is not None else _lost_result(future))
            future.release()
    except BaseException:
        client.cancel(list(futures))
        raise


def _future_result(future) -> dict[str, Any] | None:
    """The cell's result dict; an error row when the cell raised or was cancelled; None when the
    cell's worker died under it (``KilledWorker``) or its finished result was lost with a worker
    that died afterwards (worth running again)."""
    from distributed import wait

    wait(future)
    if future.status == "finished":
        try:
            return future.result()
        except Exception:  # noqa: BLE001 - the result was lost with its worker after finishing
            return None
    exc = _exception(future)
    if exc is None or type(exc).__name__ == "KilledWorker":
        return None
    return {"status": "error", "error": f"{type(exc).__name__}: {exc}", "elapsed_s": float("nan")}


def _exception(future) -> BaseException | None:
    """The exception the cell's future holds, if any (a cancelled future raises its own here)."""
    try:
        return future.exception()
    except (Exception, asyncio.CancelledError) as raised:
        return raised


def _lost_result(future) -> dict[str, Any]:
    """The error row of a cell that took its worker down twice, or whose result was lost again."""
    exc = _exception(future)
    text = f"{type(exc).__name__}: {exc}" if exc is not None else f"lost: the worker died ({future.status})"
    return {"status": "error", "error": text, "elapsed_s": float("nan")}


SCHEMES = ("tcp://", "tls://", "inproc://", "ucx://", "ws://", "wss://")


def spec_record(spec: SweepSpec) -> str:
    """The text of the ``sweep.yaml`` a run writes into its folder: the sweep as run."""
    return dump_yaml(spec.to_dict(), sort_keys=False)


def check_executor(executor: Any, workers: int) -> None:
    """A known executor, before anything is written."""
    if not isinstance(executor, str) and not callable(getattr(executor, "submit", None)):  # None, 5: AttributeError 'submit'
        raise LmsbenchError(f"executor: must be 'local', 'inprocess', a scheduler address (tcp://HOST:PORT) or a "
                            f"distributed.Client, got {shown(executor, 60)}")
    if executor == "local" and not (isinstance(workers, int) and workers >= 1):
        raise LmsbenchError(f"workers: a local cluster needs at least 1 worker process, got {workers}")
    if isinstance(executor, str) and executor not in ("local", "inprocess") and not executor.startswith(SCHEMES):
        raise LmsbenchError(f"scheduler: {executor!r} is not a Dask scheduler address (tcp://HOST:PORT), "
                            "nor 'local' or 'inprocess'")
    if isinstance(executor, str) and executor.startswith(SCHEMES):
        _check_address(executor)


def _check_address(address: str) -> None:
    """A scheduler address Dask can connect to: a host and a port 1-65535 (``inproc://``: Dask's
    HOST/PID/N of a scheduler in this process). Dask's own parse of ``tcp://``, ``tcp://HOST``,
    ``tcp://[::1`` or ``inproc://x`` was an internal error (ValueError), and a port beyond 65535 or
    0 a 10 s wait for a connection that cannot be."""
    scheme, _, location = address.partition("://")
    if scheme == "inproc":
        if len(location.split("/")) != 3:
            raise LmsbenchError(f"scheduler: {address!r} is not an in-process Dask address (inproc://HOST/PID/N)")
        return
    try:
        parts = urllib.parse.urlsplit(address)
        host, port = parts.hostname, parts.port
    except ValueError as exc:  # "Invalid IPv6 URL", "Port out of range 0-65535", a port that is no number
        raise LmsbenchError(f"scheduler: {address!r} is not a Dask scheduler address ({scheme}://HOST:PORT): "
                            f"{mid_sentence(str(exc))}") from None
    if not host or port is None or not 1 <= port <= 65535 or parts.path or parts.query:
        raise LmsbenchError(f"scheduler: {address!r} is not a Dask scheduler address: give {scheme}://HOST:PORT, "
                            "a host and a port 1-65535 (an IPv6 host in brackets: tcp://[::1]:8786)")


def check_spec(spec: SweepSpec):
    """The cell function of ``spec``'s kind, after checking the kind and every cell's parameter
    names (a kind may check them before any cell runs).

    Warns:
        LmsbenchWarning: random draws that repeat an earlier draw (a small discrete space, or more
            ``samples`` than its points), naming how many: their cells run once (draws are with
            replacement, so that a sweep's draws stay those of its ``sample_seed`` and a sweep resumes).
    """
    fn = resolve_kind(spec.kind)
    check = getattr(fn, "check_params", None)
    if check is not None:
        check(spec.cells())
    repeats, points = spec.repeated_draws()
    if repeats:  # the cells of a repeated draw ran once: the sweep had fewer cells than asked, without a word
        n = spec.samples - repeats
        if points is not None and spec.samples > points:
            space = f"; its random space has {points} point{'s' if points != 1 else ''}, fewer than the draws"
        elif points is not None:
            space = f"; draws are with replacement over its {points} points"
        else:
            space = ""
        hint = ": list the points under grid: to run each once" if points is not None else ""
        warnings.warn(f"sweep {spec.name}: {repeats} of the {spec.samples} random draws (samples:) repeat an earlier "
                      f"draw, and a cell runs once: {n} distinct draw{'s run' if n != 1 else ' runs'}{space}{hint}",
                      LmsbenchWarning, stacklevel=2)
    return fn


def quiet_dask() -> None:
    """Silence Dask's and Tornado's loggers in this process (closed connections at shutdown are
    logged with tracebacks that say nothing to a user; cell errors are in the table)."""
    for name in ("distributed", "tornado", "asyncio", "bokeh"):
        logging.getLogger(name).setLevel(logging.CRITICAL)


class _HeldCtrlC:
    """What :func:`_ctrl_c_held` saw: the stop signals that came while it held them."""

    def __init__(self) -> None:
        self.previous: dict[int, Any] = {}
        self.came: list[int] = []

    def record(self, signum: int, frame: Any) -> None:
        self.came.append(signum)

    def deliver(self) -> None:
        """Hand the first held signal to the handler that was in place before (the command line's:
        KeyboardInterrupt, its one line and exit status), or raise KeyboardInterrupt."""
        if not self.came:
            return
        handler = self.previous.get(self.came[0])
        if callable(handler):
            handler(self.came[0], None)
        if handler != signal.SIG_IGN:
            raise KeyboardInterrupt


@contextlib.contextmanager
def _ctrl_c_held(ignore: bool = False) -> Iterator[_HeldCtrlC]:
    """Hold Ctrl-C (SIGINT) and SIGTERM while a local cluster starts: each is recorded (in this
    process; a Python handler sees a signal whichever thread the system gives it to), and
    ``deliver()`` after the block acts on it, once the cluster can be closed: Ctrl-C was ignored
    while the cluster started (2-4 s), so it was lost and the sweep ran to its end, exit 0.
    ``ignore``: SIGINT is ignored meanwhile instead (and lost), for workers that inherit it so."""
    held = _HeldCtrlC()
    if threading.current_thread() is not threading.main_thread():  # signals are the main thread's
        yield held
        return
    held.previous = {signal.SIGINT: signal.signal(signal.SIGINT, signal.SIG_IGN if ignore else held.record),
                     signal.SIGTERM: signal.signal(signal.SIGTERM, held.record)}
    try:
        yield held
    finally:
        for sig, handler in held.previous.items():
            signal.signal(sig, handler)


@contextlib.contextmanager
def _workers_ignore_ctrl_c() -> Iterator[bool]:
    """Processes that multiprocessing spawns meanwhile (a local cluster's workers) start with
    Ctrl-C (SIGINT) ignored: through a two-line shell script that ignores it and runs Python (an
    ignored signal stays ignored in the Python it runs), so a terminal's Ctrl-C, sent to the whole
    process group, reaches the driver alone, which cancels the cells and closes the cluster, and
    this process keeps its own handler (ignoring SIGINT here while the workers were spawned lost a
    Ctrl-C that came then). Yields False, the script not used, where it cannot run (a /tmp mounted
    noexec): the caller then ignores SIGINT while the workers start, as before."""
    import multiprocessing.spawn

    previous = multiprocessing.spawn.get_executable()  # bytes or str
    script = _ctrl_c_script(os.fsdecode(previous))
    if script is not None:
        multiprocessing.spawn.set_executable(str(script))
    try:
        yield script is not None
    finally:
        multiprocessing.spawn.set_executable(previous)


def _ctrl_c_script(python: str) -> Path | None:
    """The script that runs ``python`` with SIGINT ignored: ``TMP/lmsbench-workers-UID/python-HASH``,
    one per Python, written whole each time and kept (a folder made and removed per run was left
    behind by every hard stop: the grace timer's ``os._exit`` runs no cleanup); None where it cannot
    run (``os.access`` X_OK fails on a noexec mount) or the folder is not this user's alone."""
    import hashlib
    import shlex
    import stat
    import tempfile

    folder = Path(tempfile.gettempdir()) / f"lmsbench-workers-{os.getuid()}"
    script = folder / f"python-{hashlib.sha256(python.encode()).hexdigest()[:12]}"
    try:
        folder.mkdir(mode=0o700, exist_ok=True)
        st = os.lstat(folder)
        if not stat.S_ISDIR(st.st_mode) or st.st_uid != os.getuid() or st.st_mode & 0o077:
            return None  # another user's, or a link: not a folder to run a script from
        tmp = folder / f".{script.name}.{os.getpid()}.tmp"
        tmp.write_text(f"#!/bin/sh\ntrap '' INT\nexec {shlex.quote(python)} \"$@\"\n")
        tmp.chmod(0o700)
        os.replace(tmp, script)
    except OSError:
        return None
    return script if os.access(script, os.X_OK) and Path("/bin/sh").is_file() else None


@contextlib.contextmanager
def sweep_client(executor: Any, workers: int) -> Iterator[Any]:
    """A Dask client for ``executor``: a new LocalCluster, a scheduler address, or a given client."""
    import dask
    from distributed import Client, LocalCluster

    if executor == "local":
        quiet_dask()
        # a cell that kills its worker fails after one retry instead of three
        with dask.config.set({"distributed.scheduler.allowed-failures": 1}), _workers_ignore_ctrl_c() as wrapped:
            cluster = None
            try:
                with _ctrl_c_held(ignore=not wrapped) as held:
                    try:
                        # no dashboard, and its HTTP server on a free port: the default 8787 of another
                        # cluster on the machine made Dask warn on stderr
                        # one extraction thread a worker (``features.extract_many``): the workers are the parallelism
                        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                               dashboard_address=":0", scheduler_kwargs={"dashboard": False},
                                               silence_logs=logging.CRITICAL, env={THREADS_ENV: "1"})
                    except Exception:
                        if not held.came:
                            raise
                        # a worker stopped by that Ctrl-C as it started ("Nanny failed to start"): the stop is said
                held.deliver()  # a Ctrl-C while the cluster started stops here, the cluster closed below
                with Client(cluster) as client:
                    yield client
            finally:
                if cluster is not None:
                    cluster.close()
    elif isinstance(executor, str):
        quiet_dask()
        with Client(executor, timeout="10s") as client:
            yield client
    else:
        yield executor
