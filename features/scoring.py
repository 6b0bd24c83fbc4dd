"""Scoring extracted features against ground truth, and against the scan itself where there is none.

Against ground truth (``score_scan``): the truth is any object with the numpy fields of
``sim.VisibleTruth`` (sensor frame): ``segments`` (k,4 x1,y1,x2,y2 of each visible straight face),
``segment_beams`` (k,2 first,last beam), ``corners`` (m,4 x,y,angle,convex), ``corner_beams`` (m,).

Line matching (tolerances in ``ScoreConfig``): an extracted line and a truth face are *compatible*
when
- their normal angles differ by at most ``angle_tol`` (5 deg, in rad),
- both end points of the extracted segment lie within ``distance_tol`` (0.05 m) of the face's
  infinite line, and
- projected on the face, the two overlap by at least ``min_overlap`` (0.5) of the extracted
  segment's length and 0.5 of the face's visible length.
Compatible pairs are matched one-to-one (Hungarian assignment on the normalised angle, distance and
overlap deficits). Faces seen by fewer than ``min_truth_beams`` (10) beams or shorter than
``min_truth_length`` (0.3 m) are "don't care": a line matched or compatible with one is neither a
true nor a false positive, and missing one is no miss. Every other extracted line is a false
positive (including a second line on an already matched face), every other face a miss.
Errors of true positives: rho (extracted - truth, m) and alpha (wrapped, rad) of the infinite lines,
and the distances of both end points to the face's end points (m).

Corners match one-to-one within ``corner_tol`` (0.1 m); a truth corner next to a don't-care face
(a face ending within 2 beams of the corner's beam) is itself don't-care.

Without ground truth (``explained_fraction``): a valid beam is explained when some extracted line
whose beam span covers it predicts its range within 3 sigma (the range where the beam meets the
line, ``rho / cos(bearing - alpha)``); the RMS range residual is taken over the explained beams.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import linear_sum_assignment

from lms200.codes import real_rows
from lms200.errors import InputError
from lms200.finite import shown

from lms200.angles import wrap

from .baselines import checks
from .realdata import TRUTH_FIELDS, check_features, truth_arrays
from .realdata import explained_fraction as explained_fraction  # its home is realdata; scoring's name kept for users
from .types import FeatureSet, whole_number

_BIG = 1e6


@dataclass(frozen=True)
class ScoreConfig:
    """Matching tolerances (see the module docstring)."""

    angle_tol: float = float(np.deg2rad(5.0))  # rad
    distance_tol: float = 0.05
    min_overlap: float = 0.5
    min_truth_beams: int = 10
    min_truth_length: float = 0.3
    corner_tol: float = 0.1

    def __post_init__(self) -> None:
        """ConfigError naming the field: nan, 0 or negative tolerances matched nothing (F1 0.0,
        silently), an infinite one everything, text failed deep in numpy."""
        checks.angle("angle_tol", self.angle_tol, np.pi / 2)
        for name in ("distance_tol", "corner_tol"):
            checks.positive(name, getattr(self, name), "m")
        checks.between("min_overlap", self.min_overlap, 0.0, 1.0)
        checks.integer("min_truth_beams", self.min_truth_beams, 0)
        checks.non_negative("min_truth_length", self.min_truth_length, "m")


@dataclass(frozen=True)
class ScanScore:
    """Scores of one scan. Ratios are nan where their denominator is 0.

    Attributes:
        tp, fp, fn: matched lines, unmatched extracted lines, missed truth faces.
        precision, recall, f1: from tp, fp, fn.
        rho_errors: (tp,) extracted minus truth rho of matched lines (m).
        alpha_errors: (tp,) wrapped extracted minus truth alpha (rad).
        endpoint_errors: (tp, 2) distances of the two end points to the truth face's (m).
        matches: (tp, 2) indices (extracted line, truth face).
        corner_tp, corner_fp, corner_fn, corner_precision, corner_recall: as for lines.
        corner_errors: (corner_tp,) position errors of matched corners (m).
        n_truth, n_dont_care: scored and don't-care truth faces.
    """

    tp: int
    fp: int
    fn: int
    precision: float
    recall: float
    f1: float
    rho_errors: np.ndarray
    alpha_errors: np.ndarray
    endpoint_errors: np.ndarray
    matches: np.ndarray
    corner_tp: int
    corner_fp: int
    corner_fn: int
    corner_precision: float
    corner_recall: float
    corner_errors: np.ndarray
    n_truth: int = 0
    n_dont_care: int = 0
    extra: dict = field(default_factory=dict)


def _ratio(a: float, b: float) -> float:
    return float(a / b) if b > 0 else float("nan")


def prf(tp: int, fp: int, fn: int) -> tuple[float, float, float]:
    """Precision, recall and F1 (nan where undefined: no detection, no truth). InputError for a
    count that is no whole number >= 0 (-1 or nan gave nan scores, silently; None or text was a
    TypeError)."""
    for name, count in (("tp", tp), ("fp", fp), ("fn", fn)):
        if (type(count) is not int or count < 0) and (whole_number(count) is None or count < 0):  # type: ignore[operator]
            raise InputError(f"{name}: must be a whole number >= 0 (a count), got {shown(count)}")
    p, r = _ratio(tp, tp + fp), _ratio(tp, tp + fn)
    f = _ratio(2 * tp, 2 * tp + fp + fn)
    return p, r, f


def _rows(name: str, a: object, width: int, what: str, exact: bool = False) -> np.ndarray:
    """``a`` as float64 rows at least ``width`` wide (exactly, with ``exact``: segments, whose (k, 8)
    line rows were read as end points, silently), nan allowed; InputError naming ``name`` otherwise."""
    return real_rows(a, name, width, what, finite=False, wider=not exact)


def truth_lines(segments: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Normal form (rho >= 0, alpha) of segments (k,4); InputError naming ``segments`` unless (k, 4) numbers."""
    segments = _rows("segments", segments, 4, "x1, y1, x2, y2 m", exact=True)
    dx, dy = segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1]
    norm = np.maximum(np.hypot(dx, dy), 1e-12)
    nx, ny = -dy / norm, dx / norm
    rho = nx * segments[:, 0] + ny * segments[:, 1]
    flip = rho < 0
    nx, ny, rho = np.where(flip, -nx, nx), np.where(flip, -ny, ny), np.abs(rho)
    return rho, np.arctan2(ny, nx)


