"""Progress for long steps: the one-off numba compile announced, and a heartbeat that prints a
line whenever a command has been silent for a few seconds (so a user never watches a dead
terminal). Drivers only: algorithm code never prints."""

from __future__ import annotations

import sys
import threading
import time
from typing import IO, Any, Callable, ContextManager

import numpy as np

Log = Callable[[str], None]

#: Methods that run those kernels.
COMPILED_METHODS = ("sensor", "split_merge", "iepf")


def stderr(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def warm_up_kernels(log: Log = stderr, slam: bool = False, methods: tuple[str, ...] = COMPILED_METHODS) -> float:
    """Load (or compile, the first time in a checkout) the extractors' numba kernels now (those of
    ``methods``, by default every compiled one; the pooled noise estimate's with "sensor"), and with
    ``slam`` the default SLAM pipeline's (scan matching, pose graph, map merge), so that a run's
    scans/s measure the run, not the compiler. When numba compiles (a fresh checkout, or code that
    changed) and that takes more than a second, it says "compiling kernels, once" and then a line
    every few seconds until done; loading the cached machine code says nothing, however long it
    takes. Returns the seconds it took."""
    from numba.core import event

    compiles = _compile_watch()
    from features import extract, extract_many
    from features.noise_estimate import neighbour_sigma
    from lms200 import Scan

    # a room-like scan: two walls meeting in a corner, so every kernel (lines, merging, corners) runs
    bearings = np.linspace(-np.pi / 2, np.pi / 2, 361)
    ranges = np.minimum(2.0 / np.maximum(np.cos(bearings), 1e-9), 3.0 / np.maximum(np.sin(bearings), 1e-9))
    ranges = np.where(ranges > 8.0, np.inf, ranges)
    scan = Scan.lms200(ranges + 0.002 * np.random.default_rng(0).standard_normal(361))
    # and the same scan in cm mode (range_max > 10 m), whose noise the sensor method estimates ("auto")
    scans = (scan, scan.replace(range_max=81.83))
    start = time.perf_counter()
    first = "compiling kernels, once (about 1-2 min; cached beside the code for every later run) ..."
    event.register("numba:compile", compiles)  # numba raises this event for compiles only, not cache loads
    try:
        with Heartbeat(log, "compiling kernels", first=first, first_after=1.0, when=lambda: compiles.compiled) as beat:
            for sample in scans:  # single calls, batches and the pooled noise estimate take different kernels
                for method in methods:
                    extract(sample, method=method)
                    extract_many([sample, sample], method=method)
            if "sensor" in methods:
                neighbour_sigma(list(scans))
            if slam:
                for sample in scans:
                    _warm_up_slam(sample)
    finally:
        event.unregister("numba:compile", compiles)
    seconds = time.perf_counter() - start
    if beat.announced:
        log(f"kernels compiled in {seconds:.0f} s")
    return seconds


def _compile_watch() -> Any:
    """A numba event listener whose ``compiled`` turns True once a kernel starts compiling (numba
    raises "numba:compile" for compiles, not for loads from its on-disk cache)."""
    from numba.core import event

    class CompileWatch(event.Listener):
        compiled = False

        def on_start(self, ev: Any) -> None:
            self.compiled = True

        def on_end(self, ev: Any) -> None:
            pass

    return CompileWatch()


def _warm_up_slam(scan: Any) -> None:
    """The default SLAM pipeline over a few copies of ``scan`` taken 2 cm apart (every per-scan
    kernel, the keyframe map and the final line merge run; the result is discarded): three 0.1 s
    apart, then one 2 s later, so that the correlative search (``slam.correlative``: likelihood
    field, window scores, fit) runs too (the prediction's 3 std then exceed the ICP's reach)."""
    from lms200 import Record
    from slam import SlamConfig, run_slam

    stamps = (0.0, 0.1, 0.2, 2.2)
    records = [Record(scan=scan.replace(stamp=t, ranges=scan.ranges - 0.02 * k)) for k, t in enumerate(stamps)]
    run_slam(records, SlamConfig())


#: the heartbeats active now, outermost first: one inside another (the compile's inside the demo's)
#: speaks for both while it has announced itself
_ACTIVE: list["Heartbeat"] = []
_ACTIVE_LOCK = threading.Lock()


class Heartbeat:
    """While active, prints ``... LABEL: N s`` whenever nothing was said for ``every`` seconds
    (with ``first``: that line after ``first_after`` s, and nothing at all before it; with ``when``
    as well, not before ``when()`` is true: the slow part has started). Inside another heartbeat
    that has announced itself, it keeps quiet: the first demo printed "... demo: 5 s" and
    "... compiling kernels: 5 s" together.

    Use ``beat.say(msg)`` for the step's own messages (they reset the timer) and ``beat.label =``
    to name the current step."""

    def __init__(self, log: Log = stderr, label: str = "working", every: float = 4.0, first: str | None = None,
                 first_after: float = 0.0, when: Callable[[], bool] | None = None) -> None:
        self.log, self.label, self.every, self.when = log, label, every, when
        self.first, self.first_after, self.announced = first, first_after, first is None
        self.last = self.start = time.monotonic()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="lmsbench-heartbeat", daemon=True)

    def say(self, msg: str) -> None:
        self.last = time.monotonic()
        self.log(msg)

    def _run(self) -> None:
        while not self._stop.wait(0.25):
            now = time.monotonic()
            if not self.announced:  # the opening line, only once the step has proved slow
                if now - self.start >= self.first_after and (self.when is None or self.when()):
                    self.announced, self.last = True, now
                    self.log(str(self.first))
                continue
            if now - self.last >= self.every:
                self.last = now
                if not self._inner_speaking():
                    self.log(f"   ... {self.label}: {now - self.start:.0f} s")

    def _inner_speaking(self) -> bool:
        """A heartbeat started inside this one has announced itself (it says the time for both)."""
        with _ACTIVE_LOCK:
            inner = _ACTIVE[_ACTIVE.index(self) + 1:] if self in _ACTIVE else []
        return any(beat.announced for beat in inner)

    def __enter__(self) -> "Heartbeat":
        with _ACTIVE_LOCK:
            _ACTIVE.append(self)
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()
        with _ACTIVE_LOCK:
            if self in _ACTIVE:
                _ACTIVE.remove(self)


