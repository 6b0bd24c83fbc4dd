"""The numba backend of the sensor method is the numpy reference, compiled: on simulated worlds,
noisy synthetic rooms, degenerate inputs, other resolutions and non-default configurations both
backends give the same FeatureSet (same lines and corners, values within 1e-9)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from features import FeatureSet, extract
from features.sensor import resolve_backend
from lms200 import Scan

from backend_checks import assert_same
from sensor_geometry import cast, room
from test_sensor_props import scans

numba = pytest.importorskip("numba")


def both(scan: Scan, **params) -> tuple[FeatureSet, FeatureSet]:
    return extract(scan, method="sensor", backend="numpy", **params), extract(
        scan, method="sensor", backend="numba", **params
    )


def test_auto_backend_is_numba_when_installed() -> None:
    assert resolve_backend("auto") == "numba"
    assert resolve_backend("numpy") == "numpy"
    with pytest.raises(ValueError, match="backend"):
        extract(Scan.lms200(np.full(361, 2.0)), method="sensor", backend="fortran")


@pytest.mark.parametrize("world", ["office", "angles", "pillars"])
def test_simulated_worlds(world: str) -> None:
    sim = pytest.importorskip("sim")
    records = sim.simulate_records(world=world, seed=3, duration=40.0, rate_hz=1.0)
    n_lines = n_corners = 0
    for i, rec in enumerate(records):
        ref, got = both(rec.scan)
        assert_same(ref, got, f"{world} scan {i}")
        n_lines += len(ref.lines)
        n_corners += len(ref.corners)
    assert n_lines >= len(records)  # the comparison covers real extractions, not empty sets
    if world != "pillars":
        assert n_corners > 0


def test_simulated_office_ideal_and_cm_mode() -> None:
    sim = pytest.importorskip("sim")
    for sensor in (sim.SensorConfig.ideal(), sim.SensorConfig(units="cm")):
        for i, rec in enumerate(sim.simulate_records(world="office", seed=5, duration=20.0, rate_hz=1.0, sensor=sensor)):
            assert_same(*both(rec.scan), f"{sensor.units} scan {i}")


@pytest.mark.parametrize(
    "n, increment_deg", [(361, 0.5), (181, 1.0), (401, 0.25), (180, 1.0)], ids=["361", "181", "401", "180"]
)
def test_noisy_rooms_at_every_resolution(n: int, increment_deg: float) -> None:
    found = 0
    for seed in range(25):
        ref, got = both(room(seed, n, np.deg2rad(increment_deg)))
        assert_same(ref, got, f"room {seed} ({n} beams)")
        found += len(ref.lines)
    assert found > 25


def test_rooms_with_dropouts_and_other_configs() -> None:
    configs = [
        {},
        {"k": 5},
        {"k": 1, "min_points": 5},
        {"acute_check": False, "bridge_invalid": 3, "merge_gap": 8},
        {"corners": False},
        {"hough_angles": 11, "hough_subdiv": 2, "band_min": 0.02},
    ]
    rng = np.random.default_rng(7)
    for seed in range(12):
        scan = room(100 + seed)
        ranges = scan.ranges.copy()
        ranges[rng.random(ranges.size) < 0.03] = np.nan
        ranges[rng.random(ranges.size) < 0.02] = np.inf
        dropped = Scan(ranges, scan.angle_min, scan.angle_increment, scan.range_min, scan.range_max)
        for params in configs:
            assert_same(*both(dropped, **params), f"room {seed} {params}")


def test_a_line_longer_than_the_pairwise_block() -> None:
    """A wall seen by all 401 beams: sums over more than 128 beams use numpy's pairwise tree."""
    scan = cast([(2.0, -50.0, 2.0, 50.0)], n=401, angle_min=-np.deg2rad(50), increment=np.deg2rad(0.25), sigma=0.003)
    ref, got = both(scan)
    assert len(ref.lines) == 1 and ref.lines[0].n_points > 300
    assert_same(ref, got, "long wall")


@pytest.mark.parametrize(
    "ranges",
    [
        np.full(361, np.inf),
        np.full(361, np.nan),
        np.zeros(361),
        np.full(361, 1e300),
        np.where(np.arange(361) == 180, 2.0, np.inf),
        np.array([2.0]),
        np.full(7, 2.0),
        np.where(np.arange(361) % 2 == 0, 2.0, np.nan),
        np.full(361, 2.0),
    ],
    ids=["inf", "nan", "zeros", "huge", "one-valid", "one-beam", "seven-beams", "alternating", "circle"],
)
def test_degenerate_inputs(ranges: np.ndarray) -> None:
    scan = Scan(ranges, -np.pi / 2, np.deg2rad(0.5), 0.0, 8.183)
    ref, got = both(scan)
    assert_same(ref, got, "degenerate")
    assert got.lines == [] and got.corners == []


def test_compare_reports_each_methods_backend() -> None:
    import pandas as pd

    from experiments.compare import format_summary
    from features.registry import backend_of, make_config

    assert backend_of("sensor") == "numba"
    assert backend_of("sensor", make_config("sensor", backend="numpy")) == "numpy"
    assert backend_of("hough") == "numpy"  # no backend field: the numpy implementation
    rows = [dict(source="s", method="sensor", backend="numba", scans=1, us_median=100.0),
            dict(source="s", method="hough", backend="numpy", scans=1, us_median=900.0)]
    text = format_summary(pd.DataFrame(rows))
    assert "backend" in text.splitlines()[0]
    assert "sensor=numba, hough=numpy" in text and "not like for like" in text
    same = format_summary(pd.DataFrame(rows[:1]))
    assert "note" not in same


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # the numpy baselines' overflow on 1e300 ranges
@settings(max_examples=150, deadline=None)
@given(scans(), st.integers(1, 12))
def test_any_scan_gives_the_same_features_on_both_backends(scan: Scan, k: int) -> None:
    """Random resolutions, fields of view, special values and windows (the never-raise scans)."""
    ref, got = both(scan, k=k)
    assert_same(ref, got, f"{len(scan)} beams, k={k}")
    for method in ("split_merge", "iepf"):
        ref = extract(scan, method=method, backend="numpy")
        got = extract(scan, method=method, backend="numba")
        assert_same(ref, got, f"{method} {len(scan)} beams", method)


def test_importing_the_extractors_does_not_import_numba() -> None:
    """numba (~0.5 s to import) loads on the first compiled call, not with ``import features``."""
    import subprocess
    import sys
    from pathlib import Path

    code = ("import sys, features, features.sensor, features.baselines.split_merge, features.baselines.iepf; "
            "print('numba' in sys.modules)")
    root = Path(__file__).resolve().parents[1]
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env={"PYTHONPATH": str(root), "PATH": ""}, cwd=root)
    assert out.stdout.strip() == "False"