@dataclass(frozen=True)
class CheckedTruth:
    """A ground truth checked once (:func:`check_truth`), its fields as the scoring reads them:
    segments (k, 4) and corners (m, 4) float64, segment_beams (k, 2) and corner_beams (m,) as given.
    ``score_scan`` takes it without checking again, so a caller that scores several methods' features
    against one scan's truth checks it once (the check was 10-35 us a call)."""

    segments: np.ndarray
    segment_beams: np.ndarray
    corners: np.ndarray
    corner_beams: np.ndarray

    def __post_init__(self) -> None:
        """The fields checked (``realdata.truth_arrays``) and shaped as the scoring reads them, once,
        however it is built (a hand-built one with nan faces scored recall 1.0, silently; None fields
        were a TypeError)."""
        a = truth_arrays(self)  # float64; the beam indices are kept as given
        object.__setattr__(self, "segments", a["segments"].reshape(-1, 4))
        object.__setattr__(self, "segment_beams", np.asarray(self.segment_beams).reshape(-1, 2))
        object.__setattr__(self, "corners", a["corners"].reshape(-1, 4))
        object.__setattr__(self, "corner_beams", np.asarray(self.corner_beams).reshape(-1))


def check_truth(truth: Any) -> CheckedTruth:
    """``truth`` (``sim.VisibleTruth``'s fields: see the module docstring) checked, as a CheckedTruth.

    Raises:
        InputError: naming ``truth`` or its field: another object, fields of shapes that disagree,
            nan faces (another object was an AttributeError deep in the scoring; nan faces were
            counted as missed, silently).
    """
    if isinstance(truth, CheckedTruth):
        return truth
    if not all(hasattr(truth, name) for name in TRUTH_FIELDS):
        truth_arrays(truth)  # the message naming what it lacks
    return CheckedTruth(*(getattr(truth, name) for name in TRUTH_FIELDS))


