"""Bounds of SLAM on hostile input: an endless iterator of records (run_slam), a scan of very
many lines (the paper preset's EKF)."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

from lms200 import Record, Scan
from slam import SlamConfig, SlamInputError, run_slam
from slam.config import SlamConfigError


def _records(n: int, beams: int = 181) -> list[Record]:
    """``n`` scans 0.1 s apart of a robot standing in a square room (ranges to its walls)."""
    bearings = np.linspace(-np.pi / 2, np.pi / 2, beams)
    with np.errstate(divide="ignore"):
        ranges = np.minimum(3.0 / np.maximum(np.cos(bearings), 1e-9), 2.0 / np.abs(np.sin(bearings)))
    return [Record(Scan(np.minimum(ranges, 7.9), -np.pi / 2, np.pi / (beams - 1), 0.0, 8.0, stamp=0.1 * k))
            for k in range(n)]


def test_an_endless_iterator_ends_the_run_at_the_scan_bound(monkeypatch: pytest.MonkeyPatch) -> None:
    """Defect: run_slam(itertools.repeat(record)) never ended, its trajectory growing; then an
    iterator past a beam bound was refused after all the work (a 1081-beam bag at 40 Hz after
    52 min), its result lost. An iterator is now read up to MAX_SLAM_SCANS (made 20 here) and the
    run ends there, its result returned with a one-line SlamLimitWarning."""
    import warnings

    import slam.run
    from slam.run import SlamLimitWarning

    assert slam.run.MAX_SLAM_SCANS == 24 * 3600 * 75  # 24 h of an LMS200 at 75 Hz
    rec = _records(1)[0]
    monkeypatch.setattr(slam.run, "MAX_SLAM_SCANS", 20)
    read = itertools.count()

    def endless():  # one scan again and again, 0.1 s apart (all of one stamp is refused: same_stamp_problem)
        for _ in itertools.repeat(None):
            k = next(read)
            assert k < 100, "read on past the bound"
            yield dataclasses.replace(rec, scan=rec.scan.replace(stamp=0.1 * k))

    for preset in ("default", "paper"):
        with pytest.warns(SlamLimitWarning, match=r"^records: the run ended after 20 scans \(slam.run.MAX_SLAM_SCANS"
                                                  r".*; the iterator's scans after them, if any, were not read$"):
            result = run_slam(endless(), SlamConfig(preset=preset))
        assert result.trajectory.shape == (20, 4)
    # a list longer than the bound is refused before any work; one within it is taken whole
    records = _records(21)
    with pytest.raises(SlamInputError, match=r"^records: 21 scans, more than a run reads \(slam.run.MAX_SLAM_SCANS, 20"):
        run_slam(records, SlamConfig(preset="paper"))
    records = records[:20]
    with warnings.catch_warnings():
        warnings.simplefilter("error", SlamLimitWarning)
        assert run_slam(records, SlamConfig(preset="paper")).trajectory.shape == (20, 4)
        # max_scans reads no further than it says, silently, whatever the bound
        timed = (dataclasses.replace(rec, scan=rec.scan.replace(stamp=0.1 * k)) for k in itertools.count())
        assert run_slam(timed, SlamConfig(preset="paper"), max_scans=30).trajectory.shape == (30, 4)
        it = iter(records)
        assert run_slam(it, SlamConfig(preset="paper"), max_scans=5).trajectory.shape == (5, 4)
        assert next(it) is records[5]  # the source is not read past max_scans
        # a count past sys.maxsize is no islice count (a raw ValueError): it reads the whole source
        assert run_slam(records[:3], SlamConfig(preset="paper"), max_scans=2**63).trajectory.shape == (3, 4)
    for bad in (0, -1, True, 2.5, "3", -10**5000):  # the last one's repr (> 4,300 digits) raised inside the message
        with pytest.raises(SlamInputError, match=r"^max_scans: must be an integer >= 1 \(or None\), got "):
            run_slam(records, max_scans=bad)


def _many_lines(m: int, seed: int = 0):
    """Observations of ``m`` distinct short lines (rho 1-20 m, lengths 0.3-3 m) in the sensor frame."""
    from slam.observations import Observations

    rng = np.random.default_rng(seed)
    rho, alpha, length = rng.uniform(1, 20, m), rng.uniform(-np.pi, np.pi, m), rng.uniform(0.3, 3, m)
    foot = np.column_stack((rho * np.cos(alpha), rho * np.sin(alpha)))
    along = np.column_stack((-np.sin(alpha), np.cos(alpha))) * (length / 2)[:, None]
    ends = np.hstack((foot - along, foot + along))
    cov = np.tile(np.diag([0.02**2, 0.01**2]), (m, 1, 1))
    return Observations(lines=np.column_stack((rho, alpha)), line_cov=cov, line_ends=ends), length


def test_a_scan_of_very_many_lines_is_observed_up_to_max_lines() -> None:
    """Defect: the paper preset's filter took every line of a step: 20,000 lines ran over 60 s,
    growing the state toward a 12.8 GB covariance. Now it observes the longest
    observations.max_lines (100) of them, says how many it left, and the step is quick."""
    import time

    from slam.filter import SlamFilter
    from slam.run import SlamLimitWarning, run_observations

    obs, length = _many_lines(20_000)
    f = SlamFilter(SlamConfig(preset="paper"))
    t0 = time.perf_counter()
    info = f.step(0.0, obs)
    assert time.perf_counter() - t0 < 10  # ~0.1 s; the old code did not finish in 60 s
    assert info.n_unobserved == 19_900 and info.n_new == len(f.landmarks) == 100
    assert f.ekf.P.shape == (205, 205)
    # the landmarks are the 100 longest lines (the filter starts at the origin: a line's landmark is its observation)
    longest = np.sort(np.argsort(-length)[:100])
    got = f.ekf.x[5:, 0].reshape(-1, 2)
    assert np.allclose(got[:, 0], obs.lines[longest, 0]) and np.allclose(np.cos(got[:, 1] - obs.lines[longest, 1]), 1)
    # the map's bound: 30 landmarks, the other 70 lines start none; both bounds warn once a run
    small, _ = _many_lines(100, seed=1)
    cfg = SlamConfig(preset="paper", landmarks={"max_landmarks": 30}, observations={"max_lines": 60})
    with pytest.warns(SlamLimitWarning) as seen:
        result = run_observations([0.0, 0.1], [small, small], cfg)
    d = result.diagnostics
    assert d["n_unobserved"].tolist() == [40, 40] and d["n_unadded"][0] == 30 and d["n_landmarks"].max() == 30
    assert [str(w.message) for w in seen] == [
        "80 lines or corners were not observed in 2 of 2 scans: beyond observations.max_lines (60, a bound of the "
        "filter's time and memory)",
        f"{int(d['n_unadded'].sum())} observations started no landmark in {int(np.count_nonzero(d['n_unadded']))} of 2 "
        "scans: beyond landmarks.max_landmarks (30, a bound of the filter's time and memory)"]
    with pytest.raises(SlamConfigError, match=r"^landmarks.max_landmarks: "):
        SlamConfig(preset="paper", landmarks={"max_landmarks": 10_001})


def test_run_steps_ends_an_endless_iterator_and_run_observations_refuses_it(monkeypatch: pytest.MonkeyPatch) -> None:
    """Fuzzing: run_observations(itertools.count(), itertools.repeat(obs)) listed the stamps until
    memory ran out (a MemoryError under a 2 GB limit); run_steps of an endless generator ran for
    ever. run_steps now reads an iterator up to MAX_SLAM_SCANS (made 10 here) and ends the run
    there with a SlamLimitWarning; run_observations, which lists its inputs first, refuses one
    longer (and a list longer), before any work."""
    import slam.run
    from slam import run_observations, run_steps
    from slam.observations import Observations
    from slam.run import SlamLimitWarning

    monkeypatch.setattr(slam.run, "MAX_SLAM_SCANS", 10)
    obs = Observations()
    with pytest.raises(SlamInputError, match=r"^stamps: an iterator or generator that yielded more than 10 items"):
        run_observations(itertools.count(), itertools.repeat(obs))
    with pytest.raises(SlamInputError, match=r"^stamps: 11 scans, more than a run reads"):
        run_observations([0.1 * k for k in range(11)], [obs] * 11)
    with pytest.warns(SlamLimitWarning, match=r"^steps: the run ended after 10 scans"):
        result = run_steps(((0.1 * k, obs, None, None) for k in itertools.count()), SlamConfig(preset="paper"))
    assert result.trajectory.shape == (10, 4)
    with pytest.raises(SlamInputError, match=r"^steps: must be an iterable \(one item a scan\), got int"):
        run_steps(5)
    with pytest.raises(SlamInputError, match=r"^steps: 12 scans, more than a run reads"):
        run_steps([(0.1 * k, obs, None, None) for k in range(12)], SlamConfig(preset="paper"))
    assert run_observations([0.1 * k for k in range(10)], [obs] * 10, SlamConfig(preset="paper")).trajectory.shape == (10, 4)


@pytest.mark.parametrize("step, got", [
    ("pair", "2 items"),          # (stamp, observations): was "ValueError: not enough values to unpack (expected 4, got 2)"
    (0.0, "float"),               # was "TypeError: cannot unpack non-iterable float object"
    (None, "NoneType"),
    ("abcd", "str"),              # four characters were unpacked as its four items
    (np.zeros((2, 2)), "ndarray"),  # an array step is 1-d
    (np.array(5.0), "ndarray"),     # 0-d: "TypeError: len() of unsized object" (review)
])
def test_run_steps_names_a_step_that_is_no_four_items(step: object, got: str) -> None:
    """Fuzz round 5: a step of run_steps that was no (stamp, observations, odometry, truth) was a raw
    ValueError or TypeError from the unpacking; now a SlamInputError naming the step. A step given
    as a list or a 1-d object array of four items still runs."""
    from slam import run_steps
    from slam.observations import Observations

    obs = Observations()
    good = (0.0, obs, None, None)
    with pytest.raises(SlamInputError, match=rf"^steps\[1\]: must be a tuple \(stamp s, slam.Observations, odometry "
                                             rf"pose or None, true pose or None\), got {got}$"):
        run_steps([good, (0.1, obs) if isinstance(step, str) and step == "pair" else step], SlamConfig(preset="paper"))
    row = np.empty(4, object)
    row[:] = [0.1, obs, None, None]
    assert run_steps([list(good), row], SlamConfig(preset="paper")).trajectory.shape == (2, 4)


def test_tentative_landmarks_pruned_in_a_scan_make_room_in_that_scan() -> None:
    """Review: the map's room was counted before the scan's pruning, so a full map of tentative
    landmarks pruned in that scan still refused its new lines (and ended the scan empty). Pruning
    now comes first: 30 landmarks of a first scan, not seen again within tentative_window (1 scan), give
    their room to the second scan's 30 other lines."""
    import dataclasses

    from slam.filter import SlamFilter

    first, _ = _many_lines(30, seed=1)
    second = dataclasses.replace(first, lines=first.lines + [25.0, 0.0])  # 25 m farther: no line pairs with the first's
    f = SlamFilter(SlamConfig(preset="paper", landmarks={"max_landmarks": 30, "tentative_window": 1, "confirm_hits": 2}))
    assert f.step(0.0, first).n_new == 30
    info = f.step(0.1, second)
    assert info.n_matched == 0 and info.n_unadded == 0 and info.n_new == 30 and len(f.landmarks) == 30
    assert np.allclose(f.ekf.x[5:, 0].reshape(-1, 2)[:, 0], second.lines[:, 0], atol=0.5)


