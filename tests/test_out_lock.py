"""Two commands writing one --out at once: the second is refused before any work (one line, exit
2, naming the first), and a command killed with SIGKILL leaves the folder to the next run, which
resumes it. Before, two `simulate --out D` of seeds 1 and 2 interleaved their files: one said
"D/.scans.clf.N.tmp: no such file or directory" (each removed the other's temporary files as a
killed run's), the other "simulated ... (seed 1 ...) into D" over a folder of seed 2's files, exit 0."""

from __future__ import annotations

import contextlib
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Iterator

import pytest
import yaml

from experiments.cli import main

REPO = Path(__file__).resolve().parents[1]
KIND = f"{Path(__file__).stem}:held"


def held(params: dict) -> dict:
    """Marks its start in a file, then sleeps 120 s where $HOLD_THE_CELL is set (the process that
    holds the folder), else not at all."""
    Path(params["marks"], str(params["x"])).write_text("started")
    if os.environ.get("HOLD_THE_CELL"):
        time.sleep(120.0)
    return {"y": float(params["x"])}


def test_a_second_command_into_a_held_out_is_refused_and_a_killed_ones_folder_resumes(tmp_path, capsys):
    marks = tmp_path / "marks"
    marks.mkdir()
    spec = tmp_path / "held.yaml"
    spec.write_text(yaml.safe_dump({"name": "held", "kind": KIND, "fixed": {"marks": str(marks)}, "grid": {"x": [0]}}))
    out = tmp_path / "out"
    temp = tmp_path / "temp"  # the holder's temporary folder: nothing is left there (a lock file a run piled up)
    temp.mkdir()
    env = {**os.environ, "HOLD_THE_CELL": "1", "PYTHONPATH": os.pathsep.join([str(REPO / "tests"), str(REPO)]),
           "TMPDIR": str(temp)}
    proc = subprocess.Popen([sys.executable, "-m", "experiments.cli", "sweep", str(spec), "--inprocess", "--out",
                             str(out), "--no-progress"], cwd=REPO, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while not (marks / "0").exists():  # the first run is in its cell: its sweep.yaml is written
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
            time.sleep(0.05)
        assert main(["sweep", str(spec), "--inprocess", "--out", str(out), "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert re.fullmatch(rf"lmsbench sweep: error: --out {re.escape(str(out))}: another lmsbench command "
                            rf"\(pid {proc.pid}\) is writing there; wait for it to end, or give another "
                            r"path\n", err), err
        assert not (out / "results.parquet").exists()  # nothing of the second run's
        proc.send_signal(signal.SIGKILL)  # killed: its lock ends with its process
        proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert main(["sweep", str(spec), "--inprocess", "--out", str(out), "--no-progress"]) == 0
    captured = capsys.readouterr()
    assert "held: 1 cells, 1 computed, 0 already done, 0 failed" in captured.out, captured
    assert sorted(p.name for p in out.iterdir()) == ["cells", "results.csv", "results.parquet", "sweep.yaml",
                                                     "versions.yaml"]  # no lock file in the output
    assert list(temp.iterdir()) == []


@contextlib.contextmanager
def file_held_by_another_process(target: Path) -> Iterator[int]:
    """Another process holding the output file ``target`` (``check_out_file``) while the block runs; yields its pid."""
    code = ("import sys, time\nfrom pathlib import Path\nfrom experiments.options import check_out_file, holding_outputs\n"
            "holding_outputs()\ncheck_out_file(Path(sys.argv[1]))\nprint('held', flush=True)\ntime.sleep(60)\n")
    proc = subprocess.Popen([sys.executable, "-c", code, str(target)], cwd=REPO, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None and proc.stdout.readline() == "held\n", proc.communicate()
        yield proc.pid
    finally:
        proc.kill()
        proc.communicate()


def test_an_output_file_held_by_another_command_is_refused(tmp_path, capsys):
    """`lms200 record --out F` and `calibrate --out F` take their file as a folder is taken: two
    recordings into one file interleaved their lines."""
    target = tmp_path / "scans.clf"
    with file_held_by_another_process(target) as pid:
        assert main(["lms200", "record", "--port", "socket://127.0.0.1:9", "--out", str(target)]) == 2
        err = capsys.readouterr().err
        assert err == (f"lmsbench lms200 record: error: --out {target}: another lmsbench command (pid {pid}) "
                       "is writing there; wait for it to end, or give another path\n")
        assert not target.exists()
        assert sorted(p.name for p in tmp_path.iterdir()) == [".scans.clf.lmsbench-lock"]  # the holder's, beside it


def test_an_output_file_of_a_name_near_255_bytes_is_still_guarded(tmp_path, capsys):
    """An output file named near the file system's longest name (255 bytes): its lock's name,
    ``.NAME.lmsbench-lock``, was too long (ENAMETOOLONG), so both runs went on unguarded (the second
    run got to opening its port: "cannot open socket://127.0.0.1:9 ..."). The lock's name is cut and
    carries a hash of the whole name then, so the second run is refused as for any other name."""
    import hashlib

    name = "r" * 250 + ".clf"  # 254 bytes: a name the file system takes
    target = tmp_path / name
    with file_held_by_another_process(target) as pid:
        assert main(["lms200", "record", "--port", "socket://127.0.0.1:9", "--out", str(target)]) == 2
        err = capsys.readouterr().err
        assert err == (f"lmsbench lms200 record: error: --out {target}: another lmsbench command (pid {pid}) "
                       "is writing there; wait for it to end, or give another path\n")
        lock = "." + "r" * (255 - 2 - 16 - len(".lmsbench-lock")) + "." + hashlib.sha256(name.encode()).hexdigest()[:16] \
            + ".lmsbench-lock"
        assert len(lock) == 255 and [p.name for p in tmp_path.iterdir()] == [lock]


def test_a_stale_lock_file_beside_an_output_file_is_taken_and_removed(tmp_path, capsys):
    """A killed run's hidden lock file holds no lock: the next run takes it and removes it as it ends."""
    target = tmp_path / "scans.clf"
    (tmp_path / ".scans.clf.lmsbench-lock").write_text("")
    assert main(["lms200", "record", "--port", str(tmp_path), "--out", str(target)]) == 2
    assert capsys.readouterr().err == f"lmsbench lms200 record: error: cannot open {tmp_path}: Is a directory\n"
    assert list(tmp_path.iterdir()) == []


HOLD = ("import sys, time\nfrom experiments.options import check_out, holding_outputs\n"
        "holding_outputs()\ncheck_out(sys.argv[1])\nprint('held', flush=True)\ntime.sleep(60)\n")


def test_a_folder_held_by_a_command_of_another_tmpdir_is_refused(tmp_path, capsys, monkeypatch):
    """The lock was a file in the temporary folder: two commands of different $TMPDIR (a SLURM job's,
    pam_tmpdir's) both wrote one --out, exit 0, the folder one seed's files, the other run saying
    it simulated into it."""
    out, first, second = tmp_path / "simE", tmp_path / "t1", tmp_path / "t2"
    first.mkdir()
    second.mkdir()
    proc = subprocess.Popen([sys.executable, "-c", HOLD, str(out)], cwd=REPO, env={**os.environ, "TMPDIR": str(first)},
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None and proc.stdout.readline() == "held\n", proc.communicate()
        monkeypatch.setattr(tempfile, "tempdir", str(second))
        assert main(["simulate", "--out", str(out), "--duration", "3", "--seed", "2"]) == 2
        assert capsys.readouterr().err == (f"lmsbench simulate: error: --out {out}: another lmsbench command "
                                           f"(pid {proc.pid}) is writing there; wait for it to end, or give another "
                                           "path\n")
        assert list(out.iterdir()) == [] and list(first.iterdir()) == [] and list(second.iterdir()) == []
    finally:
        proc.kill()
        proc.communicate()


def test_a_file_system_that_takes_no_byte_still_locks_and_a_refused_run_leaves_no_folder(tmp_path):
    """RLIMIT_FSIZE=0 (as a full disk, ENOSPC/EDQUOT): writing the holder's name into the lock file
    failed every --out command with "[Errno 27] File too large". The lock writes nothing now; a
    folder check_out made for its lock, still empty as the command ends, is removed."""
    import resource

    code = ("import sys\nfrom experiments.options import check_out, check_out_file, holding_outputs, release_outputs\n"
            "holding_outputs()\ntry:\n    check_out(sys.argv[1]); check_out_file(sys.argv[2])\n"
            "    print('held', flush=True)\n    sys.stdin.readline()\nfinally:\n    release_outputs()\n")
    out, target = tmp_path / "new" / "simE", tmp_path / "scans.clf"

    def no_bytes() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (0, resource.RLIM_INFINITY))

    proc = subprocess.Popen([sys.executable, "-c", code, str(out), str(target)], cwd=REPO, preexec_fn=no_bytes,
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None and proc.stdout.readline() == "held\n", proc.communicate()
        for path, args in ((out, [out, tmp_path / "other.clf"]), (target, [tmp_path / "other", target])):
            refused = subprocess.run([sys.executable, "-c", code, *map(str, args)], cwd=REPO, stdin=subprocess.DEVNULL,
                                     capture_output=True, text=True, timeout=60)  # held, so another is refused
            assert refused.returncode == 1 and refused.stderr.endswith(
                f"InputError: --out {path}: another lmsbench command (pid {proc.pid}) is writing there; wait for it "
                "to end, or give another path\n"), refused.stderr
        stdout, stderr = proc.communicate("\n", timeout=60)
        assert proc.returncode == 0, stderr
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert list(tmp_path.iterdir()) == []  # the folders it made, empty, and the lock file: gone


def test_without_a_lock_to_be_had_the_command_goes_on(tmp_path, capsys, monkeypatch):
    """A file system without locks (ENOLCK; NFS refuses a folder's, EBADF): the command runs
    unguarded, as before the lock, instead of refusing every --out."""
    import errno
    import fcntl

    def no_locks(fd: int, how: int) -> None:
        raise OSError(errno.ENOLCK, os.strerror(errno.ENOLCK))

    monkeypatch.setattr(fcntl, "flock", no_locks)
    target = tmp_path / "scans.clf"
    assert main(["lms200", "record", "--port", str(tmp_path), "--out", str(target)]) == 2
    assert capsys.readouterr().err == f"lmsbench lms200 record: error: cannot open {tmp_path}: Is a directory\n"
    assert list(tmp_path.iterdir()) == []


def test_a_command_on_another_thread_keeps_its_hold(tmp_path):
    """The holding was the process's: a second command starting on another thread released the
    first's locks (its holding_outputs began with a release of all)."""
    import threading

    from experiments.options import InputError, check_out, holding_outputs, release_outputs

    out = tmp_path / "out"
    held, done = threading.Event(), threading.Event()

    def first() -> None:
        holding_outputs()
        check_out(out)
        held.set()
        done.wait(30)
        release_outputs()

    thread = threading.Thread(target=first)
    thread.start()
    try:
        assert held.wait(30)
        holding_outputs()
        try:
            with pytest.raises(InputError) as refused:
                check_out(out)
        finally:
            release_outputs()
        assert str(refused.value) == (f"--out {out}: another lmsbench command (pid {os.getpid()}) is writing there; "
                                      "wait for it to end, or give another path")
    finally:
        done.set()
        thread.join(30)
    assert not out.exists()  # made for the lock, left empty: removed as the first ended


def test_files_written_whole_under_a_name_near_255_bytes_get_a_short_temporary_name(tmp_path):
    """An output named near the file system's longest name (255 bytes): the hidden temporary file it
    is written through (``.NAME.PID.tmp``, ``.NAME.XXXXXXXX.tmp.gz``) had a name too long to make, so
    `calibrate --out NAME.yaml` failed after its work ("....yaml.29521.tmp: file name too long") and
    ``write_log`` raised OSError. The temporary name is shortened as the lock's is; a killed run's
    leftover of that name is still found."""
    from experiments.provenance import leftover_temporaries, write_record
    from lms200 import Record, Scan, read_log, write_log

    out = tmp_path / ("c" * 250 + ".yaml")  # 255 bytes
    write_record(out, "a: 1\n")
    assert out.read_text() == "a: 1\n" and [p.name for p in tmp_path.iterdir()] == [out.name]
    seen = []
    write_record(out, lambda tmp: seen.append(tmp.name) or tmp.write_text("a: 2\n"))
    assert out.read_text() == "a: 2\n" and len(seen[0].encode()) <= 255 and seen[0].startswith(".ccc")
    left = tmp_path / seen[0].replace(f".{os.getpid()}.tmp", ".4194303.tmp")  # as a killed run leaves it
    left.write_text("cut")
    assert leftover_temporaries(out) == [left]

    log = tmp_path / ("d" * 245 + ".clf.gz")  # 252 bytes
    assert write_log(log, [Record(Scan.lms200([1.0] * 361, stamp=float(i))) for i in range(3)]) == 3
    assert [r.scan.stamp for r in read_log(log)] == [0.0, 1.0, 2.0]


def test_the_library_refuses_a_name_longer_than_255_bytes_as_an_input_error(tmp_path):
    """read_log, write_log, read_tum and write_tum of a path whose name passes 255 bytes raised a raw
    OSError ("[Errno 36] File name too long") from their first look at it: an InputError naming the
    argument now, as for any other bad path."""
    from lms200 import Record, Scan, read_log, read_tum, write_log, write_tum
    from lms200.errors import InputError

    name = "x" * 300
    calls = [lambda: read_log(tmp_path / f"{name}.clf"), lambda: read_tum(tmp_path / f"{name}.tum"),
             lambda: write_log(tmp_path / f"{name}.bag", [Record(Scan.lms200([1.0] * 361))]),
             lambda: write_tum(tmp_path / name / "t.tum", [0.0], [[0.0, 0.0, 0.0]])]
    for call in calls:
        with pytest.raises(InputError, match=r"^path: a name of 30\d bytes \(x{40}\.\.\.\), longer than a file system "
                                             r"takes \(255\); give a shorter one$"):
            call()
    assert list(tmp_path.iterdir()) == []


def test_a_shortened_hidden_name_is_not_cut_within_a_utf8_character(tmp_path):
    """``hidden_stem`` cut a long name's bytes where the count fell: within a two-byte character
    (``é``), which left a lone 0xC3 byte in the lock's and temporary file's names (a name no UTF-8
    reader takes; a killed run leaves it behind). It stops at the character before."""
    from experiments.options import lock_file
    from lms200.logs import hidden_stem

    out = tmp_path / ("é" * 125 + ".yaml")  # 255 bytes
    stem = hidden_stem(out, len(".lmsbench-lock"))
    stem.encode("utf-8")  # no lone surrogate escape
    assert stem.startswith(".éé") and len(os.fsencode(stem)) + len(".lmsbench-lock") <= 255
    name = lock_file(out).name
    name.encode("utf-8")
    assert name.endswith(".lmsbench-lock") and len(os.fsencode(name)) <= 255
    for odd in range(1, 3):  # either parity of the cut
        hidden_stem(tmp_path / ("x" * odd + "é" * 125), 14).encode("utf-8")