def _dont_care(truth: CheckedTruth, cfg: ScoreConfig) -> np.ndarray:
    seg, beams = truth.segments, truth.segment_beams
    n_beams = beams[:, 1] - beams[:, 0] + 1
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    return (n_beams < cfg.min_truth_beams) | (length < cfg.min_truth_length)


def line_compatibility(lines: np.ndarray, seg: np.ndarray, cfg: ScoreConfig) -> tuple[np.ndarray, np.ndarray]:
    """(E, T) compatibility mask and matching cost of extracted lines (rho, alpha, x0, y0, x1, y1)
    against truth segments (x1, y1, x2, y2); InputError naming the argument for other shapes or types."""
    if not isinstance(cfg, ScoreConfig):
        raise InputError(f"cfg: must be a features.scoring.ScoreConfig, got {type(cfg).__name__}")
    lines, seg = _rows("lines", lines, 6, "rho m, alpha rad, x0, y0, x1, y1 m"), _rows("seg", seg, 4, "x1, y1, x2, y2 m", exact=True)
    rho_t, alpha_t = truth_lines(seg)
    d_alpha = np.abs(wrap(lines[:, 1:2] - alpha_t[None, :]))
    d_alpha = np.minimum(d_alpha, np.pi - d_alpha)  # a line through the origin has two normals
    nx, ny = np.cos(alpha_t)[None, :], np.sin(alpha_t)[None, :]
    d0 = np.abs(lines[:, 2:3] * nx + lines[:, 3:4] * ny - rho_t[None, :])
    d1 = np.abs(lines[:, 4:5] * nx + lines[:, 5:6] * ny - rho_t[None, :])
    dist = np.maximum(d0, d1)
    # overlap along each face (t from its first to its second end point)
    ux = (seg[:, 2] - seg[:, 0])
    uy = (seg[:, 3] - seg[:, 1])
    length_t = np.maximum(np.hypot(ux, uy), 1e-12)
    ux, uy = (ux / length_t)[None, :], (uy / length_t)[None, :]
    t0 = (lines[:, 2:3] - seg[None, :, 0]) * ux + (lines[:, 3:4] - seg[None, :, 1]) * uy
    t1 = (lines[:, 4:5] - seg[None, :, 0]) * ux + (lines[:, 5:6] - seg[None, :, 1]) * uy
    lo, hi = np.minimum(t0, t1), np.maximum(t0, t1)
    overlap = np.maximum(0.0, np.minimum(hi, length_t[None, :]) - np.maximum(lo, 0.0))
    length_e = np.maximum(np.hypot(lines[:, 4] - lines[:, 2], lines[:, 5] - lines[:, 3]), 1e-12)[:, None]
    cover = np.minimum(overlap / length_e, overlap / length_t[None, :])
    angle_tol = cfg.angle_tol
    ok = (d_alpha <= angle_tol) & (dist <= cfg.distance_tol) & (cover >= cfg.min_overlap)
    cost = d_alpha / angle_tol + dist / cfg.distance_tol + (1.0 - cover)
    return ok, cost