def test_column_keeps_per_scan_values_as_a_list_would() -> None:
    """slam.run.Column (the paper preset's per-scan store): its last rows and its whole are those of
    a list of the same values, np.array'd, across block bounds (blocks of 3 rows here)."""
    from slam.run import Column

    rng = np.random.default_rng(7)
    values = [rng.normal(size=(3, 3)) for _ in range(11)]
    column = Column(np.float64, (3, 3))
    column.BLOCK_ROWS = 3
    for n, value in enumerate(values, start=1):
        column.append(value)
        for k in (1, 2, 3, 4, 7, 20):
            assert np.array_equal(column.last(k), np.array(values[:n][-k:])), (n, k)
    assert column.size == 11
    whole = column.taken()
    assert whole.dtype == np.float64 and np.array_equal(whole, np.array(values))
    assert column.size == 0 and column.taken().shape == (0, 3, 3)
    flags = Column(np.bool_)
    for flag in (True, False, True):
        flags.append(flag)
    assert flags.taken().tolist() == [True, False, True]


def test_run_steps_keeps_near_its_result_s_size_a_scan(monkeypatch: pytest.MonkeyPatch) -> None:
    """Defect: run_steps (paper preset) kept its per-scan poses, covariances and diagnostics in
    Python lists, ~710-730 B a scan at its peak (tracemalloc) for a result of 185 B a scan: 4.7 GB at
    MAX_SLAM_SCANS. They are now numpy blocks (of 64 rows here, so that 1,000 scans measure the
    growth): the peak grows by under twice the result's size a scan."""
    import tracemalloc

    import slam.run
    from slam.observations import Observations

    monkeypatch.setattr(slam.run.Column, "BLOCK_ROWS", 64)
    config = SlamConfig.from_dict({"preset": "paper"})
    obs = Observations()

    def measured(n: int) -> tuple[int, int]:
        tracemalloc.start()
        try:
            result = slam.run.run_steps(((0.1 * k, obs, None, (0.01 * k, 0.0, 0.0)) for k in range(n)), config)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        arrays = [result.trajectory, result.covariances] + [v for v in result.diagnostics.values() if isinstance(v, np.ndarray)]
        return peak, sum(a.nbytes for a in arrays)

    measured(20)  # the filter's first-run caches (numba, imports) out of the measure
    (peak_a, size_a), (peak_b, size_b) = measured(300), measured(1300)
    per_scan = (size_b - size_a) / 1000
    assert per_scan >= 180  # pose 32 B, covariance 72 B, 11 diagnostics
    assert (peak_b - peak_a) / 1000 < 2 * per_scan, ((peak_b - peak_a) / 1000, per_scan)