def on_terminal(stream: IO[str] | None = None) -> bool:
    """Whether ``stream`` (default stderr) is a terminal: progress is said there only, as the
    progress bars (tqdm's ``disable=None``) do; off a terminal stderr keeps to warnings and errors."""
    out = sys.stderr if stream is None else stream
    return bool(hasattr(out, "isatty") and out.isatty())


def say_on_terminal(msg: str, stream: IO[str] | None = None) -> None:
    """Print ``msg`` on ``stream`` (default stderr) when it is a terminal, else nothing: the line
    that announces a step before its progress bar (``slam``'s baselines)."""
    out = sys.stderr if stream is None else stream
    if on_terminal(out):
        print(msg, file=out, flush=True)


class _Quiet:
    """What :func:`heartbeat_on_terminal` gives off a terminal: a heartbeat that says nothing."""

    label = ""

    def say(self, msg: str) -> None:
        pass

    def __enter__(self) -> "_Quiet":
        return self

    def __exit__(self, *exc: object) -> None:
        pass


def heartbeat_on_terminal(label: str, first: str | None, stream: IO[str] | None = None, every: float = 4.0,
                          first_after: float = 1.0) -> ContextManager[Any]:
    """A :class:`Heartbeat` on ``stream`` (default stderr) when it is a terminal, else one that
    says nothing (its ``say`` and ``label`` do nothing either): off a terminal stderr keeps to the
    one line of an error. For the steps that take minutes without a progress bar of their own
    (``sim2real``: 2-3 min silent at its defaults; ``calibrate``; each area of ``bench``; the
    figures being drawn). ``first`` None: no opening line (the step says its own through ``say``)."""
    out = sys.stderr if stream is None else stream
    if not on_terminal(out):
        return _Quiet()

    def log(msg: str) -> None:
        print(msg, file=out, flush=True)

    return Heartbeat(log, label, every=every, first=first, first_after=first_after)