def _assign(cost: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """One-to-one pairs (i, j) among compatible entries, minimising total cost."""
    if cost.size == 0 or not ok.any():
        return np.empty((0, 2), dtype=int)
    rows, cols = linear_sum_assignment(np.where(ok, cost, _BIG))
    keep = ok[rows, cols]
    return np.column_stack((rows[keep], cols[keep]))


def score_scan(fs: FeatureSet, truth: Any, config: ScoreConfig | None = None) -> ScanScore:
    """Score one scan's features against its visible ground truth (sensor frame, see module doc):
    a ``sim.VisibleTruth`` (or any object with its fields), checked on every call, or a
    :class:`CheckedTruth` from :func:`check_truth`, checked once for every method's features."""
    if config is not None and not isinstance(config, ScoreConfig):
        raise InputError(f"config: must be a features.scoring.ScoreConfig or None, got {type(config).__name__}")
    cfg = config or ScoreConfig()
    check_features(fs)
    truth = check_truth(truth)
    seg = truth.segments
    dont = _dont_care(truth, cfg)
    lines = fs.line_array()[:, :6]  # rho, alpha, x0, y0, x1, y1
    ok, cost = line_compatibility(lines, seg, cfg) if lines.size and seg.size else (
        np.zeros((len(lines), len(seg)), bool), np.zeros((len(lines), len(seg))))
    cost = cost + 10.0 * dont[None, :]  # prefer scored faces over don't-care ones
    pairs = _assign(cost, ok)
    scored = pairs[~dont[pairs[:, 1]]] if pairs.size else pairs
    matched_e = np.zeros(len(lines), bool)
    matched_e[pairs[:, 0]] = True
    neutral = ~matched_e & (ok[:, dont].any(axis=1) if dont.any() else False)
    tp = int(scored.shape[0])
    fp = int(np.count_nonzero(~matched_e & ~neutral))
    fn = int(np.count_nonzero(~dont)) - tp
    # errors of the true positives
    rho_t, alpha_t = truth_lines(seg)
    if tp:
        e, t = scored[:, 0], scored[:, 1]
        rho_e, alpha_e = lines[e, 0], lines[e, 1]
        d_alpha = wrap(alpha_e - alpha_t[t])
        flip = np.abs(d_alpha) > np.pi / 2  # normals on opposite sides of a line through the origin
        rho_err = np.where(flip, -rho_e, rho_e) - rho_t[t]
        alpha_err = wrap(np.where(flip, d_alpha + np.pi, d_alpha))
        a0, a1 = lines[e, 2:4], lines[e, 4:6]
        b0, b1 = seg[t, 0:2], seg[t, 2:4]
        same = np.hypot(*(a0 - b0).T) + np.hypot(*(a1 - b1).T)
        swap = np.hypot(*(a0 - b1).T) + np.hypot(*(a1 - b0).T)
        ends = np.where(
            (same <= swap)[:, None],
            np.column_stack((np.hypot(*(a0 - b0).T), np.hypot(*(a1 - b1).T))),
            np.column_stack((np.hypot(*(a0 - b1).T), np.hypot(*(a1 - b0).T))),
        )
    else:
        rho_err = alpha_err = np.empty(0)
        ends = np.empty((0, 2))
    precision, recall, f1 = prf(tp, fp, fn)
    ctp, cfp, cfn, cerr = _score_corners(fs, truth, dont, cfg)
    cp, cr, _ = prf(ctp, cfp, cfn)
    return ScanScore(
        tp, fp, fn, precision, recall, f1, rho_err, alpha_err, ends, scored,
        ctp, cfp, cfn, cp, cr, cerr, int(np.count_nonzero(~dont)), int(np.count_nonzero(dont)),
    )


def _score_corners(fs: FeatureSet, truth: CheckedTruth, dont_faces: np.ndarray, cfg: ScoreConfig):
    tc, tb, beams = truth.corners, truth.corner_beams, truth.segment_beams
    ec = fs.corner_array()
    # a corner next to a don't-care face is don't-care
    near = (np.abs(beams[None, :, 0] - tb[:, None]) <= 2) | (np.abs(beams[None, :, 1] - tb[:, None]) <= 2)
    dont = (near & dont_faces[None, :]).any(axis=1) if beams.size else np.zeros(tc.shape[0], bool)
    if ec.size and tc.size:
        dist = np.hypot(ec[:, None, 0] - tc[None, :, 0], ec[:, None, 1] - tc[None, :, 1])
        ok = dist <= cfg.corner_tol
        pairs = _assign(dist + 10.0 * dont[None, :], ok)
    else:
        ok = np.zeros((ec.shape[0], tc.shape[0]), bool)
        dist = np.zeros_like(ok, float)
        pairs = np.empty((0, 2), int)
    scored = pairs[~dont[pairs[:, 1]]] if pairs.size else pairs
    matched = np.zeros(ec.shape[0], bool)
    matched[pairs[:, 0]] = True
    neutral = ~matched & (ok[:, dont].any(axis=1) if dont.any() else False)
    tp = int(scored.shape[0])
    fp = int(np.count_nonzero(~matched & ~neutral))
    fn = int(np.count_nonzero(~dont)) - tp
    err = dist[scored[:, 0], scored[:, 1]] if tp else np.empty(0)
    return tp, fp, fn, err