def test_lmsbench_slams_runs_say_a_bound_they_met_once_naming_each_run(tmp_path) -> None:
    """`slam --preset paper` with an extractor of more lines a scan than observations.max_lines said
    "N lines or corners were not observed ..." twice, the same line, once for the run and once for its
    paper preset (odometry) baseline, naming neither: now each run's own line, naming it, as it ends."""
    import warnings

    from lms200 import write_log
    from slam.run import SlamBoundWarning, bounds_met

    from experiments.slamrun import load_input, run

    log = tmp_path / "room.clf"
    write_log(log, [Record(r.scan, odom=(0.0, 0.0, 0.0), truth=(0.0, 0.0, 0.0)) for r in _records(12)])
    config = SlamConfig(preset="paper", observations={"max_lines": 1})
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        done = run(load_input(log), config, progress=False)
    bound, = bounds_met(done.result.diagnostics, config)  # the room's walls: more than one line a scan
    assert bound.scans == 12 and bound.count >= 12
    # the baseline is the same filter driven by the (standing) odometry: its own counts, from its own run
    with pytest.warns(SlamBoundWarning, match=r"^\d+ lines or corners were not observed in \d+ of 12 scans: beyond "):
        odo = run_slam(load_input(log).records, SlamConfig(preset="paper", observations={"max_lines": 1},
                                                          motion={"use_odometry": True}))  # run_slam says its own
    other, = bounds_met(odo.diagnostics, config)
    beyond = "beyond observations.max_lines (1, a bound of the filter's time and memory)"
    assert [str(w.message) for w in said if issubclass(w.category, SlamBoundWarning)] == [
        f"{bound.count:,} lines or corners were not observed in 12 of 12 scans of this run (paper preset): {beyond}",
        f"{other.count:,} lines or corners were not observed in {other.scans} of 12 scans of the paper preset "
        f"(odometry) baseline: {beyond}"]


