"""`lmsbench compare` given one input under two spellings (a simulate folder and its scans.clf, a
path and a link to it, a hard link) counted its scans twice, exit 0; it is refused before any
work, naming both spellings."""

from __future__ import annotations

import os

import pytest

from experiments.cli import main
from sim import simulate_records
from sim_folder import write_sim_folder


@pytest.fixture(scope="module")
def sim1(tmp_path_factory):
    folder = tmp_path_factory.mktemp("same") / "sim1"
    return write_sim_folder(folder, simulate_records("office", seed=0, duration=1.0, rate_hz=3.0), world_seed=0)


@pytest.mark.parametrize("second", ["scans.clf", "link", "hard.clf", "link.clf"])
def test_one_input_under_two_spellings_is_refused_before_any_work(sim1, tmp_path, capsys, second):
    first = str(sim1)
    if second == "scans.clf":
        other = str(sim1 / "scans.clf")
    elif second == "link":  # a link to the folder
        other = str(tmp_path / "link")
        os.symlink(sim1, other)
    elif second == "hard.clf":  # another name of the folder's scans.clf
        other = str(tmp_path / "hard.clf")
        os.link(sim1 / "scans.clf", other)
    else:  # a link to the folder's scans.clf, given first
        other = str(tmp_path / "link.clf")
        os.symlink(sim1 / "scans.clf", other)
        first, other = other, first
    out = tmp_path / "o"
    assert main(["compare", first, other, "--methods", "ransac", "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err == (f"lmsbench compare: error: {first} and {other} are the same input ({(sim1 / 'scans.clf').resolve()}), "
                   "given twice: each source once (the tables would count its scans twice)\n")
    assert not out.exists()


def test_two_inputs_of_one_content_are_two_sources(sim1, tmp_path, capsys):
    """A copy is another file (two runs may well be alike): compared as two sources."""
    copy = tmp_path / "copy.clf"
    copy.write_bytes((sim1 / "scans.clf").read_bytes())
    out = tmp_path / "o"
    assert main(["compare", str(sim1), str(copy), "--methods", "ransac", "--out", str(out), "--no-progress"]) == 0
    assert "copy.clf" in (out / "summary.txt").read_text() and "sim1" in (out / "summary.txt").read_text()


def test_a_simulate_folder_of_the_interlaced_sensor_is_said_to_charge_the_motion_to_the_extractors(sim1, tmp_path, capsys):
    """`lmsbench simulate` (interlaced LMS200 by default) then `lmsbench compare DIR` scored the moving
    scans against one pose's truth, silently: office seed 0, 30 s at 2 scans/s, sensor F1 0.933 against
    0.983 for `compare office:0` on the same tour. A world named as a source is not interlaced."""
    assert main(["compare", str(sim1), "office:0", "--duration", "1", "--methods", "split_merge",
                 "--out", str(tmp_path / "o"), "--no-progress"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert [line for line in err if "interlaced" in line] == [
        "lmsbench compare: warning: sim1: simulated with the interlaced LMS200 (simulate's default), each beam from "
        "the pose at its own time, but scored against the visible truth of the pose at the scan's stamp: the robot's "
        "motion within a scan (up to 1.2 deg, 1 cm) counts as the extractors' error (the sensor method's most); a "
        "world named as a source (office:0) is simulated without it, as is a simulate --sensor YAML with "
        "interlaced: false"]
    assert main(["compare", "office:0", "--duration", "1", "--methods", "split_merge", "--out", str(tmp_path / "w"),
                 "--no-progress"]) == 0
    assert "interlaced" not in capsys.readouterr().err
