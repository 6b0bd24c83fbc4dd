"""The commands' kernel warm-up (experiments.progress.warm_up_kernels) leaves nothing to compile
for a real log's run: after it, extracting from cm-mode scans (whose noise the sensor method
estimates, "auto") one by one and in a batch, and the default SLAM over them, add no numba
signature, nor scans 2 s apart (the correlative search's kernels). Otherwise a first run on a
fresh checkout times the compiler (MIT CSAIL's SLAM reported 375 scans/s instead of ~1,000 when
the auto-noise kernels were left out)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import sys
import numpy as np
import numba
from experiments.progress import warm_up_kernels

warm_up_kernels(log=lambda msg: None, slam=True)

def signatures():
    return {(name, attr): len(obj.signatures) for name, mod in list(sys.modules.items())
            if name.startswith(("features", "slam", "lms200")) and mod is not None
            for attr, obj in list(vars(mod).items()) if isinstance(obj, numba.core.registry.CPUDispatcher)}

before = signatures()
from features import available_methods, extract, extract_many
from lms200 import Record, Scan
from slam import SlamConfig, run_slam

rng = np.random.default_rng(3)
b = np.deg2rad(np.linspace(-90, 90, 361))
walls = np.minimum(3.0 / np.maximum(np.abs(np.cos(b)), 1e-9), 4.0 / np.maximum(np.abs(np.sin(b)), 1e-9))
scans = [Scan.lms200(np.round(np.minimum(walls - 0.03 * k, 50.0) + 0.01 * rng.standard_normal(361), 2),
                     stamp=0.2 * k, range_max=81.83) for k in range(6)]
for m in ("sensor", "split_merge", "iepf"):
    extract(scans[0], m)
    extract_many(scans, m)
run_slam([Record(scan=s) for s in scans], SlamConfig())
sparse = run_slam([Record(scan=s.replace(stamp=2.0 * k)) for k, s in enumerate(scans)], SlamConfig())
assert sparse.diagnostics["searched_fraction"] == 1.0  # 2 s apart: the correlative search on every step
after = signatures()
print(sorted(f"{n}.{a}" for (n, a), c in after.items() if c != before.get((n, a), 0)))
"""


@pytest.mark.slow
def test_warm_up_leaves_nothing_to_compile_for_cm_mode_logs() -> None:
    out = subprocess.run([sys.executable, "-c", CHILD], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().splitlines()[-1] == "[]", out.stdout


@pytest.mark.slow
def test_a_warm_up_from_the_cache_says_nothing() -> None:
    """Once the kernels are cached (the test above compiled them), a new process's warm-up loads
    them without a word: "compiling kernels, once" is for compiles only, however long a load takes."""
    child = ("from experiments.progress import warm_up_kernels\n"
             "said = []\n"
             "warm_up_kernels(log=said.append, slam=True)\n"
             "print(said)\n")
    out = subprocess.run([sys.executable, "-c", child], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().splitlines()[-1] == "[]", out.stdout


def test_the_compile_watch_sees_compiles_and_not_calls() -> None:
    import numba

    from experiments.progress import _compile_watch
    from numba.core import event

    def plus_one(x: float) -> float:
        return x + 1.0

    fn = numba.njit(plus_one)  # not cached: this process compiles it
    watch, again = _compile_watch(), _compile_watch()
    event.register("numba:compile", watch)
    try:
        assert not watch.compiled
        assert fn(1.0) == 2.0 and watch.compiled
    finally:
        event.unregister("numba:compile", watch)
    event.register("numba:compile", again)
    try:
        assert fn(2.0) == 3.0 and not again.compiled  # compiled already: a call, no compile
    finally:
        event.unregister("numba:compile", again)


def test_the_heartbeat_waits_for_its_condition() -> None:
    import threading
    import time

    from experiments.progress import Heartbeat

    said: list[str] = []
    spoke = threading.Event()
    started = threading.Event()

    def log(msg: str) -> None:
        said.append(msg)
        spoke.set()

    with Heartbeat(log, "step", first="slow step ...", first_after=0.0, when=started.is_set):
        time.sleep(0.6)  # the heartbeat polls every 0.25 s: past first_after, but the slow part has not begun
        assert said == []
        started.set()
        assert spoke.wait(10.0)  # generous: a loaded machine may run the polling thread late
    assert said == ["slow step ..."]


def test_a_heartbeat_inside_another_speaks_for_both() -> None:
    """The first demo printed '   ... demo: 5 s' and '   ... compiling kernels: 5 s' together (a new
    user's review): the demo's heartbeat and the compile's, one inside the other, each on its own
    clock. While the inner one has announced itself, the outer keeps quiet; after it, the outer
    speaks again."""
    import threading
    import time

    from experiments.progress import Heartbeat

    said: list[str] = []
    outer_spoke = threading.Event()

    def log(msg: str) -> None:
        said.append(msg)
        if "outer" in msg:
            outer_spoke.set()

    with Heartbeat(log, "outer", every=0.3):
        with Heartbeat(log, "inner", every=0.3):  # no first line: announced from the start
            time.sleep(1.6)  # about six polls of each
        inner = list(said)
        assert outer_spoke.wait(10.0)  # generous: a loaded machine may run the polling thread late
    assert inner and all("inner" in line for line in inner), inner
    assert any("outer" in line for line in said[len(inner):]), said


def test_sim2real_and_calibrate_beat_on_a_terminal_only() -> None:
    """sim2real ran 2-3 min at its defaults without a line on a terminal (calibrate 10-15 s); they
    now beat like the demo there, and stay silent off a terminal (stderr keeps an error's one line)."""
    import io
    import time

    from experiments.progress import heartbeat_on_terminal

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    # The terminal's two lines are waited for (a deadline): the heartbeat thread polls every 0.25 s,
    # and a fixed 1.0 s sleep left 0.25 s of slack for a thread a loaded machine runs late. The
    # pipe gets at least as long as the terminal needed for its two lines.
    tty, pipe = Terminal(), io.StringIO()
    t0 = time.monotonic()
    with heartbeat_on_terminal("sim2real", "sim2real: starting ...", stream=tty, every=0.3, first_after=0.0):
        while len(tty.getvalue().splitlines()) < 2 and time.monotonic() < t0 + 30.0:
            time.sleep(0.05)
    needed = time.monotonic() - t0
    with heartbeat_on_terminal("sim2real", "sim2real: starting ...", stream=pipe, every=0.3, first_after=0.0):
        time.sleep(max(1.0, needed))
    lines = tty.getvalue().splitlines()
    assert lines[0] == "sim2real: starting ..." and len(lines) >= 2
    assert all(line.startswith("   ... sim2real: ") and line.endswith(" s") for line in lines[1:])
    assert pipe.getvalue() == ""
