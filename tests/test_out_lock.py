"""Two commands writing one --out at once: the second is refused before any work (one line, exit
2, naming the first), and a command killed with SIGKILL leaves the folder to the next run, which
resumes it. Before, two `simulate --out D` of seeds 1 and 2 interleaved their files: one said
"D/.scans.clf.N.tmp: no such file or directory" (each removed the other's temporary files as a
killed run's), the other "simulated ... (seed 1 ...) into D" over a folder of seed 2's files, exit 0."""

from __future__ import annotations

import hashlib
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

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
    env = {**os.environ, "HOLD_THE_CELL": "1", "PYTHONPATH": os.pathsep.join([str(REPO / "tests"), str(REPO)])}
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
                            rf"\(pid {proc.pid}, lmsbench sweep\) is writing there; wait for it to end, or give another "
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
    # the killed run's lock file, taken by this run, is removed as it ends (none piles up in the temporary folder)
    name = hashlib.sha256(os.path.realpath(out).encode()).hexdigest()[:40] + ".lock"
    assert not (Path(tempfile.gettempdir()) / f"lmsbench-{os.getuid()}-outputs" / name).exists()


def test_an_output_file_held_by_another_command_is_refused(tmp_path, capsys):
    """`lms200 record --out F` and `calibrate --out F` take their file as a folder is taken: two
    recordings into one file interleaved their lines."""
    target = tmp_path / "scans.clf"
    code = ("import sys, time\nfrom pathlib import Path\nfrom experiments.options import check_out_file, holding_outputs\n"
            "holding_outputs('lms200 record')\ncheck_out_file(Path(sys.argv[1]))\nprint('held', flush=True)\ntime.sleep(60)\n")
    proc = subprocess.Popen([sys.executable, "-c", code, str(target)], cwd=REPO, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None and proc.stdout.readline() == "held\n", proc.communicate()
        assert main(["lms200", "record", "--port", "socket://127.0.0.1:9", "--out", str(target)]) == 2
        err = capsys.readouterr().err
        assert err == (f"lmsbench lms200 record: error: --out {target}: another lmsbench command (pid {proc.pid}, "
                       "lmsbench lms200 record) is writing there; wait for it to end, or give another path\n")
        assert not target.exists()
    finally:
        proc.kill()
        proc.communicate()


def test_without_a_lock_to_be_had_the_command_goes_on(tmp_path, capsys, monkeypatch):
    """The locks' folder not the user's (a file of its name here, or another user's folder, a link):
    the command runs unguarded, as before the lock, instead of refusing every --out."""
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    (tmp_path / f"lmsbench-{os.getuid()}-outputs").write_text("not a folder")
    target = tmp_path / "scans.clf"
    assert main(["lms200", "record", "--port", str(tmp_path), "--out", str(target)]) == 2
    assert capsys.readouterr().err == f"lmsbench lms200 record: error: cannot open {tmp_path}: Is a directory\n"
