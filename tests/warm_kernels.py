"""Compile (or load) the numba kernels the test suite's warm-up needs, in parts that can run side by side.

`make test` runs ``python tests/warm_kernels.py sensor`` and ``... others`` in the background while
``make check`` (ruff, mypy) runs: on a fresh checkout (CI's) the kernels took ~85 s of CPU to
compile in the one controller process of tests/conftest.py (pytest_configure) before any worker
started, after the static checks. The two parts share no kernel that takes long (the sensor
method's, with its pooled noise estimate; the Cartesian baselines' and the simulator's); the
default SLAM's run the sensor method, so they are left to conftest's warm-up, which then loads the
rest from numba's cache (a load says nothing). Quiet; a failure here is only a lost head start:
conftest's warm-up and the tests themselves say what is broken."""

from __future__ import annotations

import sys

PARTS = ("sensor", "others")


def warm(part: str) -> None:
    """Compile or load one part's kernels: "sensor", or "others" (split_merge, iepf, the simulator)."""
    from experiments.progress import COMPILED_METHODS, warm_up_kernels

    if part == "sensor":
        warm_up_kernels(log=lambda msg: None, methods=("sensor",))
    elif part == "others":
        warm_up_kernels(log=lambda msg: None, methods=tuple(m for m in COMPILED_METHODS if m != "sensor"))
        warm_simulator()
    else:
        raise SystemExit(f"usage: python tests/warm_kernels.py {{{','.join(PARTS)}}}")


def warm_simulator() -> None:
    """The simulator's kernels: a 0.1 s run of the `mit` world (its ray hits, depth steps, mixed returns)."""
    from sim import simulate_records

    simulate_records("mit", seed=0, duration=0.1, rate_hz=10)


if __name__ == "__main__":
    for name in sys.argv[1:] or [""]:
        warm(name)
