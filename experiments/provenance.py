"""What a result needs beside it to be reproduced: the versions of the code and libraries that
made it, and a fresh timestamped run folder when no ``--out`` is given (linked as ``latest`` once
the run has finished)."""

from __future__ import annotations

import contextlib
import datetime
import os
import platform
import subprocess
import sys
from importlib import metadata
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence

from lms200.finite import printable

#: Distributions whose version can change a result.
PACKAGES = ("lmsbench", "numpy", "scipy", "numba", "pybullet", "pandas", "filterpy", "gtsam", "matplotlib")


def versions() -> dict[str, str]:
    """Python, the platform, the installed version of every package in PACKAGES (absent ones are
    left out) and, run from a git checkout, its commit (``lmsbench_git``, as ``lmsbench
    --version`` gives it): the package's version alone did not tell two checkouts apart."""
    out = {"python": platform.python_version(), "platform": f"{sys.platform}-{platform.machine()}"}
    for name in PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    commit = checkout_commit()
    if commit is not None:
        out["lmsbench_git"] = commit
    return out


#: the checkout this module lies in (lmsbench installed editable, ``make setup``), if a git one
CHECKOUT = Path(__file__).resolve().parents[1]
GIT_TIMEOUT_S = 5.0  # s: a git that does not answer leaves the commit out


def checkout_commit() -> str | None:
    """The commit of the git checkout lmsbench runs from ("2a1ee83d2902", with ", modified" when
    tracked files differ from it), or None where it runs from no checkout (an installed wheel) or
    git cannot say (not installed, not a repository). Two quick git calls, no import."""
    if not (CHECKOUT / ".git").exists():  # a folder, or a worktree's file
        return None
    try:
        head = subprocess.run(["git", "-C", str(CHECKOUT), "rev-parse", "--short=12", "HEAD"], capture_output=True,
                              text=True, timeout=GIT_TIMEOUT_S)
        if head.returncode != 0 or not head.stdout.strip():
            return None
        status = subprocess.run(["git", "-C", str(CHECKOUT), "status", "--porcelain", "--untracked-files=no"],
                                capture_output=True, text=True, timeout=GIT_TIMEOUT_S)
    except (OSError, subprocess.SubprocessError):
        return None
    modified = status.returncode == 0 and bool(status.stdout.strip())
    return head.stdout.strip() + (", modified" if modified else "")


def version_text() -> str:
    """What ``lmsbench --version`` prints: the installed package's version and, run from a git
    checkout, its commit: ``lmsbench 0.1.0 (git 2a1ee83d2902)``."""
    try:
        text = f"lmsbench {metadata.version('lmsbench')}"
    except metadata.PackageNotFoundError:  # run from a checkout that was never installed
        text = "lmsbench (not installed)"
    commit = checkout_commit()
    return text + (f" (git {commit})" if commit else "")


def new_run_folder(base: str | os.PathLike, now: datetime.datetime | None = None) -> Path:
    """A new folder ``base/YYYY-MM-DD_HH-MM-SS`` (``-2``, ``-3``, ... when taken), so runs never
    overwrite each other. ``base/latest`` is not moved here: :func:`link_latest` moves it once the
    run has written all its outputs (it moved here, at the start, so a run stopped by Ctrl-C or an
    error left ``latest`` naming its partial folder, the last finished run no longer linked)."""
    base = Path(base)
    base.mkdir(parents=True, exist_ok=True)
    stamp = (now or datetime.datetime.now()).strftime("%Y-%m-%d_%H-%M-%S")
    folder, n = base / stamp, 1
    while True:
        try:
            folder.mkdir()
            return folder
        except FileExistsError:
            n += 1
            folder = base / f"{stamp}-{n}"


def link_latest(folder: str | os.PathLike) -> Path:
    """Point the symlink ``latest`` beside ``folder`` (a run folder of :func:`new_run_folder`) at
    it: called by a command once its outputs there are complete, so ``latest`` always names the
    last run that finished. Returns the link."""
    folder = Path(folder)
    latest = folder.parent / "latest"
    tmp = folder.parent / f".latest.{os.getpid()}"
    tmp.unlink(missing_ok=True)
    tmp.symlink_to(folder.name)
    os.replace(tmp, latest)  # atomic: `latest` always names a whole run
    return latest


