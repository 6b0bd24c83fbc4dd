"""Scoring on hand-built cases: every expected count and error is computed by hand."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from features.scoring import ScoreConfig, explained_fraction, score_scan, truth_lines
from features.types import Corner, FeatureSet, Line
from lms200 import Scan


@dataclass
class Truth:  # shaped like sim.VisibleTruth
    segments: np.ndarray
    segment_beams: np.ndarray
    corners: np.ndarray
    corner_beams: np.ndarray


# A room corner seen from the origin: wall A along y = -2 (x 0..3), wall B along x = 3 (y -2..2),
# wall C along y = 2 (x 3..0); corners at (3,-2) and (3,2), plus a short don't-care face.
SEGS = np.array([[0.0, -2.0, 3.0, -2.0], [3.0, -2.0, 3.0, 2.0], [3.0, 2.0, 0.0, 2.0]])
BEAMS = np.array([[0, 112], [113, 246], [247, 360]])
CORNERS = np.array([[3.0, -2.0, np.pi / 2, 0.0], [3.0, 2.0, np.pi / 2, 0.0]])
TRUTH = Truth(SEGS, BEAMS, CORNERS, np.array([112, 246]))


def line_from(seg, first=0, last=10, shift=0.0, turn=0.0) -> Line:
    """A Line on segment (x1,y1,x2,y2), shifted along its normal by ``shift`` m and turned by
    ``turn`` rad about its midpoint."""
    p0, p1 = np.array(seg[:2], float), np.array(seg[2:], float)
    mid = (p0 + p1) / 2
    c, s = np.cos(turn), np.sin(turn)
    rot = np.array([[c, -s], [s, c]])
    p0, p1 = mid + rot @ (p0 - mid), mid + rot @ (p1 - mid)
    rho, alpha = truth_lines(np.array([[*p0, *p1]]))
    n = np.array([np.cos(alpha[0]), np.sin(alpha[0])])
    p0, p1 = p0 + shift * n, p1 + shift * n
    return Line(float(rho[0] + shift), float(alpha[0]), tuple(p0), tuple(p1), first, last, n_points=last - first + 1)


def perfect() -> list[Line]:
    return [line_from(s, *b) for s, b in zip(SEGS, BEAMS)]


def corners_at(points) -> list[Corner]:
    return [Corner(x, y, np.pi / 2, 0, (0, 1)) for x, y in points]


def test_perfect_extraction_scores_one():
    fs = FeatureSet(perfect(), corners_at([(3, -2), (3, 2)]), "hand")
    s = score_scan(fs, TRUTH)
    assert (s.tp, s.fp, s.fn) == (3, 0, 0)
    assert s.precision == s.recall == s.f1 == 1.0
    np.testing.assert_allclose(s.rho_errors, 0, atol=1e-12)
    np.testing.assert_allclose(s.alpha_errors, 0, atol=1e-12)
    np.testing.assert_allclose(s.endpoint_errors, 0, atol=1e-12)
    assert (s.corner_tp, s.corner_fp, s.corner_fn) == (2, 0, 0)
    np.testing.assert_allclose(s.corner_errors, 0, atol=1e-12)


def test_shifted_line_is_a_miss_and_a_false_positive():
    lines = perfect()
    lines[1] = line_from(SEGS[1], *BEAMS[1], shift=0.2)
    s = score_scan(FeatureSet(lines, [], "hand"), TRUTH)
    assert (s.tp, s.fp, s.fn) == (2, 1, 1)
    assert s.precision == pytest.approx(2 / 3) and s.recall == pytest.approx(2 / 3)
    assert s.f1 == pytest.approx(2 / 3)


def test_small_shift_is_matched_with_its_rho_error():
    lines = perfect()
    lines[1] = line_from(SEGS[1], *BEAMS[1], shift=0.02)
    s = score_scan(FeatureSet(lines, [], "hand"), TRUTH)
    assert (s.tp, s.fp, s.fn) == (3, 0, 0)
    k = list(s.matches[:, 1]).index(1)
    assert s.rho_errors[k] == pytest.approx(0.02)
    assert s.alpha_errors[k] == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(s.endpoint_errors[k], [0.02, 0.02])


def test_turned_line_beyond_the_angle_tolerance_is_not_matched():
    lines = perfect()
    lines[0] = line_from(SEGS[0], *BEAMS[0], turn=np.deg2rad(8))  # ends 0.1 m off the wall too
    assert (score_scan(FeatureSet(lines, [], "hand"), TRUTH).tp) == 2
    lines[0] = line_from(SEGS[0], *BEAMS[0], turn=np.deg2rad(0.5))
    s = score_scan(FeatureSet(lines, [], "hand"), TRUTH)
    assert s.tp == 3
    k = list(s.matches[:, 1]).index(0)
    assert abs(s.alpha_errors[k]) == pytest.approx(np.deg2rad(0.5))


def test_angle_tolerance_alone_rejects():
    lines = perfect()
    lines[1] = line_from(SEGS[1], *BEAMS[1], turn=np.deg2rad(0.3))
    assert score_scan(FeatureSet(lines, [], "hand"), TRUTH, ScoreConfig(angle_tol=np.deg2rad(0.2))).tp == 2


def test_duplicate_line_on_a_matched_face_is_a_false_positive():
    lines = perfect() + [line_from(SEGS[2], 250, 300)]
    s = score_scan(FeatureSet(lines, [], "hand"), TRUTH)
    assert (s.tp, s.fp, s.fn) == (3, 1, 0)


def test_short_piece_of_a_face_does_not_count_as_found():
    piece = [3.0, -2.0, 3.0, -1.0]  # a quarter of wall B
    lines = [perfect()[0], line_from(piece, 113, 150), perfect()[2]]
    s = score_scan(FeatureSet(lines, [], "hand"), TRUTH)
    assert (s.tp, s.fp, s.fn) == (2, 1, 1)


def test_empty_extraction_misses_everything():
    s = score_scan(FeatureSet([], [], "hand"), TRUTH)
    assert (s.tp, s.fp, s.fn) == (0, 0, 3)
    assert np.isnan(s.precision) and s.recall == 0.0 and s.f1 == 0.0
    assert (s.corner_tp, s.corner_fn) == (0, 2)


def test_dont_care_faces_neither_count_nor_penalise():
    short = np.array([[2.0, 0.5, 2.0, 0.7]])  # 0.2 m seen by 6 beams
    truth = Truth(np.vstack((SEGS, short)), np.vstack((BEAMS, [[200, 205]])), CORNERS, np.array([112, 246]))
    s = score_scan(FeatureSet(perfect(), [], "hand"), truth)
    assert (s.tp, s.fp, s.fn, s.n_dont_care) == (3, 0, 0, 1)
    s = score_scan(FeatureSet(perfect() + [line_from(short[0], 200, 205)], [], "hand"), truth)
    assert (s.tp, s.fp, s.fn) == (3, 0, 0)


def test_line_through_the_origin_matches_either_normal():
    seg = np.array([[-1.0, -1.0, 1.0, 1.0]])
    truth = Truth(seg, np.array([[0, 100]]), np.empty((0, 4)), np.empty(0, int))
    base = line_from(seg[0], 0, 100)
    flipped = Line(0.0, float(np.remainder(base.alpha + 2 * np.pi, 2 * np.pi) - np.pi), base.start, base.end, 0, 100)  # the other normal, in (-pi, pi]
    s = score_scan(FeatureSet([flipped], [], "hand"), truth)
    assert s.tp == 1
    assert s.alpha_errors[0] == pytest.approx(0.0, abs=1e-9)


def test_corners_within_and_beyond_tolerance():
    s = score_scan(FeatureSet(perfect(), corners_at([(3.05, -2.0), (3.3, 2.0)]), "hand"), TRUTH)
    assert (s.corner_tp, s.corner_fp, s.corner_fn) == (1, 1, 1)
    np.testing.assert_allclose(s.corner_errors, [0.05])
    assert s.corner_precision == 0.5 and s.corner_recall == 0.5


def _wall_scan(x_wall: float = 3.0) -> Scan:
    angles = -np.pi / 2 + np.arange(361) * np.deg2rad(0.5)
    with np.errstate(divide="ignore"):
        r = np.where(np.abs(angles) < np.deg2rad(60), x_wall / np.cos(angles), np.inf)
    return Scan.lms200(r)


def test_explained_fraction_exact_and_perturbed():
    scan = _wall_scan()
    span = np.flatnonzero(scan.valid)
    line = Line(3.0, 0.0, (3.0, -5.0), (3.0, 5.0), int(span[0]), int(span[-1]))
    frac, rms = explained_fraction(FeatureSet([line], [], "hand"), scan)
    assert frac == 1.0 and rms == pytest.approx(0.0, abs=1e-12)
    moved = Line(3.5, 0.0, (3.5, -5.0), (3.5, 5.0), int(span[0]), int(span[-1]))
    frac, rms = explained_fraction(FeatureSet([moved], [], "hand"), scan)
    assert frac == 0.0 and np.isnan(rms)
    r = scan.ranges.copy()
    r[span[:10]] += 0.02  # 4 sigma: unexplained
    r[span[10:20]] -= 0.01  # 2 sigma: explained
    frac, rms = explained_fraction(FeatureSet([line], [], "hand"), scan.replace(ranges=r), sigma=0.005)
    assert frac == pytest.approx((span.size - 10) / span.size)
    assert rms == pytest.approx(np.sqrt(10 * 0.01**2 / (span.size - 10)))  # RMS of explained beams


def test_explained_fraction_counts_uncovered_beams_as_unexplained():
    scan = _wall_scan()
    span = np.flatnonzero(scan.valid)
    half = span[: span.size // 2]
    line = Line(3.0, 0.0, (3.0, -5.0), (3.0, 0.0), int(half[0]), int(half[-1]))
    frac, _ = explained_fraction(FeatureSet([line], [], "hand"), scan)
    assert frac == pytest.approx(half.size / span.size)
    assert explained_fraction(FeatureSet([], [], "hand"), scan)[0] == 0.0


def test_truth_without_faces_makes_every_line_a_false_positive():
    empty = Truth(np.empty((0, 4)), np.empty((0, 2), int), np.empty((0, 4)), np.empty(0, int))
    s = score_scan(FeatureSet(perfect(), corners_at([(3, -2)]), "hand"), empty)
    assert (s.tp, s.fp, s.fn) == (0, 3, 0) and s.precision == 0.0 and np.isnan(s.recall)
    assert (s.corner_tp, s.corner_fp, s.corner_fn) == (0, 1, 0)
    assert s.rho_errors.shape == (0,) and s.endpoint_errors.shape == (0, 2)
