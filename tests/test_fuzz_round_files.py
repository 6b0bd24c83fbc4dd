"""Bad input found by a fuzz round over YAML files, output locations, inputs, interrupts and the
environment (2026-12-06). Each test failed on the code before its fix."""

from __future__ import annotations

import contextlib
import os
import resource
from pathlib import Path
from typing import Iterator

import numpy as np
import pytest

from experiments.sweep.spec import SweepSpecError, load_sweep
from lms200 import LmsbenchError
from slam.config import SlamConfig, SlamConfigError


# YAML keys may be null, numbers or true/false: with two or more unknown keys, one of them not text,
# sorting them for the message raised TypeError ('<' not supported between 'NoneType' and 'str'), an
# internal error: `lmsbench slam RUN --config C` and `lmsbench sweep F` with `~: 1` beside a misspelt key.

def test_a_slam_config_of_a_null_key_beside_an_unknown_one_names_both() -> None:
    with pytest.raises(SlamConfigError, match=r"^unknown SLAM config field\(s\) \[None, 'world'\]; known: "):
        SlamConfig.from_dict({None: 1, "world": "office"})
    with pytest.raises(SlamConfigError, match=r"^unknown field\(s\) \[1, 'x'\] in SLAM config section 'loop_closure'"):
        SlamConfig.from_dict({"loop_closure": {1: 2, "x": 3}})


def test_a_sweep_file_of_a_null_key_beside_an_unknown_one_names_both(tmp_path: Path) -> None:
    f = tmp_path / "s.yaml"
    f.write_text("~: 1\nworld: office\n")
    with pytest.raises(SweepSpecError, match=r"unknown key\(s\) \[None, 'world'\] in the sweep file") as err:
        load_sweep(f)
    assert isinstance(err.value, LmsbenchError)



