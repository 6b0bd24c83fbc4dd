"""Progress for long steps: the one-off numba compile announced, and a heartbeat that prints a
line whenever a command has been silent for a few seconds (so a user never watches a dead
terminal). Drivers only: algorithm code never prints."""

from __future__ import annotations

import sys
import threading
import time
from pathlib import Path
from typing import Callable

import numpy as np

Log = Callable[[str], None]

#: Modules of compiled kernels (numba ``cache=True``): their cache sits in __pycache__ beside them.
KERNEL_MODULES = ("features.sensor.engine", "features.baselines.engine")
#: Methods that run those kernels.
COMPILED_METHODS = ("sensor", "split_merge", "iepf")


def stderr(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _kernels_cached() -> bool:
    """True when every kernel module has a numba cache index newer than its source."""
    import importlib.util

    for name in KERNEL_MODULES:
        spec = importlib.util.find_spec(name)
        if spec is None or spec.origin is None:
            continue
        src = Path(spec.origin)
        index = list((src.parent / "__pycache__").glob(f"{src.stem}.*.nbi"))
        if not index or min(p.stat().st_mtime for p in index) < src.stat().st_mtime:
            return False
    return True


def warm_up_kernels(log: Log = stderr) -> float:
    """Load (or compile, the first time in a checkout) the extractors' numba kernels now, saying
    "compiling kernels, once" when they are not cached yet. Returns the seconds it took."""
    from features import extract
    from lms200 import Scan

    cached = _kernels_cached()
    start = time.perf_counter()
    if not cached:
        log("compiling kernels, once (about 20-60 s; cached beside the code for every later run) ...")
    # a room-like scan: two walls meeting in a corner, so every kernel (lines, merging, corners) runs
    bearings = np.linspace(-np.pi / 2, np.pi / 2, 361)
    ranges = np.minimum(2.0 / np.maximum(np.cos(bearings), 1e-9), 3.0 / np.maximum(np.sin(bearings), 1e-9))
    ranges = np.where(ranges > 8.0, np.inf, ranges)
    scan = Scan.lms200(ranges + 0.002 * np.random.default_rng(0).standard_normal(361))
    with Heartbeat(log, "compiling kernels") if not cached else _nothing():
        for method in COMPILED_METHODS:
            extract(scan, method=method)
    seconds = time.perf_counter() - start
    if not cached:
        log(f"kernels compiled in {seconds:.0f} s")
    return seconds


class _nothing:
    def __enter__(self) -> None:
        return None

    def __exit__(self, *exc: object) -> None:
        return None


class Heartbeat:
    """While active, prints ``... LABEL: N s`` whenever nothing was said for ``every`` seconds.

    Use ``beat.say(msg)`` for the step's own messages (they reset the timer) and ``beat.label =``
    to name the current step."""

    def __init__(self, log: Log = stderr, label: str = "working", every: float = 4.0) -> None:
        self.log, self.label, self.every = log, label, every
        self.last = self.start = time.monotonic()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="lmsbench-heartbeat", daemon=True)

    def say(self, msg: str) -> None:
        self.last = time.monotonic()
        self.log(msg)

    def _run(self) -> None:
        while not self._stop.wait(0.5):
            now = time.monotonic()
            if now - self.last >= self.every:
                self.last = now
                self.log(f"   ... {self.label}: {now - self.start:.0f} s")

    def __enter__(self) -> "Heartbeat":
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()
