"""A `lmsbench simulate --out DIR` run stopped or killed while writing its files (Ctrl-C, SIGKILL, a
crash, a power loss) left a cut scans.clf, or the earlier run's scans.clf / groundtruth.tum /
world.json beside its new config.yaml, and `slam DIR`, `info DIR/scans.clf`, `compare DIR`,
`sim2real DIR/scans.clf` read it as a finished, shorter run: exit 0, no warning (a review). The run
now writes each file whole (a hidden temporary file renamed into place) and leaves the hidden
.simulate-unfinished (options.SIMULATE_UNFINISHED) until all of them are; the readers refuse such a
folder, one line, exit 2; the next simulate into it takes it and leaves no temporary file."""

from __future__ import annotations

import json
import re
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from experiments.cli import main
from experiments.options import SIMULATE_OUTPUTS, SIMULATE_UNFINISHED

from test_out_folders import _stop_at_write

REPO = Path(__file__).resolve().parents[1]


def _unfinished(command: str, folder: Path, settings: bool = True) -> list[str]:
    """The refusal; ``settings``: the marker holds the run's settings (not one from before it did)."""
    rerun = (f"rerun it with lmsbench simulate --config {folder / SIMULATE_UNFINISHED} --out {folder} (that file holds "
             "its settings)" if settings else f"run lmsbench simulate --out {folder} again with the options the run was given")
    return [f"lmsbench {command}: error: {folder}: the lmsbench simulate run that wrote this folder did not finish "
            f"(it was stopped or killed while writing its files; {SIMULATE_UNFINISHED} is left), so its scans.clf may "
            f"be cut short or an earlier run's; {rerun}"]


def _readers_refuse(folder: Path, capsys, tmp_path: Path, settings: bool = True) -> None:
    """Every reader of a simulate folder refuses ``folder``, one line naming it, exit 2."""
    for argv, command in [(["slam", str(folder), "--quiet", "--out", str(tmp_path / "slam")], "slam"),
                          (["slam", str(folder / "scans.clf"), "--quiet", "--out", str(tmp_path / "slam")], "slam"),
                          (["info", str(folder / "scans.clf")], "info"),
                          (["info", str(folder)], "info"),
                          (["compare", str(folder), "--out", str(tmp_path / "cmp")], "compare"),
                          (["sim2real", str(folder / "scans.clf"), "--out", str(tmp_path / "s2r")], "sim2real"),
                          (["figures", "--log", str(folder / "scans.clf"), "--no-slam", "--duration", "1",
                            "--out", str(tmp_path / "fig")], "figures")]:
        assert main(argv) == 2, argv
        assert capsys.readouterr().err.splitlines() == _unfinished(command, folder, settings), argv
    assert not [p for p in tmp_path.iterdir() if p.name in ("slam", "cmp", "s2r", "fig")]  # refused before any output


def _taken_by_the_next_run(folder: Path, capsys) -> None:
    """The next simulate into ``folder`` takes it, leaves no hidden file, and its log reads."""
    assert main(["simulate", "--duration", "1", "--out", str(folder), "--quiet"]) == 0, capsys.readouterr().err
    assert sorted(p.name for p in folder.iterdir()) == sorted(SIMULATE_OUTPUTS)
    capsys.readouterr()
    assert main(["info", str(folder / "scans.clf"), "--json"]) == 0, capsys.readouterr().err


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 6])
def test_a_simulate_run_stopped_at_each_file_is_refused_by_the_readers(tmp_path, capsys, monkeypatch, n):
    """An earlier run (corridor, 2 s) in DIR, then a run (office, 1 s) stopped at its n-th file:
    before, the 5th stop (world.json) left the new scans.clf and groundtruth.tum beside the
    corridor's world.json, and `slam DIR` ran, exit 0, scoring the office's map against the
    corridor's walls; the 3rd left a cut (empty) scans.clf. The 1st is the marker itself, written
    whole: stopped there, nothing of the run is in DIR, and the corridor's files read as before."""
    folder = tmp_path / "sim"
    assert main(["simulate", "--world", "corridor", "--duration", "2", "--out", str(folder), "--quiet"]) == 0
    with monkeypatch.context() as m:
        _stop_at_write(m, folder, n)
        assert main(["simulate", "--duration", "1", "--out", str(folder), "--quiet"]) == 130
    assert capsys.readouterr().err.splitlines()[-1:] == ["lmsbench simulate: interrupted"]
    if n == 1:
        assert sorted(p.name for p in folder.iterdir()) == sorted(SIMULATE_OUTPUTS)
        assert main(["info", str(folder / "scans.clf"), "--json"]) == 0, capsys.readouterr().err
        assert json.loads(capsys.readouterr().out)["scans"] == 75  # the corridor's
        return
    _readers_refuse(folder, capsys, tmp_path)
    assert (folder / SIMULATE_UNFINISHED).is_file()
    _taken_by_the_next_run(folder, capsys)