def test_an_overlong_line_is_refused_without_reading_it_to_its_end(tmp_path: Path,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """Without --skip-bad-lines a line over MAX_LINE_CHARS is refused as soon as it is found: the reader
    read it to its end first, so a gzip of 4 GB of 'x' after a log's first scans (4 MB on disk) took 42 s
    of `lmsbench info` to be refused (memory bounded, time not)."""
    import lms200.carmen as carmen
    from lms200 import LogFormatError, read_log

    monkeypatch.setattr(carmen, "MAX_LINE_CHARS", 500)
    read = []
    real_open_text = carmen.open_text

    class Counting:
        def __init__(self, f) -> None:
            self.f = f

        def readline(self, n: int = -1) -> str:
            line = self.f.readline(n)
            read.append(len(line))
            return line

        def __enter__(self) -> Counting:
            return self

        def __exit__(self, *exc: object) -> None:
            self.f.close()

    monkeypatch.setattr(carmen, "open_text", lambda path: Counting(real_open_text(path)))
    scan = "FLASER 5 2.0 2.0 2.0 2.0 2.0 1 2 0.5 1 2 0.5 10.0 host 10.0"
    path = tmp_path / "bomb.clf"
    path.write_text(scan + "\n" + "x" * 2_000_000)
    with pytest.raises(LogFormatError, match=r"bomb\.clf:2: malformed overlong line: longer than 500 characters"):
        list(read_log(path))
    assert sum(read) < 20_000  # it read all 2,000,000 characters of the line before refusing it
    reader = read_log(path, skip_bad_lines=True)  # skipping it reads on, as it must, to the line's end
    assert [r.scan.stamp for r in reader] == [10.0] and reader.stats.skipped[0][:1] == (2,)


# A full disk while writing an output left it cut beside whole files, under the error line: slam's
# trajectory.tum of 0 bytes beside its config.yaml, a slam.png 'image file is truncated' beside a whole
# metrics.json, a figure's PNG / PDF / CSV, compare's table and summary.txt, sim2real's tables, a study's
# tables and notes. Each is now written whole (a hidden temporary file renamed into place). A file-size
# limit (RLIMIT_FSIZE; Python ignores SIGXFSZ, so a write past it fails with EFBIG) plays the full disk.

@contextlib.contextmanager
def file_size_limit(nbytes: int) -> Iterator[None]:
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    resource.setrlimit(resource.RLIMIT_FSIZE, (nbytes, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))


def test_write_tum_on_a_full_disk_leaves_the_earlier_file_whole(tmp_path: Path) -> None:
    from lms200 import InputError, read_tum, write_tum

    path = tmp_path / "trajectory.tum"
    write_tum(path, np.arange(3.0), np.zeros((3, 3)))
    before = path.read_bytes()
    with file_size_limit(200), pytest.raises(InputError, match=rf"^path: cannot write {path}: File too large$"):
        write_tum(path, np.arange(50.0), np.ones((50, 3)))
    assert path.read_bytes() == before  # it was cut to the 200 bytes the limit let through
    assert [p.name for p in tmp_path.iterdir()] == ["trajectory.tum"]  # no temporary file left
    assert len(read_tum(path)[0]) == 3
    with file_size_limit(200), pytest.raises(InputError):
        write_tum(tmp_path / "new.tum", np.arange(50.0), np.ones((50, 3)))
    assert not (tmp_path / "new.tum").exists()  # a new file: none at all, not a cut one


def test_save_figure_on_a_full_disk_leaves_no_cut_figure(tmp_path: Path) -> None:
    import matplotlib.pyplot as plt
    import pandas as pd

    from experiments.style import save_figure

    table = pd.DataFrame({"x": np.arange(100.0)})
    for formats, limit in ((("png", "pdf"), 4000), ((), 300)):  # (PIL removes a PNG it could not finish)
        fig, ax = plt.subplots()
        ax.plot(np.arange(100.0), np.sin(np.arange(100.0)))
        with file_size_limit(limit), pytest.raises(OSError, match="File too large"):
            save_figure(fig, tmp_path / "fig", table, formats=formats)
        assert list(tmp_path.iterdir()) == []  # a fig.pdf of the 4000 bytes, a fig.csv of 300 were left
        plt.close("all")


def test_slam_png_on_a_full_disk_is_not_left_cut(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import errno
    from types import SimpleNamespace

    import experiments.slamrun as slamrun

    def plot_to_a_full_disk(path: Path, data: object, result: object) -> None:
        Path(path).write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(100))  # the first bytes, then no room
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(slamrun, "plot", plot_to_a_full_disk)
    with pytest.raises(OSError, match="No space left"):
        slamrun.write_scores(tmp_path, SimpleNamespace(), SimpleNamespace(metrics={"ate": 0.1}, result=None))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["metrics.json"]  # and a cut slam.png beside it


def test_a_home_where_matplotlib_cannot_make_its_folder_adds_no_lines(tmp_path: Path) -> None:
    """HOME=/dev/null (as a read-only or missing home: a container run as a user without one has HOME=/):
    matplotlib said "mkdir -p failed for path /dev/null/.config/matplotlib ..." and "Matplotlib created
    a temporary cache directory at ..." on stderr of every command that draws, above its own lines."""
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k not in ("MPLCONFIGDIR", "XDG_CONFIG_HOME", "XDG_CACHE_HOME")}
    env["HOME"] = "/dev/null"
    code = ("import sys\nfrom experiments.cli import main\nstatus = main(['--version'])\n"  # then a command's drawing
            "import matplotlib.pyplot as plt\nplt.figure().savefig(sys.argv[1])\nprint('drawn')\nsys.exit(status)\n")
    run = subprocess.run([sys.executable, "-c", code, str(tmp_path / "f.png")], env=env, cwd=Path(__file__).resolve().parents[1],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0 and run.stdout.endswith("\ndrawn\n"), run
    assert run.stderr == ""


def test_compare_into_its_own_folder_whose_summary_txt_is_a_pipe_does_not_wait_for_ever(tmp_path: Path) -> None:
    """A named pipe in place of one of compare's own outputs (summary.txt) in a folder an earlier compare
    wrote: the write opened the pipe and waited for a reader for ever (a hang, Ctrl-C only). Written
    whole now, the pipe is replaced by the new file."""
    import signal
    import stat

    from experiments.cli import main

    out = tmp_path / "c"
    argv = ["compare", "office:0", "--duration", "1", "--rate", "2", "--methods", "split_merge", "--out", str(out),
            "--quiet"]
    assert main(argv) == 0
    (out / "summary.txt").unlink()
    os.mkfifo(out / "summary.txt")

    def hang(*_: object) -> None:
        raise TimeoutError("compare waited on the pipe for 60 s")

    previous = signal.signal(signal.SIGALRM, hang)
    signal.alarm(60)
    try:
        assert main(argv) == 0
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    assert stat.S_ISREG((out / "summary.txt").stat().st_mode)
    assert (out / "summary.txt").read_text().startswith("source")


# A full disk while matplotlib writes a PDF (compare's realdata_* figures, `figures`): its PDF backend,
# cleaning up after the failed write, raised an error of its own that masked the OSError (ENOSPC) in its
# __context__: `internal error: AttributeError: 'Stream' object has no attribute 'pos'` (or a zlib
# 'error'), exit 1, instead of the one line a full disk is (on a 72 KB tmpfs: `unshare -m sh -c 'mount -t
# tmpfs -o size=72k tmpfs full && lmsbench compare LOG --methods split_merge --out full/c'`).

def _pdf_disk_full_after(monkeypatch: pytest.MonkeyPatch, nbytes: int) -> None:
    """The files matplotlib opens to write (its PDFs) find no room after ``nbytes`` bytes."""
    import errno

    import matplotlib.cbook as cbook

    opened = cbook.to_filehandle

    class Full:
        def __init__(self, fh: object) -> None:
            self.fh = fh

        def write(self, data: bytes) -> int:
            if self.fh.tell() + len(data) > nbytes:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            return self.fh.write(data)

        def __getattr__(self, name: str) -> object:
            return getattr(self.fh, name)

    def to_filehandle(fname: object, flag: str = "r", return_opened: bool = False, encoding: object = None) -> object:
        fh, was_opened = opened(fname, flag, True, encoding)
        if "w" in flag:
            fh = Full(fh)
        return (fh, was_opened) if return_opened else fh

    monkeypatch.setattr(cbook, "to_filehandle", to_filehandle)


@pytest.mark.parametrize("nbytes", [500, 2200])  # matplotlib's zlib error, its AttributeError
def test_save_figure_of_a_pdf_on_a_full_disk_raises_the_full_disk(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                   nbytes: int) -> None:
    import errno

    import matplotlib.pyplot as plt

    from experiments.style import save_figure

    _pdf_disk_full_after(monkeypatch, nbytes)
    fig, ax = plt.subplots()
    ax.plot(range(100))
    with pytest.raises(OSError) as raised:
        save_figure(fig, tmp_path / "fig", None, formats=("pdf",))
    assert type(raised.value) is OSError and raised.value.errno == errno.ENOSPC
    assert list(tmp_path.iterdir()) == []  # no cut fig.pdf, no temporary file
    plt.close("all")


def test_compare_writing_a_pdf_on_a_full_disk_says_so_in_one_line(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                   capsys: pytest.CaptureFixture) -> None:
    import tempfile

    from experiments.cli import main
    from test_log_readers import flaser, write

    log = write(tmp_path, "short-corrected.log", [flaser(181, value=2.0 + t / 10, stamp=float(t)) for t in range(8)])
    out = tmp_path / "c"
    _pdf_disk_full_after(monkeypatch, 2200)
    assert main(["compare", str(log), "--methods", "split_merge", "--no-progress", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err == (f"lmsbench compare: error: cannot write: no space left on device (on the disk of --out {out} "
                   f"or of the temporary folder {tempfile.gettempdir()})\n"), err
    assert not [p for p in out.iterdir() if p.suffix == ".pdf" or p.name.endswith(".tmp")]


# Whole-file writes (a temporary file renamed into place) changed two things a write in place kept: an
# existing file's permission bits (a 0600 trajectory.tum or fig.pdf became 0664 / 0644, the umask's),
# and a symbolic link (fig.pdf -> paper/fig.pdf: the link was replaced by a regular file, paper/fig.pdf
# left as it was). Both held for every whole-file output, through lms200.logs.write_whole.

def _figure() -> object:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.plot([1.0, 2.0])
    return fig


def test_write_tum_keeps_an_existing_files_mode_and_writes_through_a_symbolic_link(tmp_path: Path) -> None:
    import stat

    from lms200 import read_tum, write_tum

    own = tmp_path / "own.tum"
    own.write_text("old\n")
    own.chmod(0o600)
    write_tum(own, np.arange(3.0), np.zeros((3, 3)))
    assert stat.S_IMODE(own.stat().st_mode) == 0o600 and len(read_tum(own)[0]) == 3
    (tmp_path / "real").mkdir()
    target = tmp_path / "real" / "t.tum"
    target.write_text("old\n")
    link = tmp_path / "link.tum"
    link.symlink_to(target)
    write_tum(link, np.arange(4.0), np.zeros((4, 3)))
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert len(read_tum(target)[0]) == 4
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.tum", "own.tum", "real"]
    assert [p.name for p in (tmp_path / "real").iterdir()] == ["t.tum"]  # no temporary file left


def test_save_figure_keeps_an_existing_files_mode_and_writes_through_a_symbolic_link(tmp_path: Path) -> None:
    import stat

    import pandas as pd

    from experiments.style import save_figure

    (tmp_path / "fig.pdf").write_text("old")
    (tmp_path / "fig.pdf").chmod(0o600)
    save_figure(_figure(), tmp_path / "fig", None, formats=("pdf",))
    assert stat.S_IMODE((tmp_path / "fig.pdf").stat().st_mode) == 0o600
    assert (tmp_path / "fig.pdf").read_bytes().startswith(b"%PDF")
    (tmp_path / "paper").mkdir()
    target = tmp_path / "paper" / "linked.pdf"
    target.write_text("old")
    (tmp_path / "linked.pdf").symlink_to(target)
    save_figure(_figure(), tmp_path / "linked", pd.DataFrame({"x": [1]}), formats=("pdf",))
    assert (tmp_path / "linked.pdf").is_symlink() and target.read_bytes().startswith(b"%PDF")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig.pdf", "linked.csv", "linked.pdf", "paper"]


def _draw_with_home(tmp_path: Path, env_set: dict[str, str], before: str = "") -> str:
    """stderr of main(['--version']), then a drawing, in a process of its own with ``env_set``."""
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k not in ("MPLCONFIGDIR", "XDG_CONFIG_HOME", "XDG_CACHE_HOME")}
    env.update(env_set)
    code = (f"import sys\n{before}from experiments.cli import main\nstatus = main(['--version'])\n"
            "import matplotlib.pyplot as plt\nplt.figure().savefig(sys.argv[1])\nprint('drawn')\nsys.exit(status)\n")
    run = subprocess.run([sys.executable, "-c", code, str(tmp_path / "f.png")], env=env,
                         cwd=Path(__file__).resolve().parents[1], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0 and run.stdout.endswith("\ndrawn\n"), run
    return run.stderr


def test_an_mplconfigdir_the_user_set_that_cannot_be_made_is_still_said(tmp_path: Path) -> None:
    """`HOME=/dev/null MPLCONFIGDIR=/dev/null/mine lmsbench compare ...`: matplotlib's warnings about a
    folder the user named were dropped with those about its own default (they are the user's to mend)."""
    err = _draw_with_home(tmp_path, {"HOME": "/dev/null", "MPLCONFIGDIR": "/dev/null/mine"})
    assert err.startswith("mkdir -p failed for path /dev/null/mine: [Errno 20] Not a directory: '/dev/null/mine'\n"), err
    assert "Matplotlib created a temporary cache directory at " in err
    assert "because there was an issue with MPLCONFIGDIR (/dev/null/mine)" in err


def test_main_adds_its_matplotlib_warning_filter_once() -> None:
    import logging

    from experiments.cli import _NoConfigFolderWarning, main

    main(["--version"])
    main(["--version"])
    assert sum(isinstance(f, _NoConfigFolderWarning) for f in logging.getLogger("matplotlib").filters) == 1


def test_a_read_only_home_that_has_its_matplotlib_folder_adds_no_lines(tmp_path: Path) -> None:
    """A read-only home that already holds ~/.config/matplotlib: matplotlib's third warning, "... is not a
    writable directory", was said alone (its other two were dropped). (Run as root, a read-only folder is
    writable: os.access says it is not, as it does for a user on a read-only home.)"""
    (tmp_path / "home" / ".config" / "matplotlib").mkdir(parents=True)
    folder = str((tmp_path / "home" / ".config" / "matplotlib").resolve())
    before = ("import os\n_access = os.access\n"
              f"os.access = lambda p, m, **k: False if str(p) == {folder!r} and m == os.W_OK else _access(p, m, **k)\n")
    assert _draw_with_home(tmp_path, {"HOME": str(tmp_path / "home")}, before) == ""
