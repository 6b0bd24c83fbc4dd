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


@pytest.fixture(autouse=True)
def _sys_path_restored():
    """sys.path and sys.meta_path as they were before each test: a user's MODULE:FUNCTION imported
    from the test's folder keeps that folder searched for the process (experiments.user_methods.import_named),
    and a later test's "cannot import mysw" found the earlier test's mysw.py through it."""
    import sys

    saved, finders = list(sys.path), list(sys.meta_path)
    yield
    sys.path[:] = saved
    sys.meta_path[:] = meta_path_after(finders, sys.meta_path)


def meta_path_after(before: list, now: list) -> list:
    """``sys.meta_path`` after a test: without the user folders' finders (FolderFinder) the test
    added, every other finder kept. The whole list put back dropped the finder that dask's import of
    the importlib_metadata backport appends (it deletes the standard PathFinder's
    find_distributions): importlib.metadata then found no installed package for the rest of the
    xdist worker (provenance.versions() gave python and platform alone, a flaky failure)."""
    from experiments.user_methods import FolderFinder

    return [f for f in now if not isinstance(f, FolderFinder) or f in before]


class _UserMethodsDropped(dict):
    """The extractor registry during a test: the built-in methods it loads stay registered
    afterwards (their modules register once), the MODULE:FUNCTION ones registered here do not."""

    def __init__(self, real: dict) -> None:
        super().__init__(real)
        self.real = real

    def __setitem__(self, key, value) -> None:
        super().__setitem__(key, value)
        if ":" not in key:
            self.real[key] = value


@pytest.fixture
def user_methods_dropped(monkeypatch: pytest.MonkeyPatch) -> None:
    """A user's MODULE:FUNCTION extractors registered by the test are gone after it."""
    from features import registry

    monkeypatch.setattr(registry, "_REGISTRY", _UserMethodsDropped(registry._REGISTRY))


def pytest_xdist_auto_num_workers(config: pytest.Config) -> int:
    """``-n auto`` (`make test`): one worker more than the cores this process may use. Part of the
    suite waits rather than computes (Ctrl-C and kill tests wait for a child's line, the virtual
    LMS200 device paces its telegrams, progress tests wait for a heartbeat), and a third worker on
    two cores fills those waits: pytest's time on the 2-core machine 262 s -> 233 s (3 workers;
    237 s with 4), 2026-12-06, idle. ``PYTEST_XDIST_AUTO_NUM_WORKERS`` still sets it."""
    import os

    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return cores + 1


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Under pytest-xdist, the modules with a test marked ``slow`` first (each whole, in their
    order), then the rest as collected: a test of 20 s that starts last keeps one core busy while
    the other has nothing left (``--dist worksteal``, in the Makefile, moves queued tests to an
    idle worker, not a running one); started first, the other worker takes the quick ones
    meanwhile. A module stays together, so its module-scoped fixtures are built once a worker
    (the slow tests alone first split modules, and a fixture of both halves was built twice). The
    order is the same in every worker (xdist requires it). In one process (``-n 0``) it is left."""
    if getattr(config, "workerinput", None) is None:
        return
    slow_modules = {item.module for item in items if item.get_closest_marker("slow") is not None}
    items.sort(key=lambda item: item.module not in slow_modules)  # stable: False (a slow module) first


def pytest_configure(config: pytest.Config) -> None:
    """Under pytest-xdist (`make test` runs ``-n auto``), compile the numba kernels once, in the
    controller, before the workers start: the extractors', the default SLAM's and the simulator's
    (a 0.1 s run of the `mit` world). Each worker then loads them from numba's on-disk cache
    instead of compiling all of them again (about 40 s each on a fresh checkout), and no test's
    output carries a "compiling kernels" line that depends on which worker ran first. Not for
    ``--collect-only``; a warm-up that fails is one warning line, and the tests then show what
    fails. (`make test` compiles most of them beforehand, during its static checks: tests/warm_kernels.py.)"""
    if getattr(config, "workerinput", None) is not None or not getattr(config.option, "numprocesses", None):
        return
    if config.option.collectonly:
        return
    import sys

    from experiments.progress import warm_up_kernels

    said: list[str] = []  # warm_up_kernels speaks only when numba compiles (a cache load says nothing)
    try:
        seconds = warm_up_kernels(log=said.append, slam=True)
        from warm_kernels import warm_simulator

        warm_simulator()
    except Exception as exc:  # noqa: BLE001 - the tests themselves report what is broken
        print(f"warning: compiling the numba kernels before the workers failed ({type(exc).__name__}: {exc}); "
              "each worker compiles its own", file=sys.stderr)
        return
    if said:
        print(f"numba kernels compiled once for the workers in {seconds:.0f} s", file=sys.stderr)