@pytest.mark.parametrize("n", [2, 3, 5])
def test_the_refusal_names_the_command_that_reruns_the_run_that_did_not_finish(tmp_path, capsys, monkeypatch, n):
    """The refusal said "run lmsbench simulate --out DIR again", which runs the defaults (office,
    seed 0, 120 s), not the settings of the run that did not finish; `simulate --config
    DIR/config.yaml --out DIR` is refused (it would write over the file it reads), and config.yaml
    is the earlier run's when the run stopped before writing it (its 2nd file, the first after the
    marker). The marker now holds the run's settings and the refusal names `simulate --config
    DIR/.simulate-unfinished --out DIR`: run as named, it leaves the files a clean run of the same
    settings writes, byte for byte."""
    argv = ["--world", "office", "--seed", "3", "--duration", "1.5", "--rate-hz", "4", "--odometry", "--quiet"]
    folder = tmp_path / "sim"
    assert main(["simulate", "--world", "corridor", "--duration", "2", "--out", str(folder), "--quiet"]) == 0
    with monkeypatch.context() as m:
        _stop_at_write(m, folder, n)
        assert main(["simulate", *argv, "--out", str(folder)]) == 130
    capsys.readouterr()
    assert main(["info", str(folder)]) == 2
    refusal = capsys.readouterr().err.splitlines()
    assert refusal == _unfinished("info", folder)
    command = refusal[0].split("rerun it with lmsbench ")[1].split(" (that file")[0].split()
    assert command == ["simulate", "--config", str(folder / SIMULATE_UNFINISHED), "--out", str(folder)]
    assert main(command) == 0, capsys.readouterr().err
    assert main(["simulate", *argv, "--out", str(tmp_path / "clean")]) == 0
    assert sorted(p.name for p in folder.iterdir()) == sorted(SIMULATE_OUTPUTS)  # the marker gone, nothing hidden
    for name in SIMULATE_OUTPUTS:
        assert (folder / name).read_bytes() == (tmp_path / "clean" / name).read_bytes(), name


def test_a_killed_runs_temporary_files_are_removed_by_the_next_run(tmp_path, capsys):
    """What SIGKILL leaves mid-scans.clf: the marker and a cut hidden temporary log (no Python
    cleanup runs). A folder of nothing else is refused by its readers; the next simulate into it
    removes the temporary file (before, such files stayed for good: a cut log of up to GBs)."""
    folder = tmp_path / "sim"
    folder.mkdir()
    (folder / SIMULATE_UNFINISHED).write_text("lmsbench simulate is writing this folder\n")
    (folder / ".scans.clf.4242.tmp").write_text("# CARMEN log written by lmsbench\nROBOTLASER1 0 -1.5")
    (folder / ".config.yaml.4242.tmp").write_text("world: off")
    (folder / "..simulate-unfinished.4242.tmp").write_text("# lmsbench simulate is writing")  # a marker being written
    _readers_refuse(folder, capsys, tmp_path, settings=False)  # a marker from before it held the settings
    _taken_by_the_next_run(folder, capsys)


def test_the_next_run_keeps_a_users_own_hidden_files(tmp_path, capsys):
    """A review: the next simulate removed every .NAME.*.tmp, a user's .scans.clf.notes.tmp too;
    only the .NAME.PID.tmp a killed run leaves is removed."""
    folder = tmp_path / "sim"
    assert main(["simulate", "--duration", "1", "--out", str(folder), "--quiet"]) == 0
    mine = folder / ".scans.clf.notes.tmp"
    mine.write_text("my notes")
    (folder / ".map.png.77.tmp").write_text("cut")
    assert main(["simulate", "--duration", "1", "--out", str(folder), "--quiet"]) == 0
    assert mine.read_text() == "my notes" and not (folder / ".map.png.77.tmp").exists()