def test_lmsbench_slam_says_its_runs_bound_before_a_baseline_fails(tmp_path, monkeypatch) -> None:
    """The run's bound was said only after every baseline had run: a baseline that failed (or a Ctrl-C
    during one, 78 s on MIT CSAIL) lost it, though the run's files were written."""
    import warnings

    from lms200 import write_log
    from slam.run import SlamBoundWarning

    import experiments.slamrun as slamrun

    log = tmp_path / "room.clf"
    write_log(log, [Record(r.scan, odom=(0.0, 0.0, 0.0), truth=(0.0, 0.0, 0.0)) for r in _records(12)])
    config = SlamConfig(preset="paper", observations={"max_lines": 1})
    real = slamrun._quiet_bounds

    def baseline_stops(records, cfg):  # the run itself, then a stop in its odometry baseline
        if cfg.motion.use_odometry:
            raise KeyboardInterrupt
        return real(records, cfg)

    monkeypatch.setattr(slamrun, "_quiet_bounds", baseline_stops)
    with warnings.catch_warnings(record=True) as said, pytest.raises(KeyboardInterrupt):
        warnings.simplefilter("always")
        slamrun.run(slamrun.load_input(log), config, progress=False, out=tmp_path / "out")
    assert [str(w.message).split(" of ")[1:3] for w in said if issubclass(w.category, SlamBoundWarning)] == [
        ["12 scans", "this run (paper preset): beyond observations.max_lines (1, a bound"]]
    assert (tmp_path / "out" / "trajectory.tum").is_file()


