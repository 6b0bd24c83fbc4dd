"""Scans seconds apart (keyframe logs): the correlative search of the default pipeline, and the
health flag where the scans do not fix the motion. Simulated runs with exact truth; one real log."""

from __future__ import annotations

import numpy as np
import pytest

from slam import SlamConfig, run_slam
from slam.config import AlignmentConfig
from slam.correlative import fit, free_share, free_space, make_field, search, see_through
from slam.geometry import compose, to_world
from slam.icp import make_reference
from slam.metrics import ate


@pytest.fixture(scope="module")
def sparse_runs():
    """Simulated office runs (90 s) decimated to 0.5 scans/s: 2 s between scans, up to 1 m and
    115 degrees of motion between two of them."""
    from sim import simulate_records

    return {seed: simulate_records("office", seed=seed, duration=90.0, rate_hz=0.5) for seed in (0, 1, 7)}


@pytest.fixture(scope="module")
def slam_once():
    """``run_slam(records, config)``, run once for the module: tests that check different sides of
    the same run (the same records, item for item, and an equal config) share it. Each run is kept
    with its records, so a list built anew from the same records finds it too."""
    runs: list[tuple[list, SlamConfig, object]] = []

    def run(records, config: SlamConfig):
        for seen, seen_config, result in runs:
            if seen_config == config and len(seen) == len(records) and all(a is b for a, b in zip(seen, records)):
                return result
        runs.append((list(records), config, run_slam(records, config)))
        return runs[-1][2]

    return run


@pytest.fixture(scope="module")
def real_log():
    """The records of a real log (a path), read once for the module; the tests read them, never change them."""
    read: dict = {}

    def records(path) -> list:
        from lms200 import read_log

        if path not in read:
            read[path] = list(read_log(path))
        return read[path]

    return records


def _ate(records, config: SlamConfig, run=run_slam):
    result = run(records, config)
    truth = np.array([(r.scan.stamp, *r.truth) for r in records])
    return ate(result.trajectory, truth).rmse, result.diagnostics


@pytest.mark.parametrize("seed", [0, 7])
def test_scans_two_seconds_apart_are_tracked(sparse_runs, slam_once, seed):
    """Measured: ATE 0.017 and 0.006 m with the search, 5.0 and 1.9 m without (the ICP from the
    constant-velocity prediction reaches 0.5 m, the motion is up to 1 m and 115 degrees); no
    step ambiguous, so healthy."""
    records = sparse_runs[seed]
    err, diag = _ate(records, SlamConfig(), slam_once)
    assert err < 0.05
    assert diag["searched_fraction"] > 0.9 and diag["healthy"]
    old, _ = _ate(records, SlamConfig.from_dict({"alignment": {"search": False}}))
    assert old > 1.0  # the case needs the search: without it the run is lost


def test_a_run_the_scans_do_not_fix_is_not_healthy(sparse_runs):
    """Seed 1 slides along a bare corridor (ATE 2.3 m, measured): 1 of its 44 steps had a
    distinct pose that fitted as well, which only the motion model told apart."""
    err, diag = _ate(sparse_runs[1], SlamConfig())
    assert err > 0.5
    assert diag["ambiguous_fraction"] > 0.0 and np.sum(diag["ambiguous"]) == 1
    assert not diag["healthy"]