def test_a_finished_folder_and_one_from_before_the_marker_read(tmp_path, capsys):
    """A finished run leaves its five files and nothing hidden; a folder without the marker (every
    folder simulate wrote before it) reads as before."""
    folder = tmp_path / "sim"
    assert main(["simulate", "--duration", "1", "--out", str(folder), "--quiet"]) == 0
    assert sorted(p.name for p in folder.iterdir()) == sorted(SIMULATE_OUTPUTS)
    capsys.readouterr()
    assert main(["info", str(folder / "scans.clf"), "--json"]) == 0, capsys.readouterr().err
    assert main(["slam", str(folder), "--quiet", "--out", str(tmp_path / "slam")]) == 0, capsys.readouterr().err


def _env() -> dict:
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO / "tests"), str(REPO)])}


def _log_being_written(folder: Path) -> int:
    """The size of the log the run is writing (its temporary file, or scans.clf itself), 0 if none."""
    sizes = [p.stat().st_size for p in [*folder.glob(".scans.clf.*.tmp"), folder / "scans.clf"] if p.is_file()]
    return max(sizes, default=0)


@pytest.mark.slow
def test_simulate_killed_while_writing_its_log_is_refused_and_rerun(tmp_path, capsys):
    """A real SIGKILL of `lmsbench simulate --duration 60` once its log holds 256 KB (of about
    11 MB): before, the cut scans.clf stayed and `info` / `slam` read it, exit 0. Only the end state
    is asserted: whenever the kill lands in the write, the folder is refused by its readers."""
    folder = tmp_path / "sim"
    cmd = [sys.executable, "-m", "experiments.cli", "simulate", "--duration", "60", "--out", str(folder), "--quiet"]
    proc = subprocess.Popen(cmd, cwd=REPO, env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 600
        while _log_being_written(folder) < 256 * 1024:
            if proc.poll() is not None:
                pytest.fail(f"the run ended (exit {proc.returncode}) before its log was seen growing: "
                            f"{proc.communicate()[1]}")
            assert time.monotonic() < deadline, "no log written in 600 s"
            time.sleep(0.005)
        os.kill(proc.pid, signal.SIGKILL)
        proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == -signal.SIGKILL
    _readers_refuse(folder, capsys, tmp_path)
    assert (folder / SIMULATE_UNFINISHED).is_file() and not (folder / "scans.clf").exists()
    _taken_by_the_next_run(folder, capsys)


def test_the_sensor_yaml_of_an_unfinished_sim2real_folder_is_refused_by_its_readers(tmp_path, capsys):
    """sim2real stopped while writing left its tables beside no sensor.yaml, or an earlier run's, with no
    mark (round 7); now its .sim2real-unfinished (options.SIM2REAL_UNFINISHED) is left, and the readers of
    its sensor.yaml refuse it, one line, exit 2, before any output. The folder here is made by hand (the
    marker beside an earlier run's sensor.yaml); test_out_folders stops a real run at its figure."""
    from sim import SensorConfig

    from experiments.options import SIM2REAL_UNFINISHED
    from experiments.sweep.kinds import _read_sensor_files
    from experiments.sweep.spec import SweepSpecError

    s2r = tmp_path / "s2r"
    s2r.mkdir()
    SensorConfig().to_yaml(s2r / "sensor.yaml", header="sensor model used by lmsbench sim2real x.clf")
    (s2r / SIM2REAL_UNFINISHED).write_text("# lmsbench sim2real is writing this folder\n")
    said = (f"{s2r / 'sensor.yaml'}: the lmsbench sim2real run that wrote {s2r} did not finish (it was stopped or killed "
            f"while writing its files; {SIM2REAL_UNFINISHED} is left, holding its settings), so its sensor.yaml is an "
            f"earlier run's or of a run cut short; run that lmsbench sim2real --out {s2r} again")
    for argv in (["simulate", "--duration", "1", "--quiet"], ["compare", "office", "--duration", "1"]):
        out = tmp_path / argv[0]
        assert main([*argv, "--sensor", str(s2r / "sensor.yaml"), "--out", str(out)]) == 2
        assert capsys.readouterr().err.splitlines() == [f"lmsbench {argv[0]}: error: --sensor {said}"]
        assert not out.exists()
    with pytest.raises(SweepSpecError, match=f"^sensor_file: {re.escape(said)}$"):
        _read_sensor_files([{"sensor_file": str(s2r / "sensor.yaml")}])
    (s2r / SIM2REAL_UNFINISHED).unlink()  # a finished folder's sensor.yaml reads
    assert _read_sensor_files([{"sensor_file": str(s2r / "sensor.yaml")}])
