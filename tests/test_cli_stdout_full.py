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


def _closed(args: list[str], fd: int, timeout: float = 120) -> subprocess.CompletedProcess:
    """``lmsbench ARGS`` with standard descriptor ``fd`` closed (``>&-``: 1, ``2>&-``: 2); the other
    one captured."""
    return subprocess.run([sys.executable, "-m", "experiments.cli", *args], cwd=ROOT, timeout=timeout,
                          stdout=subprocess.PIPE if fd == 2 else None, stderr=subprocess.PIPE if fd == 1 else None,
                          preexec_fn=lambda: os.close(fd), text=True)


CLOSED = "cannot write the standard output: bad file descriptor (it was closed)"


@pytest.mark.parametrize("args, name", [(["--help"], "lmsbench"), (["--version"], "lmsbench"),
                                        (["info", "LOG"], "lmsbench info")])
def test_a_closed_standard_output_is_one_line_and_status_2(tmp_path, args, name):
    """``lmsbench info LOG >&-`` was "internal error: AttributeError: 'NoneType' object has no
    attribute 'write'" and a traceback, exit 1 (Python leaves sys.stdout None): now as ``> /dev/full``."""
    log = tmp_path / "run.clf"
    write_log(log, [Record(Scan(np.full(181, 2.0), -np.pi / 2, np.pi / 180, 0.0, 8.183, stamp=float(k))) for k in range(3)])
    out = _closed([str(log) if a == "LOG" else a for a in args], 1)
    assert (out.returncode, out.stderr) == (2, f"{name}: error: {CLOSED}\n")


def test_a_closed_standard_output_keeps_a_user_errors_line_and_status():
    out = _closed(["info", "/nonexistent/log.clf"], 1)
    assert (out.returncode, out.stderr) == (2, "lmsbench info: error: /nonexistent/log.clf: no such log\n")
    out = _closed([], 1)  # no command: its usage line, and no traceback of the exit's flush
    assert out.returncode == 2 and out.stderr.startswith("lmsbench: error: a command is required: ")
    assert out.stderr.count("\n") == 1


def test_a_closed_standard_error_keeps_the_status_and_stdout_clean(tmp_path):
    """``2>&-``: Python leaves sys.stderr None, and print(file=None) writes to stdout: a user error's
    line went to stdout; ``simulate`` failed with "internal error: ImportError: cannot import name
    'simulate_records' from 'sim'" on stdout, exit 1."""
    out = _closed(["info", "/nonexistent/log.clf"], 2)
    assert (out.returncode, out.stdout) == (2, "")
    out = _closed(["simulate", "--duration", "0.2", "--out", str(tmp_path / "sim"), "--quiet"], 2)
    assert (out.returncode, out.stdout) == (0, f"simulated 7 scans of world office (seed 0, 0.2 s) into {tmp_path / 'sim'}\n")


class _FullStream:
    """A text stream every write of which fails as one to /dev/full does."""

    def write(self, text: str) -> int:
        raise OSError(28, "No space left on device")

    def flush(self) -> None:
        pass


@pytest.mark.parametrize("args, status, out", [(["info", "{tmp}/none.clf"], 2, ""), (["info", "--bogus"], 2, ""),
                                               (["--version"], 0, "lmsbench ")])
def test_a_standard_error_that_cannot_be_written_keeps_the_status(tmp_path, monkeypatch, capsys, args, status, out):
    """``lmsbench info MISSING 2>/dev/full``: the OSError of the error's own line came out of its handler,
    and the user error exited 1 (an uncaught exception), not 2; every user error exits 2, said or not."""
    from experiments.cli import main

    monkeypatch.setattr(sys, "stderr", _FullStream())
    assert main([a.format(tmp=tmp_path) for a in args]) == status
    said = capsys.readouterr().out
    assert said.startswith(out) and (said if out else "") == said


def test_a_closed_standard_descriptor_is_not_taken_by_the_next_file_opened(tmp_path):
    """With fd 2 closed, the next file opened took number 2, and whatever wrote to "stderr" (a C
    library, a child process) wrote into it; it is pointed at /dev/null first."""
    code = ("import os, sys; from experiments.cli import _standard_streams; _standard_streams(); "
            f"f = open({str(tmp_path / 'f')!r}, 'w'); print(f.fileno(), sys.stderr is not None, os.path.realpath('/proc/self/fd/2'))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, stdout=subprocess.PIPE, text=True, timeout=60,
                         preexec_fn=lambda: os.close(2))
    fd, has_stderr, target = out.stdout.split()
    assert (int(fd) > 2, has_stderr, target) == (True, "True", "/dev/null")


def test_a_closed_standard_descriptor_is_reopened_inheritable_for_child_processes():
    """os.open's /dev/null on the closed fd 2 was not inherited (PEP 446): a Dask worker of
    `lmsbench sweep S.yaml 2>&-` started with fd 2 closed, its sys.stderr None, and every cell
    failed ("ImportError: cannot import name 'simulate_records' from 'sim'"), exit 1."""
    code = ("import subprocess, sys; from experiments.cli import _standard_streams; _standard_streams(); "
            "print(subprocess.run([sys.executable, '-c', 'import sys; print(sys.stderr is not None)'], "
            "stdout=subprocess.PIPE, text=True).stdout.strip())")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, stdout=subprocess.PIPE, text=True, timeout=60,
                         preexec_fn=lambda: os.close(2))
    assert out.stdout == "True\n"


@pytest.mark.parametrize("fd", [1, 2])
def test_importing_the_simulator_with_a_closed_standard_descriptor_keeps_the_other(fd):
    """sim.lidar silences fds 1 and 2 while pybullet prints its banner: with fd 2 closed, os.dup(1)
    took number 2 and stdout was /dev/null for the rest of the process (nothing printed, exit 0);
    with either closed, sys.stdout / sys.stderr None failed the import (AttributeError)."""
    code = ("import sys; from sim import LMS200Sim; "
            "print('imported', file=sys.stdout if sys.stdout is not None else sys.stderr)")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=60,
                         preexec_fn=lambda: os.close(fd))
    assert (out.returncode, out.stdout + out.stderr) == (0, "imported\n")
