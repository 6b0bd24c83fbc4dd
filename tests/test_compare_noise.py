"""compare gives every extractor the source's noise: the range noise fields of all methods, and for
split_merge / iepf the scatter about fitted lines (``sigma_fit``) of their split and merge tests;
a field the caller sets replaces that field alone (tests/test_noise_overrides.py)."""

from __future__ import annotations

import numpy as np

from experiments.compare import _with_noise
from features.noise_estimate import fit_sigma
from features.registry import get_method, make_config
from lms200 import Scan


def test_the_baselines_get_the_fit_scatter_and_a_given_noise_leaves_it() -> None:
    runs = [(m, get_method(m).run, make_config(m)) for m in ("sensor", "split_merge", "iepf")]
    out = {name: cfg for name, _, cfg in _with_noise(runs, {}, 0.012, 0.0095)}
    assert out["split_merge"].sigma == 0.012 and out["split_merge"].sigma_fit == 0.0095
    assert out["iepf"].sigma == 0.012 and out["iepf"].sigma_fit == 0.0095
    assert out["sensor"].sigma_r == 0.012 and not hasattr(out["sensor"], "sigma_fit")
    given = {name: cfg for name, _, cfg in _with_noise(runs, {"split_merge": {"sigma": 0.02}}, 0.012, 0.0095)}
    assert given["split_merge"].sigma == make_config("split_merge").sigma  # the caller's, not the source's
    assert given["split_merge"].sigma_fit == 0.0095  # not a field the caller set: the source's
    assert given["iepf"].sigma_fit == 0.0095
    assert {n: c.sigma_fit for n, c in out.items() if n != "sensor"} != {"split_merge": None, "iepf": None}


def test_fit_sigma_of_noiseless_scans_is_floored_at_1_mm() -> None:
    """An L room without noise: the residuals are rounding (~1e-16 m); the thresholds built from the
    estimate must stay finite and > 0, as with neighbour_sigma's floor."""
    b = np.deg2rad(0.5) * (np.arange(361) - 180)
    r = np.minimum(3.0 / np.maximum(np.abs(np.cos(b)), 1e-9), 2.5 / np.maximum(np.abs(np.sin(b)), 1e-9))
    scan = Scan(np.minimum(r, 8.0), float(b[0]), np.deg2rad(0.5), 0.0, 8.183)
    assert fit_sigma([scan] * 3) == 0.001
    noisy = Scan(scan.ranges + 0.01 * np.random.default_rng(0).standard_normal(361), scan.angle_min,
                 scan.angle_increment, 0.0, 8.183)
    assert 0.008 < fit_sigma([noisy] * 3) < 0.012


def test_records_in_memory_get_the_noise_a_log_gets(tmp_path) -> None:
    """sim2real scores a log's records and a simulated run as logs: Source.from_records must estimate
    every noise log_source estimates (sim2real once gave the sensor method no bearing noise on the
    real log, so its 'real' figures were not compare's), from the same scans to the same values."""
    import dataclasses

    from experiments.compare import Source, log_source
    from features.noise_estimate import bearing_sigma, neighbour_sigma
    from lms200 import read_log, write_log
    from sim import SensorConfig, simulate_records

    recs = simulate_records("office", seed=3, duration=3.0, rate_hz=5, sensor=SensorConfig(units="cm", noise_sigma=0.008))
    path = tmp_path / "run.clf"
    write_log(path, recs)
    from_log, in_memory = log_source(path), Source.from_records(list(read_log(path)), name="run.clf")
    estimates = [f.name for f in dataclasses.fields(Source) if f.name.startswith("estimate_")]
    for name in estimates:
        if name == "estimate_sigma":  # sigma_r: compare estimates it from any re-iterable records
            continue
        assert getattr(from_log, name) is not None, name
        assert getattr(in_memory, name) is not None, name
        assert getattr(in_memory, name)() == getattr(from_log, name)(), name
    assert in_memory.estimate_bearing_sigma() == bearing_sigma(read_log(path))
    assert in_memory.estimate_extractor_sigma() == neighbour_sigma(read_log(path))
    assert 0.006 < in_memory.estimate_extractor_sigma() < 0.012  # the 8 mm of the run, cm-rounded


def test_compare_runs_the_sensor_method_with_the_sources_bearing_noise() -> None:
    """compare hands a log-like source's bearing-noise estimate to the sensor method (issue #13):
    its rows equal extract() given that noise, and differ from extract() without it; a range noise
    the caller sets for the sensor method leaves it (a researcher's walkthrough: it dropped it)."""
    from experiments.compare import NOISE_FIELDS, Source, _with_noise, compare
    from features import extract
    from features.registry import get_method
    from sim import SensorConfig, simulate_records

    recs = simulate_records("office", seed=5, duration=4.0, rate_hz=4, sensor=SensorConfig(noise_sigma=0.008))
    src = Source.from_records(recs, name="run")
    src.estimate_extractor_sigma = lambda: 0.01
    src.estimate_bearing_sigma = lambda: 0.02
    table = compare([src], ["sensor"])
    noise = {f: 0.01 for f in NOISE_FIELDS if f in ("sigma_r", "sigma_r_cm")}
    with_b = [len(extract(r.scan, "sensor", sigma_bearing=0.02, **noise).lines) for r in recs]
    without = [len(extract(r.scan, "sensor", **noise).lines) for r in recs]
    assert table["n_lines"].tolist() == with_b
    assert with_b != without  # the bearing noise changes the lines: the test can fail
    runs = [("sensor", get_method("sensor").run, get_method("sensor").config_type())]
    (_, _, given), = _with_noise(runs, {"sensor": {"sigma_r": 0.02}}, 0.01, None, 0.02)
    assert given.sigma_bearing == 0.02 and given.sigma_r_cm == 0.01  # the caller set sigma_r alone
    (_, _, estimated), = _with_noise(runs, {}, 0.01, None, 0.02)
    assert estimated.sigma_bearing == 0.02 and estimated.sigma_r == 0.01


def test_source_sigma_floors_at_the_extractors_min_sigma(monkeypatch):
    """compare floored a source's own noise at a bare 1e-6 beside features.baselines.checks.MIN_SIGMA_M
    (the floor the extractors refuse below): one constant now, so the two cannot drift apart."""
    from experiments import compare
    from features.baselines import checks

    src = compare.Source("tiny", "sim", 0, [], sigma_r=1e-300)
    assert compare._source_sigma(src, None) == checks.MIN_SIGMA_M == 1e-6
    monkeypatch.setattr(compare, "EXTRACTOR_MIN_SIGMA_M", 2e-6)
    assert compare._source_sigma(src, None) == 2e-6
