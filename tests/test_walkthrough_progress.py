"""Long steps that ran silent on a terminal (a researcher's walkthrough, 2026-12-05): slam's
baselines after its own bar had gone, the SLAM kernels a slam sweep compiled in its workers,
each area of bench, the figures being drawn. On a terminal each now says what it starts and
beats while it runs; off a terminal stderr keeps to warnings and errors."""

from __future__ import annotations

import io
import json
import re
import sys
import time
import types
from pathlib import Path

import numpy as np
import pytest

from lms200 import write_log, write_tum


class Terminal(io.StringIO):
    """A stderr that says it is a terminal (the progress bars and heartbeats speak only there)."""

    def isatty(self) -> bool:
        return True


@pytest.fixture(scope="module")
def odometry_folder(tmp_path_factory) -> Path:
    """A 3 s office run with wheel odometry, laid out as `lmsbench simulate` writes it: slam runs
    both its baselines on it (the paper preset, and the paper preset driven by the odometry)."""
    from sim import make_world, simulate_records
    from sim.records import OdometryConfig

    out = tmp_path_factory.mktemp("odo")
    records = simulate_records("office", seed=1, duration=3.0, odometry=OdometryConfig())
    write_log(out / "scans.clf", records)
    truth = np.array([(r.scan.stamp, *r.truth) for r in records])
    write_tum(out / "groundtruth.tum", truth[:, 0], truth[:, 1:])
    make_world("office", seed=1).to_json(out / "world.json")
    return out


def test_slam_announces_each_baseline_with_a_bar_on_a_terminal(odometry_folder, tmp_path, monkeypatch, capsys):
    """`lmsbench slam LOG` showed a bar for the run's own SLAM, which went (leave=False), and then
    nothing while the baselines ran (MIT CSAIL: 78.6 s at load 3-4); its summary, "1988 scans in
    6.2 s of wall-clock time", read as the command's time. Each baseline is now announced with a
    bar of its own, and the summary names the run's own time and gives the whole command's."""
    from experiments.cli import main

    tty = Terminal()
    monkeypatch.setattr(sys, "stderr", tty)
    t0 = time.perf_counter()
    assert main(["slam", str(odometry_folder), "--out", str(tmp_path / "o")]) == 0
    took = time.perf_counter() - t0
    err, out = tty.getvalue(), capsys.readouterr().out
    n = json.loads((tmp_path / "o" / "metrics.json").read_text())["n_scans"]
    paper = (f"slam: baseline: the paper preset (EKF) over the same {n} scans, for the comparison table "
             "(--no-paper-baseline leaves it out) ...")
    odometry = (f"slam: baseline: the paper preset driven by the input's odometry over the same {n} scans, for the "
                "comparison table (--no-odometry-baseline leaves it out) ...")
    assert paper in err and odometry in err
    assert err.index(paper) < err.index(odometry)
    assert "paper preset: " in err[err.index(paper):err.index(odometry)]  # the bar, after its announcement
    assert "paper preset (odometry): " in err[err.index(odometry):]
    m = json.loads((tmp_path / "o" / "metrics.json").read_text())
    first = re.search(rf"{n} scans in ([0-9.]+) s of wall-clock time \([0-9]+ scans/s of CPU time\) for this run's "
                      "own SLAM, [0-9]+ map lines; outputs in ", out)
    assert first and float(first.group(1)) == round(m["seconds"], 1)
    seconds = {row["source"]: row.get("seconds") for row in m["table"]}
    assert seconds["slam"] == m["seconds"] and seconds["raw odometry"] is None
    assert seconds["paper preset"] > 0 and seconds["paper preset (odometry)"] > 0
    total = re.search(r"  the whole command took ([0-9.]+) s of wall-clock time \(this run's SLAM ([0-9.]+) s; the "
                      r"baselines' paper preset ([0-9.]+) s, paper preset \(odometry\) ([0-9.]+) s; the rest reading "
                      r"the input, compiling or loading kernels, scoring and writing the outputs\)\n", out)
    assert total, out
    whole, own, base1, base2 = (float(g) for g in total.groups())
    assert (own, base1, base2) == tuple(round(v, 1) for v in (m["seconds"], seconds["paper preset"],
                                                                seconds["paper preset (odometry)"]))
    assert own + base1 + base2 - 0.15 <= whole <= took + 0.05


def test_slam_says_nothing_of_its_baselines_off_a_terminal_or_with_quiet(odometry_folder, tmp_path, monkeypatch,
                                                                         capsys):
    from experiments.cli import main

    assert main(["slam", str(odometry_folder), "--out", str(tmp_path / "a")]) == 0
    assert "baseline" not in capsys.readouterr().err  # stderr is no terminal here
    tty = Terminal()
    monkeypatch.setattr(sys, "stderr", tty)
    assert main(["slam", str(odometry_folder), "--out", str(tmp_path / "b"), "--quiet"]) == 0
    assert tty.getvalue() == ""


def test_a_slam_sweep_compiles_the_slam_kernels_before_its_workers(tmp_path, monkeypatch):
    """The first cell of `sweep sweeps/slam_vs_noise.yaml` took 36 s compiling the SLAM kernels in
    the workers, with no "compiling kernels" note: the command warmed up the extractors' kernels
    only. A slam sweep now warms up the SLAM's too (which says "compiling kernels, once" when it
    compiles), an extract sweep the extractors' alone."""
    import experiments.progress
    import experiments.sweep
    from experiments.cli import main

    calls: list[dict] = []

    def stop(*args, **kwargs):
        raise RuntimeError("stopped before any cell")

    monkeypatch.setattr(experiments.progress, "warm_up_kernels", lambda **kw: calls.append(kw) or 0.0)
    monkeypatch.setattr(experiments.sweep, "run_sweep", stop)
    repo = Path(__file__).resolve().parents[1]
    for sweep, slam in (("slam_vs_noise.yaml", True), ("k_vs_noise.yaml", False)):
        # the sweep stops there: an internal error, exit 1
        assert main(["sweep", str(repo / "sweeps" / sweep), "--inprocess", "--out", str(tmp_path / sweep)]) == 1
        assert calls.pop() == {"slam": slam}