def write_record(path: str | os.PathLike, content: str | Callable[[Path], object]) -> Path:
    """Write a file whole or not at all: ``content`` (text, or a function that writes the file at
    the path it is given) goes into a hidden temporary file beside ``path``, renamed over it
    (``os.replace`` is atomic on POSIX). The files that tell a command's --out folder as its own
    (``experiments.options.Owner``'s records) are written this way, the first of them before any
    other output, so a run stopped at any moment (Ctrl-C, kill) leaves a folder the next run into
    the same --out recognises: files written before the record, or a record cut empty, were "not
    written by an earlier run" and refused that run."""
    from lms200.logs import write_whole

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    # .NAME.PID.tmp, hidden: check_out passes it over; an existing file's permission bits are kept, a
    # symbolic link's target is replaced (write_whole)
    if callable(content):
        return write_whole(path, content)
    text = printable(content)  # sim2real's report.md of a log under b<0xff>/ failed after the whole run
    return write_whole(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))


def write_parquet(table: Any, path: str | os.PathLike) -> None:
    """A pandas table as Parquet at ``path``, through a file handle: pyarrow opens a path itself only
    when it is UTF-8 (`compare --out b<0xff>` failed at its table, after the work)."""
    with open(path, "wb") as fh:
        table.to_parquet(fh, index=False)


def read_parquet(path: str | os.PathLike, **kwargs: Any) -> Any:
    """``pandas.read_parquet(path, **kwargs)``, through a file handle where the path is not UTF-8
    (pyarrow's own open failed: `figures --tables b<0xff>`); a path that is no regular file is given
    to pyarrow as before (a pipe there is its error, not a wait in ``open``)."""
    import pandas as pd

    name = os.fspath(path)
    if printable(name) == name or not Path(path).is_file():
        return pd.read_parquet(path, **kwargs)
    with open(path, "rb") as fh:
        return pd.read_parquet(fh, **kwargs)


def leftover_temporaries(path: str | os.PathLike) -> list[Path]:
    """The temporary files :func:`write_record` left beside ``path`` in a process that was killed
    before it renamed them (``.NAME.PID.tmp`` only: a user's ``.NAME.notes.tmp`` is not one)."""
    from lms200.logs import temporaries

    return [tmp for tmp, _ in temporaries(Path(path))]


def write_synced(path: Path, text: str) -> None:
    """``text`` into ``path``, on disk (the file and its folder's entry) when this returns."""
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(text)
        fh.flush()
        os.fsync(fh.fileno())
    fsync_path(path.parent)


def fsync_path(path: Path) -> None:
    """Push a file's bytes, or a folder's entries, to the disk."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextlib.contextmanager
def marked_unfinished(out: Path, marker: str, text: str, outputs: Sequence[str]) -> Iterator[None]:
    """Write a command's ``outputs`` (file names in ``out``) inside this block, with the folder marked
    unfinished meanwhile: a killed run's temporary files of them (and of ``marker``) removed, then
    ``marker`` written whole and on disk before any output, holding ``text`` (the run's settings),
    and removed once every output is on disk. A run stopped or killed in the block (Ctrl-C, SIGKILL,
    a crash, a power loss) leaves the marker, which the readers of the folder refuse
    (``experiments.options.check_simulate_finished`` / ``check_sim2real_finished``); an exception in
    the block leaves it too. ``lmsbench simulate`` and ``sim2real`` write their folders so."""
    out.mkdir(parents=True, exist_ok=True)
    for name in (*outputs, marker):  # .NAME.PID.tmp only: not a user's own .scans.clf.notes.tmp (a review)
        for tmp in leftover_temporaries(out / name):
            tmp.unlink(missing_ok=True)
    unfinished = out / marker
    write_record(unfinished, lambda tmp: write_synced(tmp, text))  # whole or not at all: a cut one lost settings
    fsync_path(out)
    yield
    for name in outputs:  # on disk before the marker goes: after a power loss it stays, or they are whole
        fsync_path(out / name)
    fsync_path(out)
    unfinished.unlink()
    fsync_path(out)