def _heading_steps_error(trajectory: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """(n - 1,) rad: how far each step's turn of the estimate (stamp, x, y, theta rows) is from the truth's."""
    d = np.diff(trajectory[:, 3]) - np.diff(truth[:, 3])
    return np.abs(np.remainder(d + np.pi, 2 * np.pi) - np.pi)


def test_a_corridor_seen_half_a_turn_the_wrong_way_does_not_win():
    """Scans 0.64 s apart (csail-robotlaser1's interval) along the simulated corridor: the
    prediction's 3 std of heading span the whole turn (``motion.sigma_alpha`` 4 rad/s^2 x dt^2),
    and the corridor looks alike both ways. Before the turn bound and the keep rule the search
    took the half-turn pose (measured: ATE 3.17 m, a 180-degree step); now ATE 0.025 m and no
    step turns more than 0.63 degrees off the truth's (asserted: 0.05 m and 1 degree)."""
    from sim import simulate_records

    records = simulate_records("corridor", seed=0, duration=45.0, rate_hz=1.5625)
    result = run_slam(records, SlamConfig())
    truth = np.array([(r.scan.stamp, *r.truth) for r in records])
    assert ate(result.trajectory, truth).rmse < 0.05
    assert np.degrees(_heading_steps_error(result.trajectory, truth).max()) < 1.0
    assert result.diagnostics["searched_fraction"] > 0.9  # 3 std of 0.42 m exceed the ICP's 0.5 m reach


def test_the_search_keeps_to_the_turn_a_robot_can_make():
    """``turn`` = (heading, max turn): every candidate's heading lies within the bound of that
    heading, even where the best pose of the whole turn lies outside it (the room seen from a
    pose 2 rad from the reference)."""
    world = _room()[0]
    true = np.array([1.5, 1.2, 2.0])
    c, s = np.cos(true[2]), np.sin(true[2])
    scan = (world[::7] - true[:2]) @ np.array([[c, -s], [s, c]])
    field = make_field(world, 0.1, 0.2)
    free = search(scan, field, true, 1.0, np.pi, 0.2, np.radians(1.0), 4, 0.3, 0.1)
    assert abs(free[0].pose[2] - true[2]) <= np.radians(1.5)  # unbounded: the true heading wins
    bounded = search(scan, field, true, 1.0, np.pi, 0.2, np.radians(1.0), 4, 0.3, 0.1, turn=(0.0, 1.0))
    assert bounded and all(abs(np.arctan2(np.sin(b.pose[2]), np.cos(b.pose[2]))) <= 1.0 + 1e-9 for b in bounded)
    assert search(scan, field, true, 1.0, 0.2, 0.2, np.radians(1.0), 4, 0.3, 0.1, turn=(0.0, 1.0)) == []


@pytest.mark.shared_data
def test_csail_robotlaser1_does_not_flip(shared_data):
    """csail-robotlaser1, scans 500-599 (0.64 s apart, a corridor and a turn in place): before the
    turn bound and the keep rule the search flipped the pose half a turn at scans 553 and 559 of
    the whole log (ATE 9.97 m against the log's own poses, 0.347 m without the search); on this
    slice ATE 0.96 m then, 0.083 m now (measured)."""
    from lms200 import read_log

    records = list(read_log(shared_data / "csail-robotlaser1.log.gz"))[500:600]
    truth = np.array([(r.scan.stamp, *r.odom) for r in records])
    result = run_slam(records, SlamConfig())
    assert ate(result.trajectory, truth).rmse < 0.3
    assert np.degrees(_heading_steps_error(result.trajectory, truth).max()) < 20.0


def _room() -> tuple[np.ndarray, np.ndarray]:
    """Points (m, 2) on the walls of an L-shaped room with a pillar (no symmetry), 2 cm apart,
    and their unit normals."""
    corners = [(0, 0), (8, 0), (8, 3), (4, 3), (4, 6), (0, 6), (0, 0)]
    pts, nrm = [], []
    for (x0, y0), (x1, y1) in zip(corners[:-1], corners[1:]):
        length = np.hypot(x1 - x0, y1 - y0)
        s = np.linspace(0, 1, int(length / 0.02), endpoint=False)
        pts.append(np.column_stack((x0 + s * (x1 - x0), y0 + s * (y1 - y0))))
        nrm.append(np.tile([-(y1 - y0) / length, (x1 - x0) / length], (s.size, 1)))
    a = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    pts.append(np.column_stack((2 + 0.3 * np.cos(a), 2 + 0.3 * np.sin(a))))
    nrm.append(np.column_stack((np.cos(a), np.sin(a))))
    return np.concatenate(pts), np.concatenate(nrm)


@pytest.mark.parametrize("turn", [None, (np.pi, 1.0)])
def test_the_search_peaks_wrap_round_the_whole_turn(turn):
    """``peaks=True`` with the whole turn: the first and last headings of the window are
    neighbours. The room seen at the window's second heading (5 degrees past the seam at -pi):
    unwrapped, the last heading, the best pose's neighbour across the seam, was a peak of its own
    (0.47, 10 degrees and 0.28 m from the best), also with a turn bound whose arc spans the seam."""
    world = _room()[0]
    step = np.radians(5.0)
    true = np.array([1.5, 1.2, -np.pi + step])
    c, s = np.cos(true[2]), np.sin(true[2])
    scan = (world[::7] - true[:2]) @ np.array([[c, -s], [s, c]])
    field = make_field(world, 0.1, 0.2)
    out = search(scan, field, np.array([1.5, 1.2, 0.0]), 0.4, np.pi, 0.2, step, 6, 0.001, 0.001, turn=turn, peaks=True)
    assert np.allclose(out[0].pose, true) and out[0].score == pytest.approx(1.0)
    near = [o for o in out[1:] if abs(np.angle(np.exp(1j * (o.pose[2] - true[2])))) <= 2.5 * step]  # across the seam: 2 steps
    assert near == [], [(o.pose, o.score) for o in near]  # every other candidate is another heading
    assert all(o.score < 0.25 for o in out[1:])


def test_search_finds_a_pose_a_metre_and_a_half_turn_from_the_guess():
    world = _room()[0]
    true = np.array([1.5, 1.2, 2.0])
    rng = np.random.default_rng(0)
    c, s = np.cos(true[2]), np.sin(true[2])
    scan = (world[::7] - true[:2]) @ np.array([[c, -s], [s, c]]) + rng.normal(0, 0.01, world[::7].shape)
    np.testing.assert_allclose(to_world(true, scan), world[::7], atol=0.06)  # the room seen from the true pose
    field = make_field(world, 0.1, 0.2)
    guess = compose(true, np.array([0.9, -0.7, -1.4]))
    best = search(scan, field, guess, 2.0, np.pi, 0.2, np.radians(1.0), 3, 0.3, 0.1)
    assert len(best) == 3 and best[0].score >= best[1].score >= best[2].score
    d = best[0].pose - true
    assert np.hypot(d[0], d[1]) <= 0.15 and abs(np.arctan2(np.sin(d[2]), np.cos(d[2]))) <= np.radians(1.5)


def test_fit_tells_a_tight_fit_from_points_near_a_wall():
    """On the walls: every point's residual is 0 (fit 1); 5 cm off both axes: every residual is
    5 cm (fit exp(-0.5 (5/3)^2) = 0.25, as the formula); the inlier fraction would be 1 for both."""
    world, normals = _room()
    ref = make_reference(world, normals, 0.0)
    walls = world[:-60:5]
    assert fit(walls, None, ref, np.zeros(3), 0.15, 0.03, -1.0) == pytest.approx(1.0, abs=1e-9)
    off = fit(walls, None, ref, np.array([0.05, 0.05, 0.0]), 0.15, 0.03, -1.0)
    assert off == pytest.approx(np.exp(-0.5 * (0.05 / 0.03) ** 2), abs=0.03)


def test_see_through_is_the_share_of_the_map_in_view_that_the_beams_pass():
    """A corridor 2 m wide, closed 6 m behind the robot and open ahead (beyond the 30 m reach), its
    walls sampled every 5 cm as the map. From the true pose no beam passes a map point (each returns
    from a wall, or from nothing). Turned half a turn, the beams that returned from the side walls
    far ahead now point at the end wall 6 m away and pass it: the share is the map points in view
    nearer than the returns of their beam and both neighbours by more than the chord test's
    tolerance, counted here point by point in plain Python."""
    from experiments.synthetic import room_scan
    from slam.scanslam import ScanPoints

    walls = np.array([[-6.0, -1.0, 40.0, -1.0], [-6.0, 1.0, 40.0, 1.0], [-6.0, -1.0, -6.0, 1.0]])
    along = np.arange(-6.0, 40.0, 0.05)
    side = np.linspace(-1.0, 1.0, 41)
    map_points = np.concatenate([np.column_stack((along, np.full_like(along, -1.0))),
                                 np.column_stack((along, np.full_like(along, 1.0))),
                                 np.column_stack((np.full_like(side, -6.0), side))])
    al = AlignmentConfig()
    scan, _ = room_scan(walls, (0.0, 0.0, 0.0), range_max=30.0)
    bearings, ranges = ScanPoints.from_points(scan.points, al).beams
    args = (bearings, ranges, al.normal_gap, al.normal_gap_per_range, al.max_range)
    assert see_through(map_points, np.zeros(3), *args) == 0.0
    turned = np.array([0.0, 0.0, np.pi])
    share = see_through(map_points, turned, *args)
    step = float(np.median(np.diff(bearings)))
    through = seen = 0
    for q in map_points:
        x, y = -q[0], -q[1]  # the map point in the turned sensor's frame
        rho, beta = float(np.hypot(x, y)), float(np.arctan2(y, x))
        j = int(np.argmin(np.abs(bearings - beta)))
        if rho > al.max_range or abs(bearings[j] - beta) > 1.5 * step:
            continue
        seen += 1
        reach = min(ranges[max(j - 1, 0)], ranges[j], ranges[min(j + 1, bearings.size - 1)])
        through += bool(reach > rho + al.normal_gap + al.normal_gap_per_range * rho)
    assert through > 0 and share == pytest.approx(through / seen, abs=1e-12)


def test_free_space_marks_the_cells_the_map_beams_crossed_short_of_every_surface():
    """A keyframe at the origin saw a wall 5 m ahead (x = 5, y in [-3, 3], every 5 cm). The cells
    its beams crossed, up to the chord test's tolerance short of the wall (0.3 + 0.05 x 5 m) and more
    than ``normal_gap`` (0.3 m) from every map point, score -1; the field keeps its value on and near
    the wall, behind it and outside the beams' fan (unknown space says nothing). Each cell is checked
    against the geometry of the fan, not against the kernel's trace."""
    al = AlignmentConfig()
    y = np.arange(-3.0, 3.0 + 1e-9, 0.05)
    wall = np.column_stack((np.full_like(y, 5.0), y))
    # map points that stretch the field over the fan, and one inside the fan (none of them traced)
    corners = np.array([[-1.0, -4.0], [7.0, 4.0], [2.75, -0.6]])
    field = make_field(np.vstack((wall, corners)), al.search_resolution, al.search_sigma)
    free = free_space(field, np.zeros((1, 2)), [wall], al.normal_gap, al.normal_gap_per_range, al.search_sigma)

    def value(f, x, yy):
        i, j = np.rint((np.array([x, yy]) - f.origin) / f.resolution).astype(int)
        return f.values[i, j]

    stop = 5.0 - al.normal_gap - al.normal_gap_per_range * 5.0  # 4.45 m on the axis
    for x in np.arange(0.5, stop - 0.1, 0.5):
        for yy in (-0.4 * x, 0.0, 0.4 * x):  # inside the fan (|y| <= 0.6 x) and short of the tolerance
            assert value(free, x, yy) == -1.0
    for x, yy in ((4.9, 0.0), (4.6, 0.0), (5.0, 1.0), (6.0, 0.0), (2.0, 2.0), (1.0, -1.0), (2.75, -0.6)):
        # on or near the wall, past the stop point (4.45 m: the tolerance grows with range) but short of
        # the wall, behind it, outside the fan (|y| > 0.6 x), on a map point inside the crossed space:
        # the field's own value
        assert value(free, x, yy) == value(field, x, yy) >= 0.0
    assert value(field, 2.75, -0.6) > 0.0
    # a sigma so small that the field's value gap m from a point underflows: the same cells are free
    tiny = make_field(np.vstack((wall, corners)), al.search_resolution, 0.005)
    free_tiny = free_space(tiny, np.zeros((1, 2)), [wall], al.normal_gap, al.normal_gap_per_range, 0.005)
    for x in np.arange(0.5, stop - 0.1, 0.5):
        for yy in (-0.4 * x, 0.0, 0.4 * x):
            assert value(free_tiny, x, yy) == -1.0
    for x, yy in ((4.9, 0.0), (4.6, 0.0), (2.75, -0.6)):
        assert value(free_tiny, x, yy) >= 0.0
    scan = np.array([[2.0, 0.0], [3.0, 0.5], [5.0, 0.0], [5.0, 1.0]])  # two in the crossed space, two on the wall
    assert free_share(scan, free, np.zeros(3)) == 0.5
    assert free_share(scan, field, np.zeros(3)) == 0.0  # a field without free space marks none
    assert free_share(np.empty((0, 2)), free, np.zeros(3)) == 0.0


def test_see_through_wraps_a_full_turn_of_beams_at_the_seam():
    """A 360-beam ring scan (1 degree apart, from -pi + 0.5 deg): every beam returns at 3 m but the
    last, which returns at 1 m. A map point at 2 m just past -pi is nearest the first beam, whose
    neighbour across the seam returns short of it, so it is not passed.
    Unwrapped, its neighbours were taken on one side only and it read as passed (share 1); with
    the short beam on the far side of the scan instead, it is passed (the beams either side reach
    3 m), which both readings agree on."""
    step = np.deg2rad(1.0)
    bearings = -np.pi + step / 2 + np.arange(360) * step
    ranges = np.full(360, 3.0)
    ranges[-1] = 1.0
    point = 2.0 * np.array([[np.cos(-np.pi + 0.1 * step), np.sin(-np.pi + 0.1 * step)]])  # nearest the first beam
    args = (0.3, 0.05, 30.0)
    assert see_through(point, np.array([0.0, 0.0, 0.0]), bearings, ranges, *args) == 0.0
    ranges[-1], ranges[180] = 3.0, 1.0
    assert see_through(point, np.array([0.0, 0.0, 0.0]), bearings, ranges, *args) == 1.0
    assert see_through(np.empty((0, 2)), np.zeros(3), bearings, ranges, *args) == 0.0
    assert see_through(point, np.zeros(3), bearings[:2], ranges[:2], *args) == 0.0


@pytest.fixture(scope="module")
def corridor_three_seconds_apart():
    """The simulated corridor scanned at 1 degree (181 beams, as Intel's and ACES's logs), 3 s
    apart (Intel's 3.35 s): the first 12 scans, about 1 m between two."""
    from sim import simulate_records
    from sim.sensor import SensorConfig

    sensor = SensorConfig(resolution=np.radians(1.0), n_beams=181)
    return simulate_records("corridor", seed=0, duration=36.0, rate_hz=1 / 3, sensor=sensor)[:12]


def test_a_corridor_seen_backwards_loses_to_the_map_it_sees_through(corridor_three_seconds_apart, slam_once):
    """3 s apart the search's window is the whole turn and the constant-velocity prediction's 3 std
    are metres, so the scan alone chooses. The window's likelihood field and the fit count the points
    that land on the map, never against: a corridor seen half a turn the wrong way lands on the
    richer map behind the robot (measured: step 8 took a 180-degree turn that the truth does not;
    Intel has 34 such steps without odometry, ACES 17). With ``alignment.see_through`` the share of
    the map in view that a pose's beams pass counts against it, and no step turns more than 10
    degrees off the truth's (measured: at most 1.0 degree)."""
    records = corridor_three_seconds_apart
    truth = np.array([(r.scan.stamp, *r.truth) for r in records])
    old = slam_once(records, SlamConfig())
    assert np.degrees(_heading_steps_error(old.trajectory, truth).max()) > 150.0  # the case needs the fix
    new = slam_once(records, SlamConfig.from_dict({"alignment": {"see_through": True}}))
    assert new.diagnostics["searched_fraction"] > 0.9
    assert np.degrees(_heading_steps_error(new.trajectory, truth).max()) < 10.0


@pytest.mark.slow
@pytest.mark.shared_data
def test_aces_keyframe_log_is_not_reported_healthy(shared_data):
    """ACES (440 scans, 2.2 s median apart, long bare corridors): the scans do not fix the
    position along a corridor, and the run drifts by metres against the log's own corrected
    poses; it must not be reported healthy. Its first 150 scans suffice (ambiguous 0.20 of the
    steps, 0.25 on the whole log) at a third of the time."""
    from itertools import islice

    from lms200 import read_log

    records = list(islice(read_log(shared_data / "aces-corrected.log.gz"), 150))
    assert len(records) == 150
    diag = run_slam(records, SlamConfig()).diagnostics
    assert diag["ambiguous_fraction"] > 0.15
    assert not diag["healthy"]


def test_at_five_scans_a_second_the_search_stays_off():
    """At 5 scans/s the prediction's 3 std (0.17 m) lie inside the ICP's 0.5 m reach: the search
    runs only where the match fits poorly, which on seed 0 is nowhere (measured: 0 of 449 steps),
    and the result is the one without it (ATE 0.0077 m, 3 loops, healthy)."""
    from sim import simulate_records

    records = simulate_records("office", seed=0, duration=90.0, rate_hz=5.0)
    err, diag = _ate(records, SlamConfig())
    old, old_diag = _ate(records, SlamConfig.from_dict({"alignment": {"search": False}}))
    assert diag["searched_fraction"] == 0.0 and diag["ambiguous_fraction"] == 0.0 and diag["healthy"]
    assert err == pytest.approx(old, abs=1e-12) and err < 0.02
    assert diag["n_loops"] == old_diag["n_loops"]


def test_a_match_beyond_the_turn_bound_does_not_keep_its_place():
    """The keep rule (the prediction's match stays unless clearly beaten) must not keep a match
    that a heading hypothesis turned half a turn: in a corridor symmetric under a half turn the
    flipped pose fits as well as the right one (0.2 s after the last scan, the bound is
    pi x 0.2 = 0.63 rad). The search's own candidates keep to the bound; the flipped match
    used to win the tie and the step turned by pi. Now the pose nearest the prediction wins."""
    import dataclasses

    from experiments.synthetic import room_scan
    from slam.icp import refine
    from slam.scanslam import ScanPoints, ScanSlam, ScanStep

    corridor = np.array([[-20.0, -1.0, 20.0, -1.0], [-20.0, 1.0, 20.0, 1.0]])  # walls (x0, y0, x1, y1), m
    slam = ScanSlam()
    first, _ = room_scan(corridor, (0.0, 0.0, 0.0))
    slam.step(0.0, first.points)
    x = np.arange(-10.0, 10.0, 0.02)  # the local map: both walls both ways (normals towards the axis)
    slam.ref = make_reference(np.concatenate([np.column_stack((x, np.full_like(x, y))) for y in (-1.0, 1.0)]),
                              np.concatenate([np.tile([0.0, -y], (x.size, 1)) for y in (-1.0, 1.0)]), 0.05)
    true = np.array([0.1, 0.0, 0.0])
    scan, _ = room_scan(corridor, tuple(true))
    sp = ScanPoints.from_points(scan.points, slam.alignment)
    assert slam.ref is not None
    flipped = refine(sp.matched, slam.ref, np.array([0.1, 0.0, np.pi]), slam.alignment)
    m = dataclasses.replace(flipped, start=9)  # the 3.14 rad heading hypothesis won the match
    info = ScanStep(keyframe=0)
    chosen = slam._search(sp, m, true.copy(), 0.1, 1.0, 0.2, info, None)
    assert info.searched
    assert abs(np.arctan2(np.sin(chosen.pose[2]), np.cos(chosen.pose[2]))) < 0.02  # was pi: the flipped match kept
    assert np.hypot(chosen.pose[0] - true[0], chosen.pose[1] - true[1]) < 0.3
    # within the bound (1 s: the whole turn) the same match keeps its place, as before
    info = ScanStep(keyframe=0)
    kept = slam._search(sp, m, true.copy(), 0.1, 1.0, 1.0, info, None)
    assert abs(abs(kept.pose[2]) - np.pi) < 0.02


@pytest.fixture(scope="module")
def sparse_runs_with_odometry():
    """The sparse office runs of ``sparse_runs`` (2 s between scans) with wheel odometry (the
    simulator's default noise: raw odometry ATE 0.26-0.43 m)."""
    from sim import simulate_records
    from sim.records import OdometryConfig

    return {seed: simulate_records("office", seed=seed, duration=90.0, rate_hz=0.5, odometry=OdometryConfig())
            for seed in (1, 11)}


@pytest.mark.parametrize("seed", [1, 11])
def test_odometry_holds_the_default_pipeline_in_a_corridor_the_scans_do_not_fix(sparse_runs_with_odometry, slam_once,
                                                                                 seed):
    """Seeds 1 and 11 slide along bare corridors without odometry (measured: ATE 2.28 and 1.76 m,
    not healthy). With ``motion.use_odometry`` the odometry's step is the prediction, the matcher
    tries no turn beyond a quarter turn of it (or 3 std, where wider) and the search runs only
    where that match fails: ATE 0.023
    and 0.053 m, healthy, well below the raw odometry's 0.43 and 0.33 m."""
    records = sparse_runs_with_odometry[seed]
    truth = np.array([(r.scan.stamp, *r.truth) for r in records])
    odometry = np.array([(r.scan.stamp, *r.odom) for r in records])
    without, diag_without = _ate(records, SlamConfig())
    with_odometry, diag = _ate(records, SlamConfig.from_dict({"motion": {"use_odometry": True}}), slam_once)
    assert without > 1.0 and not diag_without["healthy"]
    assert with_odometry < 0.1 and diag["healthy"]
    assert with_odometry < 0.25 * ate(odometry, truth).rmse


@pytest.mark.parametrize("glitch", ["reset by 5 m and 1 rad", "one scan 1 km off", "reset by 1e6 m"])
def test_an_odometry_glitch_does_not_take_the_run_with_it(sparse_runs_with_odometry, glitch):
    """Real odometry resets and jumps. A step the search cannot check (3 std wider than its 2 m
    window, longer than the scan's reach, or not finite) is not used; a smaller one that the ICP
    cannot confirm competes with the constant-velocity prediction. Measured before: a 1 km jump
    stopped the run (gtsam: indeterminate system), 1e6 m ran out of memory, a 5 m and 1 rad reset
    gave ATE 4.1 m, reported healthy. Now 0.023 m, as without the glitch."""
    from dataclasses import replace

    records = sparse_runs_with_odometry[1]
    if glitch == "one scan 1 km off":
        records = [r if k != 20 else replace(r, odom=(r.odom[0] + 1000.0, r.odom[1], r.odom[2]))
                   for k, r in enumerate(records)]
    else:  # every later pose moved rigidly: the odometry's steps are unchanged but the one at scan 20
        jump = np.array([5.0, 0.0, 1.0]) if glitch == "reset by 5 m and 1 rad" else np.array([1e6, 0.0, 0.0])
        records = [r if k < 20 else replace(r, odom=tuple(compose(jump, np.asarray(r.odom)))) for k, r in enumerate(records)]
    err, diag = _ate(records, SlamConfig.from_dict({"motion": {"use_odometry": True}}))
    assert err < 0.05
    assert diag["odometry_fraction"] > 0.9  # the rest of the run keeps its odometry


@pytest.mark.parametrize("fault", ["frozen from scan 20", "a 1.6 rad spike at scan 20"])
def test_a_wrong_odometry_is_not_reported_healthy(sparse_runs_with_odometry, slam_once, fault):
    """An encoder feed that freezes, or a heading spike, takes the run metres off (measured: ATE
    4.35 and 3.74 m), and it was reported healthy: the match from the odometry's step passed 30 %
    of the points, so no search ran and no step was ambiguous. Now a step whose match from the
    odometry explains under 70 % while one from the constant-velocity prediction explains 70 %
    and 5 % more doubts the odometry, and one such step makes the run unhealthy. The clean run
    has none."""
    from dataclasses import replace

    records = sparse_runs_with_odometry[1]
    config = SlamConfig.from_dict({"motion": {"use_odometry": True}})
    clean = slam_once(records, config).diagnostics  # the clean run of seed 1 is the one above
    assert clean["odometry_doubt_fraction"] == 0.0 and clean["healthy"]
    if fault == "frozen from scan 20":
        records = [r if k < 20 else replace(r, odom=records[20].odom) for k, r in enumerate(records)]
    else:
        records = [r if k != 20 else replace(r, odom=(r.odom[0], r.odom[1], r.odom[2] + 1.6)) for k, r in enumerate(records)]
    err, diag = _ate(records, config)
    assert err > 1.0  # not repaired: said
    assert diag["odometry_doubt_fraction"] > 0.0 and not diag["healthy"]


def test_records_without_odometry_run_on_the_constant_velocity_model(sparse_runs, slam_once):
    """``use_odometry`` with records that have none: every step is predicted as before (the
    same trajectory to the bit), not refused and not broken."""
    records = sparse_runs[7]
    assert all(r.odom is None for r in records)
    a = slam_once(records, SlamConfig()).trajectory  # test_scans_two_seconds_apart_are_tracked[7]'s run
    b = run_slam(records, SlamConfig.from_dict({"motion": {"use_odometry": True}})).trajectory
    assert np.array_equal(a, b)


@pytest.mark.parametrize("name, bound", [("intel-corrected.log.gz", 7.0), ("aces-corrected.log.gz", 5.0)])
def test_radish_keyframe_logs_with_their_odometry(shared_data, real_log, slam_once, name, bound):
    """The Radish corrected logs' raw odometry (read from their ODOM lines) drives the default
    pipeline: ATE RMS against the logs' corrected poses Intel 11.2 -> 3.3 m, ACES 20.4 -> 2.0 m
    (measured; raw odometry 24.0 and 5.42 m)."""
    from experiments.commands.slam import in_time_order

    records = real_log(shared_data / name)
    records = [records[k] for k in in_time_order([r.scan.stamp for r in records])]  # as slam --skip-bad-lines
    truth = np.array([(r.scan.stamp, *r.corrected) for r in records])
    odometry = np.array([(r.scan.stamp, *r.odom) for r in records])
    result = slam_once(records, SlamConfig.from_dict({"motion": {"use_odometry": True}}))
    err = ate(result.trajectory, truth).rmse
    assert err < bound and err < ate(odometry, truth).rmse


def test_the_odometry_retry_gate_keeps_a_retry_from_sliding_along_a_corridor(shared_data, real_log, slam_once):
    """``motion.odom_retry_gate`` (off by default): on ACES with its odometry, a retry from a heading
    hypothesis that kept the odometry's heading but slid 0.5-1.1 m along a corridor (explaining 5-15 %
    more points of a partial overlap) took 35 of the run's consecutive steps more than 0.3 m off the
    corrected poses' (22 more than 0.5 m); held to the odometry's gate, 9 (2). Measured; the ATE is
    not better for it (5.3 against 2.0 m: the closures decide it, docs/slam.md)."""
    from slam.geometry import between

    records = real_log(shared_data / "aces-corrected.log.gz")  # in time order: the radish test's ACES run is gate off
    ref = np.array([r.corrected for r in records])

    def steps_off(gate: bool) -> np.ndarray:
        cfg = SlamConfig.from_dict({"motion": {"use_odometry": True, "odom_retry_gate": gate}})
        p = slam_once(records, cfg).trajectory[:, 1:]
        return np.array([np.hypot(*(between(p[k], p[k + 1]) - between(ref[k], ref[k + 1]))[:2])
                         for k in range(len(p) - 1)])

    off, held = steps_off(False), steps_off(True)
    assert np.sum(off > 0.3) >= 30 and np.sum(off > 0.5) >= 15
    assert np.sum(held > 0.3) <= 12 and np.sum(held > 0.5) <= 4


def test_a_scan_turned_into_known_free_space_loses_with_free_space():
    """The simulated office 2 s apart (0.5 scans/s, seed 4; its first 25 scans): the window's field
    and the fit count only the points that land on the map, and at step 23 the default search took
    a pose half a turn off the truth's step (measured: ATE 2.54 m, two 90-degree steps before it).
    With ``alignment.free_space`` the points that land where the local map's beams went count
    against a pose, and no step turns more than 10 degrees off (measured: at most 1.0 degree, ATE
    7.8 mm)."""
    from sim import simulate_records

    records = simulate_records("office", seed=4, duration=90.0, rate_hz=0.5)[:25]
    truth = np.array([(r.scan.stamp, *r.truth) for r in records])
    old = run_slam(records, SlamConfig())
    assert np.degrees(_heading_steps_error(old.trajectory, truth).max()) > 150.0  # the case needs the fix
    new = run_slam(records, SlamConfig.from_dict({"alignment": {"free_space": True}}))
    assert new.diagnostics["searched_fraction"] > 0.9
    assert np.degrees(_heading_steps_error(new.trajectory, truth).max()) < 10.0
    assert ate(new.trajectory, truth).rmse < 0.05
