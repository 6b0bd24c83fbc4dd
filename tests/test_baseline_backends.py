"""The numba backends of ``split_merge`` and ``iepf`` are their numpy references, compiled: the same
FeatureSet (lines, corners, values within 1e-9) on simulated worlds, noisy rooms with dropouts,
other resolutions, non-default configurations and degenerate inputs."""

from __future__ import annotations

import numpy as np
import pytest

from features import extract
from features.registry import backend_of
from lms200 import Scan

from backend_checks import assert_same
from sensor_geometry import cast, room

numba = pytest.importorskip("numba")

METHODS = ("split_merge", "iepf")


def check(scan: Scan, label: str, **params) -> int:
    """Both backends of both methods on ``scan``; returns the reference's line count."""
    found = 0
    for method in METHODS:
        ref = extract(scan, method=method, backend="numpy", **params)
        got = extract(scan, method=method, backend="numba", **params)
        assert_same(ref, got, f"{method} {label}", method)
        found += len(ref.lines)
    return found


def test_default_backend_is_numba() -> None:
    assert backend_of("split_merge") == backend_of("iepf") == "numba"
    with pytest.raises(ValueError, match="backend"):
        extract(Scan.lms200(np.full(361, 2.0)), method="iepf", backend="cuda")


@pytest.mark.parametrize("world", ["office", "angles", "pillars"])
def test_simulated_worlds(world: str) -> None:
    sim = pytest.importorskip("sim")
    records = sim.simulate_records(world=world, seed=4, duration=40.0, rate_hz=1.0)
    found = sum(check(rec.scan, f"{world} scan {i}") for i, rec in enumerate(records))
    assert found >= 2 * len(records)


@pytest.mark.parametrize("n, increment_deg", [(361, 0.5), (181, 1.0), (401, 0.25)], ids=["361", "181", "401"])
def test_noisy_rooms_at_every_resolution(n: int, increment_deg: float) -> None:
    found = sum(check(room(seed, n, np.deg2rad(increment_deg)), f"room {seed}") for seed in range(20))
    assert found > 40


def test_dropouts_and_other_configs() -> None:
    configs = [{}, {"runs_z": 3.0}, {"merge_rms": 0.0}, {"max_skip": 1, "min_points": 4}, {"split_threshold": 0.01}]
    rng = np.random.default_rng(11)
    for seed in range(10):
        scan = room(200 + seed)
        ranges = scan.ranges.copy()
        ranges[rng.random(ranges.size) < 0.03] = np.nan
        ranges[rng.random(ranges.size) < 0.02] = np.inf
        dropped = Scan(ranges, scan.angle_min, scan.angle_increment, scan.range_min, scan.range_max)
        for params in configs:
            check(dropped, f"room {seed} {params}", **params)


def test_a_cluster_longer_than_the_scan_half() -> None:
    """One straight wall over all 401 beams, and a circle (a split to the bottom)."""
    wall = cast([(2.0, -50.0, 2.0, 50.0)], n=401, angle_min=-np.deg2rad(50), increment=np.deg2rad(0.25), sigma=0.003)
    assert check(wall, "wall") == 2
    arc = cast(circles=[(3.0, 0.0, 1.5)], sigma=0.002)
    check(arc, "arc")


@pytest.mark.parametrize(
    "ranges",
    [np.full(361, np.inf), np.full(361, np.nan), np.zeros(361), np.full(361, 1e300),
     np.where(np.arange(361) == 180, 2.0, np.inf), np.array([2.0]), np.full(3, 2.0),
     np.where(np.arange(361) % 2 == 0, 2.0, np.nan)],
    ids=["inf", "nan", "zeros", "huge", "one-valid", "one-beam", "three-beams", "alternating"],
)
def test_degenerate_inputs(ranges: np.ndarray) -> None:
    check(Scan(ranges, -np.pi / 2, np.deg2rad(0.5), 0.0, 8.183), "degenerate")


@pytest.mark.parametrize(
    "beams, value, lines_per_method",
    [([180], np.inf, 2), ([150, 151], np.inf, 2), ([120, 240], np.inf, 3),
     ([180], np.nan, 1), ([150, 151], np.nan, 1), ([120, 240], np.nan, 1)],
)
def test_no_return_beams_break_and_invalid_beams_are_bridged_alike(beams: list, value: float,
                                                                   lines_per_method: int) -> None:
    """Both backends cut a cluster at a +inf beam and step over up to max_skip - 1 nan beams."""
    wall = cast([(2.0, -3.0, 2.0, 3.0)], sigma=0.002, seed=5)
    ranges = wall.ranges.copy()
    ranges[beams] = value
    assert check(wall.replace(ranges=ranges), f"{value} at {beams}") == len(METHODS) * lines_per_method
