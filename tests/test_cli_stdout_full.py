"""A standard output that cannot be written (``> /dev/full``, a full disk under ``> FILE``): one
line on stderr and exit status 2, never a silent 0 (``lmsbench --help > /dev/full`` exited 0:
argparse swallows the OSError of its help's write)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from lms200 import Record, Scan, write_log

ROOT = Path(__file__).resolve().parents[1]
FULL = "no space left on device"


def _run(args: list[str], unbuffered: bool) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    if unbuffered:
        env["PYTHONUNBUFFERED"] = "1"
    with open("/dev/full", "w") as full:
        return subprocess.run([sys.executable, "-m", "experiments.cli", *args], cwd=ROOT, env=env, stdout=full,
                              stderr=subprocess.PIPE, text=True, timeout=120)


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full")
@pytest.mark.parametrize("unbuffered", [False, True])
@pytest.mark.parametrize("args, name", [(["--help"], "lmsbench"), (["--version"], "lmsbench"),
                                        (["compare", "--help"], "lmsbench compare"), (["info", "LOG"], "lmsbench info")])
def test_a_standard_output_that_cannot_be_written_is_one_line_and_status_2(tmp_path, args, name, unbuffered):
    log = tmp_path / "run.clf"
    write_log(log, [Record(Scan(np.full(181, 2.0), -np.pi / 2, np.pi / 180, 0.0, 8.183, stamp=float(k))) for k in range(3)])
    out = _run([str(log) if a == "LOG" else a for a in args], unbuffered)
    assert (out.returncode, out.stderr) == (2, f"{name}: error: cannot write the standard output: {FULL}\n")


def test_pointing_a_stdout_without_a_descriptor_at_dev_null_leaks_no_descriptor(monkeypatch):
    """stdout's reader gone, its descriptor is pointed at /dev/null; a stdout with none (a StringIO,
    as a library caller's capture) left the /dev/null descriptor open on every call (a review)."""
    import io
    import os

    from experiments.cli import _stdout_to_devnull

    monkeypatch.setattr(sys, "stdout", io.StringIO())
    before = len(os.listdir("/proc/self/fd"))
    for _ in range(50):
        _stdout_to_devnull()
    assert len(os.listdir("/proc/self/fd")) == before
