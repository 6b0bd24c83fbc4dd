"""`compare` on synthetic rooms with exact truth, `summarise` on a hand-built table, and the CLI."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from experiments.compare import Source, compare, summarise
from experiments.synthetic import L_ROOM, room_scan
from lms200 import Record, write_log

ROOT = Path(__file__).resolve().parents[1]
BASELINES = ["split_merge", "iepf", "hough", "ransac"]
POSES = [(0.0, 0.0, 0.3), (1.0, -1.0, -0.4), (3.5, -1.5, 1.9)]


def room_source(sigma: float = 0.005) -> Source:
    records, truths = [], {}
    for k, pose in enumerate(POSES):
        scan, truth = room_scan(L_ROOM, pose, sigma=sigma, seed=k)
        scan = scan.replace(stamp=float(k))
        records.append(Record(scan, None, pose))
        truths[float(k)] = truth
    return Source("lroom", "sim", 7, records, lambda rec: truths[rec.scan.stamp], len(records))


def test_compare_table_rows_and_scores():
    table = compare([room_source()], BASELINES)
    assert len(table) == len(BASELINES) * len(POSES)
    assert set(table["method"]) == set(BASELINES)
    assert (table["seed"] == 7).all() and sorted(table["scan"].unique()) == [0, 1, 2]
    assert (table["microseconds"] > 0).all() and (table["cpu_microseconds"] > 0).all()
    # exact room, 5 mm noise: every wall of every scan found, nothing else
    assert (table["f1"] == 1.0).all() and (table["fp"] == 0).all()
    assert (table["tp"] == table["n_truth"]).all()
    assert (table["rho_err_rms"] < 0.005).all()
    assert (table["corner_fn"] == 0).all()
    assert (table["explained"] > 0.9).all()
    s = summarise(table)
    assert set(s["method"]) == set(BASELINES) and (s["f1"] == 1.0).all()
    assert s["speed_vs_sensor"].isna().all()  # no sensor method in this run
    assert (s["cpu_us_median"] > 0).all() and s["cpu_speed_vs_sensor"].isna().all()
    # every summary column is documented: in docs/baselines.md's paragraph on summary.csv or docs/realdata.md's
    # table of its real-data columns (source, method, kind and backend were in neither)
    import re

    said = (ROOT / "docs" / "baselines.md").read_text()
    said = said[said.index("`summary.csv` / `summary.txt` (per source"):]
    said = said[:said.index("and `config.yaml`")]
    realdata = (ROOT / "docs" / "realdata.md").read_text()
    said += realdata[realdata.index("| column | meaning |"):realdata.index("The ray residual of a beam")]
    names = set(re.findall(r"`([a-z0-9_]+)`", said))
    assert not set(s.columns) - names, sorted(set(s.columns) - names)


def test_methods_run_interleaved_in_rotating_order():
    table = compare([room_source()], BASELINES)
    firsts = [table[table["scan"] == k]["method"].iloc[0] for k in range(len(POSES))]
    assert firsts == BASELINES[: len(POSES)]


def test_summarise_pools_counts_and_errors():
    rows = []
    for method, us, tp, fp, fn, rho_mean, rho_rms in [
        ("sensor", 100.0, 3, 0, 1, 0.001, 0.002), ("sensor", 300.0, 1, 1, 0, 0.005, 0.005),
        ("hough", 800.0, 2, 2, 2, 0.0, 0.004), ("hough", 800.0, 0, 0, 2, np.nan, np.nan),
    ]:
        rows.append(dict(method=method, source="w", kind="sim", seed=0, scan=0, n_lines=tp + fp,
                         microseconds=us, explained=0.9, range_rms=0.004, tp=tp, fp=fp, fn=fn,
                         rho_err_mean=rho_mean, rho_err_rms=rho_rms, alpha_err_mean=0.0, alpha_err_rms=0.0,
                         endpoint_err_mean=0.01, corner_tp=1, corner_fp=0, corner_fn=1, corner_err_mean=0.02))
    s = summarise(pd.DataFrame(rows)).set_index("method")
    assert s.loc["sensor", "f1"] == pytest.approx(2 * 4 / (2 * 4 + 1 + 1))
    assert s.loc["sensor", "rho_bias_mm"] == pytest.approx((3 * 1 + 1 * 5) / 4)
    assert s.loc["sensor", "rho_rms_mm"] == pytest.approx(np.sqrt((3 * 4 + 1 * 25) / 4))
    assert s.loc["hough", "f1"] == pytest.approx(4 / (4 + 2 + 4))
    assert s.loc["hough", "speed_vs_sensor"] == pytest.approx(200.0 / 800.0)
    assert s.loc["sensor", "speed_vs_sensor"] == 1.0
    assert s.loc["hough", "scans_per_s"] == pytest.approx(1250.0)
    assert s.loc["sensor", "corner_recall"] == 0.5


def _cli(*args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", "experiments.cli", "compare", *args],
                          capture_output=True, text=True, env=env, cwd=ROOT, timeout=120)


@pytest.mark.slow
def test_cli_on_a_log_writes_table_summary_and_config(tmp_path, capsys):
    """In this process (the command's subprocess path, its status and stderr, is test_cli_errors_are_one_line's):
    an interpreter start and numba's loading of both methods' kernels less."""
    from experiments.cli import main

    log = tmp_path / "room.log"
    write_log(log, [Record(room_scan(L_ROOM, p, sigma=0.005, seed=k)[0].replace(stamp=float(k)))
                    for k, p in enumerate(POSES)])
    out = tmp_path / "out"
    code = main(["compare", str(log), "--methods", "split_merge", "hough", "--format", "csv", "--out", str(out),
                 "--no-progress", "--set", "extractor.hough.rho_step=0.01"])
    res = capsys.readouterr()
    assert code == 0, res.err
    table = pd.read_csv(out / "compare.csv")
    assert len(table) == 2 * len(POSES)
    assert (table["explained"] > 0.9).all()  # mm-mode log of 5 mm noise: 3 sigma explains ~99%
    summary = pd.read_csv(out / "summary.csv")
    assert list(summary["method"]) == ["split_merge", "hough"]
    assert "split_merge" in res.out and (out / "summary.txt").exists()
    assert "rho_step: 0.01" in (out / "config.yaml").read_text()
    import yaml

    resolved = yaml.safe_load((out / "config.yaml").read_text())  # the noise the extractors ran with
    ran = resolved["ran_with"]["room.log"]
    assert 0.004 < ran["split_merge"]["sigma"] < 0.007  # 5 mm simulated, estimated from the log
    assert 0.004 < ran["split_merge"]["sigma_fit"] < 0.007
    assert ran["hough"] == {"sigma": ran["split_merge"]["sigma"]}


def test_cli_errors_are_one_line(tmp_path, capsys):
    res = _cli("no_such_world_or_log", "--out", str(tmp_path))
    assert res.returncode == 2 and "neither a world" in res.stderr
    # the second in this process: the status and the stderr line of a subprocess are the first's
    from experiments.cli import main

    assert main(["compare", "office", "--methods", "nonexistent", "--out", str(tmp_path)]) == 2
    assert "unknown method(s) nonexistent; known: sensor" in capsys.readouterr().err


def test_compare_on_a_simulated_world():
    sim = pytest.importorskip("sim")
    if not hasattr(sim, "simulate_records"):
        pytest.skip("sim.simulate_records not on this branch yet")
    from experiments.compare import parse_sources

    sources = parse_sources(["angles"], seeds=[1], duration=2.0, rate_hz=2.0)
    table = compare(sources, ["split_merge", "hough"])
    assert set(table["source"]) == {"angles"} and set(table["seed"]) == {1}
    assert len(table) == 2 * table["scan"].nunique() and table["scan"].nunique() >= 3
    # scored against the simulator's visible truth: most faces found on a noisy LMS200 scan
    assert table["tp"].sum() > 0 and (table["n_truth"] > 0).all()
    s = summarise(table).set_index("method")
    assert (s["f1"] > 0.6).all() and (s["rho_rms_mm"] < 30).all()


def test_common_errors_use_only_faces_every_method_matched():
    from experiments.compare import common_errors

    m = pd.DataFrame([
        dict(method="a", source="w", seed=0, scan=0, face=0, rho_err=0.003, alpha_err=0.0),
        dict(method="b", source="w", seed=0, scan=0, face=0, rho_err=-0.004, alpha_err=0.01),
        dict(method="b", source="w", seed=0, scan=0, face=1, rho_err=0.5, alpha_err=0.2),  # only b
        dict(method="a", source="w", seed=1, scan=0, face=0, rho_err=0.004, alpha_err=0.0),
        dict(method="b", source="w", seed=1, scan=0, face=0, rho_err=0.0, alpha_err=0.0),
    ])
    c = common_errors(m).set_index("method")
    assert c.loc["a", "n_common"] == 2 and c.loc["b", "n_common"] == 2
    assert c.loc["a", "rho_rms_common_mm"] == pytest.approx(np.sqrt((9 + 16) / 2))
    assert c.loc["b", "rho_rms_common_mm"] == pytest.approx(np.sqrt(16 / 2))
    assert c.loc["b", "alpha_rms_common_deg"] == pytest.approx(np.rad2deg(np.sqrt(0.01**2 / 2)))


def test_simulated_sources_carry_the_exact_lines_scores():
    """The truth columns score the visible faces themselves: noiseless, they explain every beam they
    cover with no ray error; under 25 mm noise their ray RMSE is the truncated normal's (15.7 mm),
    the reference the methods' ray RMSE is read against (the same in every method's row)."""
    from features.realdata import truncated_normal_rms

    exact = compare([room_source(sigma=0.0)], ["split_merge"])
    assert np.allclose(exact["truth_ray_rmse"], 0.0, atol=1e-9)
    assert (exact["truth_explained_3cm"] > 0.95).all()
    noisy = compare([room_source(sigma=0.025)], ["split_merge", "iepf"])
    for col in ("truth_explained_3cm", "truth_ray_rmse", "n_truth_explained_3cm"):
        assert (noisy.groupby("scan")[col].nunique() == 1).all()  # one value per scan, whatever the method
    s = summarise(noisy)
    assert s["truth_ray_rmse_mm"].iloc[0] == pytest.approx(1e3 * truncated_normal_rms(0.025, 0.03), rel=0.08)
    assert (s["truth_ray_rmse_mm"] == s["truth_ray_rmse_mm"].iloc[0]).all()
    assert "truth_ray_rmse_mm" not in summarise(compare([room_source()], ["split_merge"]).drop(
        columns=["truth_explained_3cm", "n_truth_explained_3cm", "truth_ray_rmse"]))


def test_compare_checks_each_scans_truth_once(monkeypatch):
    """score_scan checked the truth on every call (np.prod of every field's shape, np.isfinite of
    every field: 28-30 us a call), once per method on the same truth; compare now checks it once a
    scan (features.scoring.check_truth) and the scores are those of the unchecked truth, field by field."""
    from features import extract, scoring
    from features.realdata import truth_arrays

    calls = []
    monkeypatch.setattr(scoring, "truth_arrays", lambda truth, *a, **k: calls.append(1) or truth_arrays(truth, *a, **k))
    table = compare([room_source()], BASELINES)
    assert len(table) == len(POSES) * len(BASELINES) and len(calls) == len(POSES)  # was one call per row
    for k, pose in enumerate(POSES):
        scan, truth = room_scan(L_ROOM, pose, sigma=0.005, seed=k)
        checked = scoring.check_truth(truth)
        assert scoring.check_truth(checked) is checked
        for method in BASELINES:
            fs = extract(scan, method)
            a, b = scoring.score_scan(fs, truth), scoring.score_scan(fs, checked)
            assert a.extra == b.extra
            for name in set(a.__dataclass_fields__) - {"extra"}:
                assert np.array_equal(np.asarray(getattr(a, name)), np.asarray(getattr(b, name)), equal_nan=True), name


@pytest.mark.parametrize("sigma", [1e-300, 5e-5, 0.0, -1.0, float("nan"), 1001.0, "abc"])
def test_compare_refuses_a_noise_no_rangefinder_has(sigma):
    """``compare(..., sigma=1e-300)`` (and ``--sigma 1e-300``) ran, exit 0: the extractors were told
    a noise of 1e-300 m (the sensor method found no line, F1 0) and every 3-sigma explained fraction
    was 0 (sigma_r_mm 1e-297). A number is taken in [0.1 mm, features.baselines.checks.MAX_SIGMA_M]."""
    from lms200 import LmsbenchError

    with pytest.raises(LmsbenchError, match=r"^sigma: must be a range noise std in \[0\.0001, 1000\] m, or 'auto', got "):
        compare([room_source()], ["split_merge"], sigma=sigma)


def test_compare_takes_a_noise_at_its_bounds():
    """The bounds themselves are taken, and a number is used as given (not floored)."""
    for sigma in (1e-4, 1000.0):
        table = compare([room_source()], ["split_merge"], sigma=sigma)
        assert (table["sigma_r"] == sigma).all()


def test_methods_are_taken_comma_separated_as_well_as_apart():
    """``--methods sensor,split_merge`` (how many tools take lists) was refused as one unknown name."""
    from experiments.options import check_methods

    assert check_methods(["sensor,split_merge", "iepf"]) == ["sensor", "split_merge", "iepf"]
    assert check_methods(["sensor, hough"]) == ["sensor", "hough"]
    assert check_methods(["sensor,", "hough"]) == ["sensor", "hough"]  # the shell's split of `sensor, hough`
    assert check_methods(["sensor", ",hough"]) == ["sensor", "hough"]
    from lms200 import LmsbenchError

    for bad, says in ((["sensor,,hough"], "an empty name between commas"), ([","], "an empty name"),
                      ([",,"], "an empty name"), (["sensor,sensor"], "named twice")):
        with pytest.raises(LmsbenchError, match=says):
            check_methods(bad)


def test_slam_takes_one_extractor_not_a_list(tmp_path):
    log = tmp_path / "room.log"
    write_log(log, room_source().records[:3])
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    res = subprocess.run([sys.executable, "-m", "experiments.cli", "slam", str(log), "--extractor", "sensor,iepf",
                          "--out", str(tmp_path / "s")], capture_output=True, text=True, env=env, cwd=ROOT, timeout=120)
    assert res.returncode == 2 and res.stderr.strip().endswith("one extractor runs in the SLAM; give one name"), res.stderr
    assert not (tmp_path / "s").exists()
