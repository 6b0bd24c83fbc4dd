"""Trajectory and map metrics on hand-built cases with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from lms200.errors import LmsbenchWarning
from lms200 import LmsbenchError, LogFormatError
from slam.metrics import Alignment2D, align_2d, ate, interpolate_poses, map_error, read_relations, relations_error, rpe


def square_path(n: int = 81) -> np.ndarray:
    """A 4 m x 4 m square driven at 1 m/s, heading along the path: (n, 4) t, x, y, theta."""
    s = np.linspace(0, 16, n)
    x = np.interp(s, [0, 4, 8, 12, 16], [0, 4, 4, 0, 0])
    y = np.interp(s, [0, 4, 8, 12, 16], [0, 0, 4, 4, 0])
    th = np.select([s < 4, s < 8, s < 12], [0.0, np.pi / 2, np.pi], -np.pi / 2)
    return np.column_stack((s, x, y, th))


def transformed(traj: np.ndarray, rot: float, t: tuple[float, float]) -> np.ndarray:
    c, s = np.cos(rot), np.sin(rot)
    xy = traj[:, 1:3] @ np.array([[c, s], [-s, c]]) + t
    return np.column_stack((traj[:, 0], xy, traj[:, 3] + rot))


def test_ate_is_zero_for_a_rigidly_moved_copy_and_recovers_the_motion():
    truth = square_path()
    est = transformed(truth, 0.7, (3.0, -2.0))
    a = ate(est, truth)
    assert a.rmse < 1e-9 and a.heading_rmse < 1e-9 and a.n == truth.shape[0]
    assert abs(a.rotation + 0.7) < 1e-9  # aligns est back onto truth
    assert not a.mirrored


def test_ate_of_a_constant_offset_without_alignment():
    truth = square_path()
    est = truth.copy()
    est[:, 1] += 0.3
    a = ate(est, truth, align=False)
    assert a.rmse == pytest.approx(0.3) and a.max == pytest.approx(0.3)
    assert ate(est, truth).rmse < 1e-9  # a pure shift aligns away


@pytest.mark.parametrize("align", ["no", "false", 0, None, 1.0])
def test_ate_refuses_an_align_that_is_no_bool(align):
    """`ate(est, truth, align="no")` aligned (the text is true): an offset of 0.3 m scored 0."""
    truth = square_path()
    est = truth.copy()
    est[:, 1] += 0.3
    with pytest.raises(LmsbenchError, match=r"^ate: align must be True or False, got "):
        ate(est, truth, align=align)
    assert ate(est, truth, align=np.bool_(False)).rmse == pytest.approx(0.3)  # numpy's bool is one


def test_ate_detects_a_mirrored_estimate():
    truth = square_path()
    est = truth.copy()
    est[:, 2] *= -1  # mirror y: a 3-D alignment could fold this onto the truth
    est[:, 3] *= -1
    a = ate(est, truth)
    assert a.mirrored and a.mirror_rmse < 1e-9 and a.rmse > 0.5


def test_ate_interpolates_the_truth_at_the_estimate_stamps():
    truth = square_path(17)  # 1 s steps
    est = np.array([[0.5, 0.5, 0.0, 0.0], [1.25, 1.25, 0.0, 0.0], [4.5, 4.0, 0.5, np.pi / 2]])
    assert ate(est, truth, align=False).rmse < 1e-12


def test_rpe_counts_errors_per_distance():
    truth = square_path(161)
    est = truth.copy()
    est[:, 1:3] *= 1.1  # 10 % scale error: 0.1 m per metre travelled on straight stretches
    r = rpe(est, truth, delta=1.0)
    assert r.n > 100
    assert r.trans_mean == pytest.approx(0.1, abs=0.02)
    assert r.rot_mean < 1e-9



@pytest.mark.parametrize("delta", [1e-300, 1e-17])
def test_rpe_of_a_delta_below_the_floats_spacing_pairs_neighbours_not_a_pose_with_itself(delta: float) -> None:
    """A delta lost in `travelled + delta` (below the spacing of floats at the distance travelled)
    paired each pose with itself: n 161 of 161 poses and errors of 0 for a 10 % scale error (fuzz4).
    Any delta down to that spacing pairs each pose with the next pose that moved, as 1e-6 m does."""
    truth = square_path(161)
    est = truth.copy()
    est[:, 1:3] *= 1.1
    ref = rpe(est, truth, delta=1e-6)
    r = rpe(est, truth, delta=delta)
    assert r.n == ref.n == 160
    assert r.trans_mean == pytest.approx(ref.trans_mean) and r.trans_mean == pytest.approx(0.1 * 0.1, rel=0.05)

def test_map_error_of_shifted_walls():
    walls = np.array([[0, 0, 10, 0], [10, 0, 10, 5], [10, 5, 0, 5.0]])
    lines = np.array([[1, 0.05, 8, 0.05], [10.02, 1, 10.02, 4], [3, 5, 2, 5], [5, 2.5, 5.5, 2.6]])
    e = map_error(lines, walls)
    assert e.n_lines == 4 and e.matched == 3  # the free-standing segment matches no wall
    assert e.distance_mean == pytest.approx((0.05 * 2 + 0.02 * 2) / 6)
    assert e.wall_coverage == pytest.approx((7 + 3 + 1) / 25)
    # the same map in a frame rotated by -0.3 rad and shifted: the alignment brings it back
    in_slam_frame = _invert(lines, 0.3, (1, 2))
    assert map_error(in_slam_frame, walls).matched < 3
    back = map_error(in_slam_frame, walls, Alignment2D(0.3, (1, 2)))
    assert back.matched == 3 and back.distance_mean == pytest.approx(e.distance_mean)


def _invert(seg, rot, t):
    """Segments moved by the inverse of Alignment2D(rot, t)."""
    c, s = np.cos(rot), np.sin(rot)
    R = np.array([[c, -s], [s, c]])
    return np.column_stack(((seg[:, :2] - t) @ R, (seg[:, 2:] - t) @ R))


def test_relations_metric_on_a_hand_built_case(tmp_path):
    traj = np.array([[0.0, 0, 0, 0], [1.0, 1, 0, np.pi / 2], [2.0, 1, 1, np.pi / 2]])
    # true motion 0 -> 1: 1 m ahead and a 90 deg turn; our estimate has it exactly
    # true motion 1 -> 2: 1.1 m ahead (our 1.0 is 0.1 short), no turn; relation at 1.5 s interpolated
    p = tmp_path / "r.relations"
    p.write_text("0 1 1 0 0 0 0 1.5707963267948966\n1 2 1.1 0 0 0 0 0.1\n0.5 1.5 0.5 0 0 0 0 0\n7 8 1 0 0 0 0 0\n")
    rel = read_relations(p)
    r = relations_error(traj, rel)
    assert r.n == 3 and r.n_skipped == 1
    errs = np.array([0.0, 0.1, np.hypot(0.5 - 0.5, 0.5 - 0.0)])
    # 0.5 s: (0.5, 0, 45 deg); 1.5 s: (1, 0.5, 90 deg): relative = (0.5 cos45 + 0.5 sin45... ) computed below
    a, b = np.array([0.5, 0.0, np.pi / 4]), np.array([1.0, 0.5, np.pi / 2])
    d = b[:2] - a[:2]
    rel3 = np.array([np.cos(a[2]) * d[0] + np.sin(a[2]) * d[1], -np.sin(a[2]) * d[0] + np.cos(a[2]) * d[1]])
    errs[2] = np.hypot(rel3[0] - 0.5, rel3[1])
    assert r.trans_mean == pytest.approx(errs.mean())
    assert r.rot_mean_deg == pytest.approx((0 + np.degrees(0.1) + 45.0) / 3)


def test_relations_reader_errors_name_the_line(tmp_path):
    p = tmp_path / "bad.relations"
    p.write_text("0 1 1 0 0 0 0 0\n0 1 x 0 0 0 0 0\n")
    with pytest.raises(LogFormatError, match=":2"):
        read_relations(p)
    p.write_text("0 1 1 0 0\n")
    with pytest.raises(LogFormatError, match="8 numbers"):
        read_relations(p)
    # a nan made the mean error null after the run, silently; an empty file said "none of the 0
    # relations falls inside the run's time span" after it
    p.write_text("0 1 1 0 0 0 0 0\n# c\n1 2 nan 0 0 0 0 0\n")
    with pytest.raises(LogFormatError, match=r"bad\.relations:3: relation row has a non-finite number: '1 2 nan"):
        read_relations(p)
    p.write_text("# only a comment\n\n")
    with pytest.raises(LmsbenchError, match=r"bad\.relations: no relations \(t1 t2 x y z roll pitch yaw a line\)"):
        read_relations(p)


def test_a_tum_trajectory_given_as_relations_is_refused_naming_both_formats(tmp_path):
    """`slam SIM --relations SIM/groundtruth.tum` read the TUM rows (t x y z qx qy qz qw, 8 numbers as
    a relation's) as relations from t to x, and scored the run 1.42 m against them, exit 0."""
    from lms200.tum import write_tum

    truth = square_path()
    p = tmp_path / "groundtruth.tum"
    write_tum(p, truth[:, 0], truth[:, 1:])
    with pytest.raises(LmsbenchError, match=r"groundtruth\.tum: a TUM trajectory \(t x y z qx qy qz qw: the last four "
                                            r"numbers of every row a unit quaternion\), not a relations file"):
        read_relations(p)
    # a trajectory whose x goes negative (a slam run's trajectory.tum) failed at that row's "t2" first (round 7:
    # "relation row's t2 -0.000217 s is outside 0 .. 2^32 s")
    write_tum(p, np.arange(3.0), np.array([[0.0, 0.0, 0.0], [-0.001, 0.0, 0.01], [0.002, 0.0, 0.02]]))
    with pytest.raises(LmsbenchError, match=r"groundtruth\.tum: a TUM trajectory \(t x y z qx qy qz qw"):
        read_relations(p)
    for row in ("0 -1 1 0 0 0 0 0.3\n", "5 -3 1 0 0 0 0 1.0\n"):  # a relation's own bad stamp is said as it was,
        p.write_text(row)  # also where its yaw of 1 rad makes (z, roll, pitch, yaw) of norm 1 (the review)
        with pytest.raises(LogFormatError, match=r"groundtruth\.tum:1: relation row's t2 -[13].000000 s is outside"):
            read_relations(p)
    # relations whose yaw is 1 rad (z, roll, pitch 0) and relations with a 3-D part still read (the climb of
    # z = 0.5 m over 1 m, 26.6 deg, said: tests/test_review_silent_passes.py)
    p.write_text("0 1 1 0 0 0 0 1.0\n1 2 1 0 0 0 0 -1.0\n2 3 1 0 0.5 0 0 0.3\n")
    with pytest.warns(LmsbenchWarning, match=r"up to 26\.6 deg, line 3"):
        assert read_relations(p).tolist() == [[0, 1, 1, 0, 1.0], [1, 2, 1, 0, -1.0], [2, 3, 1, 0, 0.3]]


def test_interpolation_takes_the_short_way_round():
    traj = np.array([[0.0, 0, 0, 3.0], [1.0, 0, 0, -3.0]])
    pose, inside = interpolate_poses(traj, np.array([0.5, 2.0]))
    assert inside.tolist() == [True, False]
    assert abs(abs(pose[0, 2]) - np.pi) < 1e-9


# --- bad input, found by fuzzing the Python API (session 32) ----------------------------------------
@pytest.mark.parametrize("call, message", [
    # a (12, 3) trajectory (no stamps) was read by reshape(-1, 4) as nine garbled rows, silently
    (lambda t: ate(t[:12, 1:], t), r"estimate: must be a \(k, 4\) array \(t s, x m, y m, theta rad\), got shape \(12, 3\)"),
    (lambda t: rpe(t, t[:12, 1:]), r"truth: must be a \(k, 4\) array .*got shape \(12, 3\)"),
    (lambda t: ate(t, "abc"), r"truth: must be a \(k, 4\) array of real numbers .*got str"),  # numpy's ValueError
    (lambda t: ate(t, None), r"truth: must be a \(k, 4\) array of real numbers .*got NoneType"),
    (lambda t: ate(t, t[:0]), r"truth: has no poses"),  # IndexError
    (lambda t: ate(t, t[::-1]), r"truth: stamps must not decrease \(row 1: 15\.8 s after 16\.0 s\)"),  # a ValueError
    (lambda t: rpe(t[::-1], t), r"estimate: stamps must not decrease"),  # paired poses in reverse, silently
    (lambda t: ate(np.where(np.arange(4) == 0, np.nan, t), t), r"estimate: its stamps \(column 0\) must be finite; row 0"),
    (lambda t: ate(t, np.where(np.arange(4) == 1, np.nan, t)), r"truth: its poses must be finite; row 0 is not"),
    (lambda t: ate(t[:1], t), r"ate: fewer than 2 estimated poses"),  # a ValueError, not an LmsbenchError
    (lambda t: rpe(t, t, delta=0.0), r"delta: must be a finite number > 0 m of true travel, got 0\.0"),
    (lambda t: rpe(t, t, delta=float("nan")), r"delta: must be a finite number > 0 .*got nan"),
    (lambda t: rpe(t, t, delta="1"), r"delta: must be a finite number > 0 .*got '1'"),  # numpy's UFuncTypeError
    (lambda t: rpe(t, t, delta=10**400), r"delta: must be a finite number > 0 m of true travel, got 1000"),  # OverflowError
    (lambda t: rpe(t, t, pairs=None), r"pairs: must be one of every, evo, got None"),
    (lambda t: relations_error(t, np.array([[1.0, 2.0, 0.1, 0.0]])), r"relations: must be a \(k, 5\) array"),
    (lambda t: relations_error(t, np.array([[1.0, 2.0, np.nan, 0.0, 0.0]])), r"relations: must be finite .*row 0"),
    (lambda t: relations_error(t, np.array([[100.0, 200.0, 0.1, 0.0, 0.0]])), r"no relation falls inside"),
    (lambda t: interpolate_poses(t, "abc"), r"stamps: must be a \(k, 1\) array of real numbers \(s\), got str"),
    (lambda t: map_error(np.array([[0, 0, 1, 0]]), np.array([[0, 0, 0, 0]])), r"walls: every wall must have two distinct ends"),
    (lambda t: map_error(np.array([[0, 0, 1, 0]]), np.array([[0, 0, 2, 0]]), alignment=0.5),
     r"alignment: must be a slam.metrics.Alignment2D or None, got float"),  # AttributeError
    (lambda t: map_error(np.array([[0, 0, 1, 0]]), np.array([[0, 0, 2, 0]]), max_distance=None),
     r"max_distance: must be a finite number > 0 m, got None"),  # TypeError
    (lambda t: map_error(np.array([[0, 0, 1]]), np.array([[0, 0, 2, 0]])), r"map_segments: must be a \(k, 4\) array"),
    # align_2d (the Alignment2D map_error takes): fuzz round 6
    (lambda t: align_2d(None, t[:, 1:3]), r"est_xy: must be a \(k, 2\) array of real numbers \(x m, y m\), got NoneType"),
    (lambda t: align_2d(t[:3, 1:3], t[:4, 1:3]), r"est_xy and true_xy: must hold one point each .*got 3 and 4"),  # matmul ValueError
    (lambda t: align_2d(t[:0, 1:3], t[:0, 1:3]), r"est_xy: has no points"),  # an alignment of nan, RuntimeWarnings
    (lambda t: align_2d(t[:, 1:3], np.where(np.arange(2) == 0, np.nan, t[:, 1:3])), r"true_xy: must be finite .*row 0"),  # LinAlgError
    (lambda t: align_2d(t[:, 1:3], t[:, 1:3] + 1e300), r"^true_xy: row 0: x and y must be within \+-1e\+09 m, got \(1e\+300, 1e\+300\) m$"),
])
def test_metrics_name_a_bad_argument(call, message: str) -> None:
    """InputError, or ConfigError for the numbers (features.baselines.checks.positive): both are
    LmsbenchErrors and ValueErrors."""
    with pytest.raises(LmsbenchError, match=message) as info:
        call(square_path())
    assert isinstance(info.value, ValueError)


@pytest.mark.parametrize("kwargs, message", [
    ({"delta": "TRAJ"}, r"^delta: must be a finite number > 0 m of true travel, got array\(\[\[0\., 0\., 0\., 0\.\], \[1\., "),
    ({"pairs": "TRAJ"}, r"^pairs: must be one of every, evo, got array\(\[\[0\., 0\., 0\., 0\.\], \[1\., "),
])
def test_metrics_errors_quote_an_array_on_one_line(kwargs: dict, message: str) -> None:
    """A trajectory given as rpe's delta or pairs (arguments swapped) was quoted by its repr, one line
    a row: a multi-line error from the API (fuzzing, 2026-12-07)."""
    traj = np.column_stack((np.arange(10.0), np.arange(10.0), np.zeros(10), np.zeros(10)))
    with pytest.raises(LmsbenchError, match=message) as info:
        rpe(traj, traj, **{k: traj for k in kwargs})
    assert "\n" not in str(info.value) and len(str(info.value)) < 300, str(info.value)


def test_a_heading_beyond_1e6_rad_is_refused_by_the_relations_reader_and_the_metrics(tmp_path) -> None:
    """fuzz4: a relation's yaw of 1e300 rad scored 138.6 deg, and an estimate's heading of 1e300 a heading
    error of noise, exit 0; such a float holds no angle. 1e6 rad (160,000 turns) is read as before."""
    rel = tmp_path / "r.relations"
    rel.write_text("1 2 0.1 0 0 0 0 1e6\n3 4 0.1 0 0 0 0 1e300\n")
    with pytest.raises(LogFormatError, match=r"r\.relations:2: relation row's yaw 1e\+300 rad lies beyond \+-1e\+06 rad"):
        read_relations(rel)
    rel.write_text("1 2 0.1 0 0 0 0 1e6\n")
    assert read_relations(rel)[0, 4] == 1e6
    truth = square_path()
    est = truth.copy()
    est[3, 3] = -1e300
    for metric in (ate, rpe):
        with pytest.raises(LmsbenchError, match=r"^estimate: row 3: pose's heading -1e\+300 rad lies beyond \+-1e\+06 rad"):
            metric(est, truth)

def test_ate_of_a_lost_run_is_nan_not_a_linalg_error() -> None:
    """A run whose estimate went nan (an unhealthy paper-preset run) scores nan; the SVD raised
    numpy's LinAlgError ("SVD did not converge")."""
    truth = square_path()
    est = truth.copy()
    est[5, 1] = np.nan
    a = ate(est, truth)
    assert np.isnan(a.rmse) and np.isnan(a.rotation) and a.n == truth.shape[0] and not a.mirrored
    assert ate(truth, truth).rmse == pytest.approx(0.0, abs=1e-12)


def test_tum_and_relations_readers_bound_a_line_and_refuse_underscores_and_huge_coordinates(tmp_path):
    """Found by fuzzing `lmsbench slam` inputs: a TUM or relations file of zeros (or binary data)
    with no line break was read as one line, whole: a 3 GB one ended in MemoryError ("internal
    error", exit 1); ``1_000`` was read as 1000 (Python's float(), which neither evo nor numpy
    takes); a TUM row at x = 1e300 m overflowed the metrics' squares (RuntimeWarnings, an error of
    inf, exit 0). Each is now a LogFormatError naming the file and line."""
    import tracemalloc

    from lms200.logs import MAX_ROW_CHARS
    from lms200.tum import read_tum

    zeros = tmp_path / "zeros.tum"
    with open(zeros, "wb") as f:
        f.write(b"0" * 4096)  # digits first: a NUL among the first 4 KB is a binary file, said at once (below)
        f.truncate(64 * MAX_ROW_CHARS)  # 64 MiB in all, no line break
    for read in (read_tum, read_relations):
        tracemalloc.start()
        with pytest.raises(LogFormatError, match=r"zeros\.tum:1: longer than 1,048,576 characters: not a text file of rows"):
            read(zeros)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        assert peak < 8 * MAX_ROW_CHARS  # old: the whole file, 64 MiB (and up) as one line
    with open(tmp_path / "nuls.tum", "wb") as f:
        f.truncate(64 * MAX_ROW_CHARS)
    with pytest.raises(LogFormatError, match=r"nuls\.tum: a binary file, not a TUM trajectory$"):
        read_tum(tmp_path / "nuls.tum")
    tum = tmp_path / "t.tum"
    tum.write_text("0 0 0 0 0 0 0 1\n1_000 1 0 0 0 0 0 1\n")
    with pytest.raises(LogFormatError, match=r"t\.tum:2: TUM row has a non-number: '1_000 1 0 0 0 0 0 1'"):
        read_tum(tum)  # old: a pose at 1000 s
    tum.write_text("0 0 0 0 0 0 0 1\n1 1e300 0 0 0 0 0 1\n")
    with pytest.raises(LogFormatError, match=r"t\.tum:2: TUM row's pose \(1e\+300, 0\) m lies beyond \+-1e\+09 m"):
        read_tum(tum)
    tum.write_text("0 0 0 0 0 0 0 1\n1 -1e9 5.4e6 0 0 0 0 1\n")  # the bound itself, and a UTM northing, read
    assert read_tum(tum)[1][1].tolist() == [-1e9, 5.4e6, 0.0]
    rel = tmp_path / "r.relations"
    rel.write_text("0 1 1 0 0 0 0 0\n1 2 1_0 0 0 0 0 0\n")
    with pytest.raises(LogFormatError, match=r"r\.relations:2: relation row has a non-number: '1 2 1_0 0 0 0 0 0'"):
        read_relations(rel)  # old: a relation of 10 m
    rel.write_text("0 1 1 0 0 0 0 0\n1 2 1 -2e200 0 0 0 0\n")
    with pytest.raises(LogFormatError, match=r"r\.relations:2: relation row's motion \(1, -2e\+200\) m lies beyond \+-1e\+09 m"):
        read_relations(rel)


def test_tum_and_relations_files_saved_with_a_byte_order_mark_read_as_without_it(tmp_path):
    """Found by fuzzing: a TUM or relations file saved by a Windows editor (a UTF-8 byte-order mark
    before its first line) was refused: the mark read as three replacement characters, so a TUM
    header comment was 'rows need 8 entries ..., got 9' and a first row 'a non-number'. It is
    skipped, as the CARMEN reader skips it; a mark anywhere else is still a non-number."""
    from lms200.tum import read_tum

    bom = "\ufeff".encode()
    rows = b"1.0 0 0 0 0 0 0 1\n2.0 1 0.5 0 0 0 0.7071067811865476 0.7071067811865476\n"
    for text in (b"# t x y z qx qy qz qw\n" + rows, rows):
        tum = tmp_path / "bom.tum"
        tum.write_bytes(bom + text)
        stamps, poses = read_tum(tum)
        assert stamps.tolist() == [1.0, 2.0]
        assert poses.ravel().tolist() == pytest.approx([0.0, 0.0, 0.0, 1.0, 0.5, np.pi / 2])
    rel = tmp_path / "bom.relations"
    rel.write_bytes(bom + b"10 11 0.3 0.02 0 0 0 0.24\n")
    assert read_relations(rel).tolist() == [[10.0, 11.0, 0.3, 0.02, 0.24]]
    tum.write_bytes(rows + bom + rows)
    with pytest.raises(LogFormatError, match=r"bom\.tum:3: TUM row has a non-number"):
        read_tum(tum)


def _map_error_unchunked(seg: np.ndarray, walls: np.ndarray, max_angle: float = np.radians(10.0),
                         max_distance: float = 0.5) -> tuple[int, float, float, float, float]:
    """map_error's score as it was computed before the walls were chunked: (lines x walls) arrays
    whole (matched, distance_mean, distance_rmse, angle_mean, wall_coverage)."""
    wa, wb = walls[:, :2], walls[:, 2:]
    wlen = np.hypot(*(wb - wa).T)
    wd = (wb - wa) / wlen[:, None]
    wn = np.column_stack((-wd[:, 1], wd[:, 0]))
    sa, sb = seg[:, :2], seg[:, 2:]
    sd = (sb - sa) / np.maximum(np.hypot(*(sb - sa).T), 1e-12)[:, None]
    ang = np.arccos(np.clip(np.abs(sd @ wd.T), 0.0, 1.0))
    da = np.abs(np.einsum("kj,nj->kn", sa, wn) - np.sum(wa * wn, 1)[None, :])
    db = np.abs(np.einsum("kj,nj->kn", sb, wn) - np.sum(wa * wn, 1)[None, :])
    dist = 0.5 * (da + db)
    ta = np.einsum("kj,nj->kn", sa, wd) - np.sum(wa * wd, 1)[None, :]
    tb = np.einsum("kj,nj->kn", sb, wd) - np.sum(wa * wd, 1)[None, :]
    lo, hi = np.minimum(ta, tb), np.maximum(ta, tb)
    overlap = np.minimum(hi, wlen[None, :]) - np.maximum(lo, 0.0)
    cost = np.where((ang < max_angle) & (overlap > 0) & (dist < max_distance), dist, np.inf)
    best = np.argmin(cost, axis=1)
    k = np.nonzero(np.isfinite(cost[np.arange(seg.shape[0]), best]))[0]
    dk = np.concatenate((da[k, best[k]], db[k, best[k]]))
    covered = 0.0
    for w in np.unique(best[k]):
        total, end = 0.0, -np.inf
        for a, b in sorted((max(lo[i, w], 0.0), min(hi[i, w], wlen[w])) for i in k[best[k] == w]):
            if b > end:
                total, end = total + b - max(a, end), b
        covered += total
    return int(k.size), float(dk.mean()), float(np.sqrt(np.mean(dk**2))), float(ang[k, best[k]].mean()), \
        covered / wlen.sum()


def test_map_error_takes_the_walls_in_chunks_with_the_unchunked_result(monkeypatch) -> None:
    """A world.json may hold ~a million walls within its 32 MB: map_error's (lines x walls) arrays
    were unbounded. Chunked, the score is that of the whole arrays (the same wall wins a tie)."""
    import slam.metrics as metrics

    rng = np.random.default_rng(7)
    walls = rng.uniform(-5, 5, (300, 4))
    walls = np.vstack((walls, walls[:40]))  # duplicate walls: ties, the first of them wins
    lines = np.vstack((walls[:120] + rng.normal(0, 0.05, (120, 4)), rng.uniform(-5, 5, (30, 4)),
                       [[np.nan] * 4]))  # a lost run's nan line matches none
    whole = map_error(lines, walls)
    assert whole.matched > 100
    want = _map_error_unchunked(lines[:-1], walls)
    got = (whole.matched, whole.distance_mean, whole.distance_rmse, whole.angle_mean, whole.wall_coverage)
    assert got[0] == want[0] and got[1:] == pytest.approx(want[1:], rel=1e-12, abs=1e-12)
    for chunk in (lines.shape[0] * 7, 1):  # 7 walls a chunk; one wall a chunk
        monkeypatch.setattr(metrics, "MAP_ERROR_CHUNK", chunk)
        assert map_error(lines, walls) == whole  # to the last bit


def test_map_error_memory_is_bounded_by_the_chunk_not_the_wall_count() -> None:
    import tracemalloc

    rng = np.random.default_rng(3)
    walls = rng.uniform(-50, 50, (40_000, 4))
    lines = walls[:400] + 0.01
    tracemalloc.start()
    try:
        e = map_error(lines, walls)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert e.matched == 400
    # whole, each (400 x 40,000) array was 128 MB, and a dozen lived at once
    assert peak < 48 << 20, f"peak {peak / 2**20:.0f} MiB"


def test_a_position_beyond_the_readers_bound_is_refused_not_overflowed() -> None:
    """Fuzzing the Python API: ate of a trajectory at 1e300 m warned "overflow encountered in
    matmul / square" on stderr and scored an RMSE of inf (against itself 0.0); read_tum refuses
    such a row, and the metrics now refuse it alike, naming the trajectory and row."""
    import warnings

    from lms200 import InputError
    from slam.metrics import ate, rpe

    t = np.column_stack((np.arange(10.0), np.arange(10.0), np.zeros(10), np.zeros(10)))
    far = t.copy()
    far[3, 1:3] = (3e300, -1e10)
    for fn in (ate, rpe):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with pytest.raises(InputError, match=r"^estimate: row 3: pose \(3e\+300, -1e\+10\) m lies beyond \+-1e\+09 m"):
                fn(far, t)
            with pytest.raises(InputError, match=r"^truth: row 3: pose"):
                fn(t, far)
    edge = t.copy()
    edge[3, 1] = 1e9  # the bound itself is taken; a lost estimate's nan is no position beyond it
    assert ate(edge, t).n == 10
    edge[3, 1] = np.nan
    assert np.isnan(ate(edge, t).rmse)


def test_align_2d_takes_lists_as_arrays() -> None:
    """A list of points was "AttributeError: 'list' object has no attribute 'mean'"; the alignment
    of a path turned by 30 deg and moved is that motion."""
    t = square_path()
    c, s = np.cos(np.radians(30)), np.sin(np.radians(30))
    moved = t[:, 1:3] @ np.array([[c, s], [-s, c]]) + [2.0, -1.0]
    al, _ = align_2d(t[:, 1:3].tolist(), moved.tolist())
    assert np.isclose(al.rotation, np.radians(30)) and np.allclose(al.translation, [2.0, -1.0])
