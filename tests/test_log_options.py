"""--topic, --skip-bad-lines and the geometry flags on every command that reads a log, and the
real-data columns of `lmsbench compare LOG`."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from experiments.cli import build_parser, main
from lms200 import LmsbenchError
from lms200.bag import BagError
from test_log_readers import _two_topic_bag, flaser, write

COMMANDS = [["info", "x.log"], ["compare", "x.log"], ["slam", "x.log", "--out", "o"],
            ["lms200", "emulate", "--log", "x.log"], ["figures"], ["demo", "--log", "x.log"]]


@pytest.mark.parametrize("words", COMMANDS, ids=lambda w: " ".join(w[:2]))
def test_every_log_command_takes_the_log_options(words: list[str]) -> None:
    args = build_parser().parse_args(words + ["--topic", "/scan_rear", "--skip-bad-lines",
                                              "--laser-resolution-deg", "0.5"])
    from experiments.logargs import read_log_options

    options = read_log_options(args)
    assert options["topic"] == "/scan_rear" and options["skip_bad_lines"] is True
    assert options["geometry"].resolution == pytest.approx(np.deg2rad(0.5))


def test_slam_and_emulate_and_figures_read_the_chosen_topic(tmp_path: Path) -> None:
    from experiments.figures.study import _intel_panels
    from experiments.lms200_sources import log_scans
    from experiments.slamrun import load_input

    bag = tmp_path / "two.bag"
    _two_topic_bag(bag)
    with pytest.raises(BagError, match="choose one"):
        load_input(bag)
    data = load_input(bag, read_options={"topic": "/scan_rear"})
    assert len(data.records) == 4 and len(data.records[0].scan) == 361
    assert [len(s) for s in log_scans(bag, loop=False, read_options={"topic": "/scan_front"})] == [181] * 4
    panels = _intel_panels(bag, 2, "split_merge", None, {"topic": "/scan_front", "geometry": None})
    assert set(panels) == {"intel_points", "intel_lines", "intel_corners"}


def test_compare_on_a_log_with_bad_lines_and_two_lasers(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    rng = np.random.default_rng(0)
    lines = [flaser(181, value=float(v), stamp=float(t)) for t, v in enumerate(rng.uniform(2, 4, 12).round(2))]
    lines[3] = lines[3].replace("FLASER 181", "FLASER inf", 1)
    lines.insert(5, flaser(361, kind="RLASER"))
    path = write(tmp_path, "corridor-corrected.log", lines)
    out = tmp_path / "cmp"
    argv = ["compare", str(path), "--methods", "split_merge", "iepf", "--no-progress", "--out", str(out)]
    assert main(argv) == 2
    assert f"{path}:4: malformed FLASER line" in capsys.readouterr().err
    assert main(argv + ["--skip-bad-lines", "--sigma", "0.01"]) == 0
    captured = capsys.readouterr()
    assert "skipped 1 bad line\n" in captured.err and "realdata_corridor-corrected_log.png" in captured.out
    summary = pd.read_csv(out / "summary.csv")
    assert set(summary["method"]) == {"split_merge", "iepf"} and (summary["scans"] == 11).all()
    for col in ("explained_3cm", "explained_3sigma", "ray_rmse_mm", "lines_per_scan", "mean_segment_m",
                "repeatability", "us_median", "sigma_r_mm"):
        assert col in summary, col
    assert (summary["sigma_r_mm"] == 10.0).all()  # --sigma given: not estimated
    assert main(argv[:-2] + ["--skip-bad-lines", "--topic", "RLASER", "--out", str(tmp_path / "rear")]) == 0
    assert (pd.read_csv(tmp_path / "rear" / "summary.csv")["scans"] == 1).all()


@pytest.mark.shared_data
def test_compare_real_log_measures(shared_data: Path) -> None:
    from experiments.compare import compare, log_source, summarise

    src = log_source(shared_data / "intel-corrected.log.gz", stride=1)
    table = compare([src], ["split_merge"], max_scans=40)
    s = summarise(table).iloc[0]
    assert 0.003 < s["sigma_r_mm"] / 1e3 < 0.006  # 1 cm codes and ~4-5 mm noise (lms200.noise)
    assert 0.5 < s["explained_3cm"] <= 1.0 and s["explained_3sigma"] <= s["explained_3cm"]
    assert 0.0 < s["ray_rmse_mm"] < 30.0 and 0.5 < s["repeatability"] <= 1.0
    assert table["repeat_in_view"].iloc[1:].notna().all() and np.isnan(table["repeat_in_view"].iloc[0])
    raw = log_source(shared_data / "mit-csail.clf.gz", stride=10)  # raw odometry: no repeatability
    t2 = compare([raw], ["split_merge"], max_scans=5)
    assert t2["repeat_in_view"].isna().all()
    with pytest.raises(LmsbenchError, match="sigma"):
        compare([log_source(shared_data / "aces-corrected.log.gz")], ["iepf"], sigma=-1.0, max_scans=1)


def _intel_with_bad_lines(shared_data: Path, tmp_path: Path, n: int = 40) -> Path:
    import gzip

    with gzip.open(shared_data / "intel-corrected.log.gz", "rt") as f:
        lines = [line.rstrip("\n") for line in f if line.startswith("FLASER")][:n]
    lines[5] = lines[5][:100]  # cut short
    lines[9] = "FLASER 180 garbage"
    return write(tmp_path, "bad.log", lines)


def test_calibrate_sim2real_and_emulate_report_the_lines_they_skip(shared_data: Path, tmp_path: Path,
                                                                   capsys: pytest.CaptureFixture,
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    """--skip-bad-lines is "reported on stderr" (its help) and info, compare, slam and figures did;
    calibrate, sim2real and lms200 emulate --log skipped the lines silently."""
    from sim import SensorConfig

    from experiments import sim2real as s2r
    from experiments.calibrate import calibrate_log
    from experiments.lms200_sources import log_scans

    path = _intel_with_bad_lines(shared_data, tmp_path)
    said = (f"{path}: skipped 2 bad lines\n  {path}:6: FLASER: FLASER with 180 beams needs 191 fields, got 21\n"
            f"  {path}:10: FLASER: FLASER with 180 beams needs 191 fields, got 3\n")
    assert len(list(log_scans(path, loop=False, read_options={"skip_bad_lines": True}))) == 38
    assert capsys.readouterr().err == said
    calibrate_log(path, skip_bad_lines=True, fit_duration=2.0)
    assert capsys.readouterr().err == said
    calibrate_log(path, skip_bad_lines=True, fit_duration=2.0, report_skips=False)
    assert capsys.readouterr().err == ""

    class Read(Exception):
        pass

    def stop(*args, **kwargs):
        raise Read

    monkeypatch.setattr(s2r, "odometry_limits_and_source", stop)  # after the log's pass
    with pytest.raises(Read):
        s2r.sim2real(path, world="office", stride=1, max_scans=None, sensor=SensorConfig(), read_options={"skip_bad_lines": True})
    assert capsys.readouterr().err == said
