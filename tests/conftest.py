"""Shared test fixtures: where the real logs are, and a skip when they are absent."""

from __future__ import annotations

from pathlib import Path

import pytest

SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "carmen"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The folder of real CARMEN logs (../shared/data/carmen); skips the test where it is absent."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"real logs not present at {SHARED_DATA} (only on the project's own machines)")
    return SHARED_DATA


def pytest_configure(config: pytest.Config) -> None:
    """Under pytest-xdist (`make test` runs ``-n``), compile the numba kernels once, in the
    controller, before the workers start: each worker then loads them from numba's on-disk cache
    instead of compiling all of them again (about 40 s each on a fresh checkout), and no test's
    output carries a "compiling kernels" line that depends on which worker ran first."""
    if getattr(config, "workerinput", None) is not None or not getattr(config.option, "numprocesses", None):
        return
    import sys

    from experiments.progress import warm_up_kernels

    seconds = warm_up_kernels(log=lambda msg: None, slam=True)
    if seconds > 1.0:
        print(f"numba kernels compiled once for the workers in {seconds:.0f} s", file=sys.stderr)