def test_run_scan_slam_keeps_near_its_result_s_size_a_scan(monkeypatch: pytest.MonkeyPatch) -> None:
    """Defect: the default preset kept every scan's ScanStep record, stamp and truth in Python lists
    and its anchor (a tuple of an int and two arrays), ~990 B a scan at its peak (tracemalloc) for a
    result of 163 B a scan: 6.4 GB at MAX_SLAM_SCANS. They are now numpy blocks (of 64 rows here;
    the scans have no valid beam, so no matching: cheap steps that keep as much a scan as any),
    and the degenerate-drift check is fed a step at a time: the peak grows by under 2.5 times the
    result's size a scan (356 B). The result is that of the lists: tests/test_slam_degenerate.py, and
    MIT CSAIL's trajectory, keyframes and map were byte-identical before and after."""
    import tracemalloc

    import slam.run

    monkeypatch.setattr(slam.run.Column, "BLOCK_ROWS", 64)
    config = SlamConfig()

    def measured(n: int) -> tuple[int, int]:
        records = (Record(Scan(np.full(8, np.nan), -0.1, 0.01, 0.0, 8.0, stamp=0.1 * k), truth=(0.01 * k, 0.0, 0.0))
                   for k in range(n))
        tracemalloc.start()
        try:
            result = run_slam(records, config)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        arrays = [result.trajectory, result.covariances] + [v for v in result.diagnostics.values() if isinstance(v, np.ndarray)]
        return peak, sum(a.nbytes for a in arrays)

    measured(20)  # first-run caches out of the measure
    (peak_a, size_a), (peak_b, size_b) = measured(300), measured(1300)
    per_scan = (size_b - size_a) / 1000
    assert per_scan >= 160  # pose and stamp 32 B, covariance 72 B, 11 diagnostics, NEES
    assert (peak_b - peak_a) / 1000 < 2.5 * per_scan, ((peak_b - peak_a) / 1000, per_scan)


def test_scanslam_anchors_and_covariances_read_as_the_lists_they_were() -> None:
    """ScanSlam is public (docs/slam.md: harnesses on ScanSlam.step): keeping its per-scan anchors and
    match covariances in numpy blocks removed ``anchors`` and made ``covariances`` a Column (no len, no
    indexing). Both read again as lists of the same values and types: (int key, (3,) pose in the
    keyframe's frame) and (3, 3) arrays, the first scan's (0, zeros) and zeros; here the sensor moves
    5 cm along x in a 6 m x 5 m box, so the second scan's pose in the first keyframe's is (0.05, 0, 0)."""
    from slam.scanslam import ScanSlam

    b = np.deg2rad(0.5) * (np.arange(361) - 180)
    r = np.minimum(3.0 / np.maximum(np.abs(np.cos(b)), 1e-3), 2.5 / np.maximum(np.abs(np.sin(b)), 1e-3))
    s = ScanSlam()
    for i in range(2):
        s.step(0.2 * i, np.c_[r * np.cos(b) - 0.05 * i, r * np.sin(b)])
    covs, anchors = s.covariances, s.anchors
    assert isinstance(covs, list) and len(covs) == 2 and isinstance(anchors, list) and len(anchors) == 2
    assert all(type(k) is int and k == 0 and rel.shape == (3,) and rel.dtype == np.float64 for k, rel in anchors)
    np.testing.assert_array_equal(anchors[0][1], np.zeros(3))
    np.testing.assert_allclose(anchors[-1][1], [0.05, 0.0, 0.0], atol=1e-6)
    np.testing.assert_array_equal(covs[0], np.zeros((3, 3)))
    last = covs[-1]
    assert last.shape == (3, 3) and last.dtype == np.float64
    np.testing.assert_allclose(last, last.T, rtol=0, atol=1e-9 * np.abs(last).max())
    assert np.all(np.linalg.eigvalsh(last) > 0)  # a match's covariance, not the first scan's zeros
    covs[-1][:] = 1.0  # a copy: the run's own values stay
    assert not np.array_equal(s.covariances[-1], covs[-1])
