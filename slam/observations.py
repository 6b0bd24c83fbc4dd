"""Observations of one scan in the form the filter uses, built from a ``features.FeatureSet``."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from features.baselines.checks import integer
from features.errors import not_a_scan
from features.realdata import check_features
from features.types import RHO_SLACK, FeatureSet, not_covariance
from lms200 import InputError, Scan
from lms200.finite import shown
from lms200.records import MAX_COORD_M
from lms200.codes import real_rows, unmasked

from .config import SlamConfig


def _empty(shape: tuple[int, ...]) -> np.ndarray:
    return np.zeros(shape)


@dataclass(frozen=True)
class Observations:
    """Line and corner observations of one scan, in the sensor frame.

    Attributes:
        lines: (m, 2) rho m >= 0, alpha rad.
        line_cov: (m, 2, 2) covariance of (rho, alpha).
        line_ends: (m, 4) segment endpoints x0, y0, x1, y1 (m).
        corners: (k, 2) x, y (m).
        corner_cov: (k, 2, 2) covariance of (x, y).
        points: (p, 2) the scan's valid points (m), used only to check a pre-alignment.
    """

    lines: np.ndarray = field(default_factory=lambda: _empty((0, 2)))
    line_cov: np.ndarray = field(default_factory=lambda: _empty((0, 2, 2)))
    line_ends: np.ndarray = field(default_factory=lambda: _empty((0, 4)))
    corners: np.ndarray = field(default_factory=lambda: _empty((0, 2)))
    corner_cov: np.ndarray = field(default_factory=lambda: _empty((0, 2, 2)))
    points: np.ndarray = field(default_factory=lambda: _empty((0, 2)))

    def __post_init__(self) -> None:
        """Every field as a finite float64 array of its shape, covariances one a row of the lines /
        corners, symmetric and positive semi-definite, lines' rho >= 0 m; InputError naming the
        field otherwise. Found by fuzzing the Python API: text was an AttributeError in the filter,
        (2, 2) lines with one covariance an IndexError, (1, 3) lines a bare unpacking error, nan
        covariances a nan trajectory, silently; a negative or asymmetric covariance or a negative
        rho was taken (2026-12-07)."""
        self._check(covariances=True)

    @classmethod
    def _built(cls, lines: np.ndarray, line_cov: np.ndarray, line_ends: np.ndarray, corners: np.ndarray,
               corner_cov: np.ndarray, points: np.ndarray) -> Observations:
        """Observations of covariances that are covariances by construction (``from_features``'s:
        an extractor's that passed :func:`features.types.not_covariance`, or none, plus a diagonal
        floor): every other field checked, the covariances' shapes and finiteness too."""
        obs = object.__new__(cls)
        for name, a in zip(("lines", "line_cov", "line_ends", "corners", "corner_cov", "points"),
                           (lines, line_cov, line_ends, corners, corner_cov, points)):
            object.__setattr__(obs, name, a)
        obs._check(covariances=False)
        return obs

    def _check(self, covariances: bool) -> None:
        """The checks of ``__post_init__``; the covariances' :func:`not_covariance` when ``covariances``."""
        rows = {name: real_rows(getattr(self, name), f"observations.{name}", cols, what)
                for name, cols, what in (("lines", 2, "rho m, alpha rad"), ("line_ends", 4, "x0, y0, x1, y1 m"),
                                         ("corners", 2, "x m, y m"), ("points", 2, "x m, y m"))}
        if covariances:  # built by a user (from_features' are a scan's, from its extractor): within the bounds of
            _check_scale(rows)  # every log and trajectory, so that the filter's products stay finite
        if rows["line_ends"].shape[0] != rows["lines"].shape[0]:
            raise InputError(f"observations.line_ends: {rows['line_ends'].shape[0]} rows for {rows['lines'].shape[0]} lines")
        for cov, of in (("line_cov", "lines"), ("corner_cov", "corners")):
            m = rows[of].shape[0]
            try:
                c = np.asarray(unmasked(getattr(self, cov)), dtype=np.float64)  # a masked item: nan, refused
            except (TypeError, ValueError):
                c = np.empty(0)
            if c.shape != (m, 2, 2) or not np.isfinite(c).all():
                raise InputError(f"observations.{cov}: must be ({m}, 2, 2) finite covariances, one a row of "
                                 f"observations.{of}, got {'shape ' + str(c.shape) if c.shape != (m, 2, 2) else 'nan / inf'}")
            if covariances:
                _check_scale({cov: c.reshape(m, 4)})
            bad = not_covariance(c) if covariances and m else c[:0, 0, 0]
            if bad.any():  # a negative variance, a correlation beyond 1 or an asymmetric one: the EKF's S was no
                k = int(np.flatnonzero(bad)[0])  # covariance and its gate and update nonsense, silently (fuzzing)
                raise InputError(f"observations.{cov}: row {k} is no covariance (it must be symmetric and positive "
                                 f"semi-definite), got {c[k].tolist()}")
            rows[cov] = c
        rho = rows["lines"][:, 0]
        if (rho < -RHO_SLACK).any():  # documented rho >= 0: a negative one is the same line with its normal turned
            k = int(np.flatnonzero(rho < -RHO_SLACK)[0])
            raise InputError(f"observations.lines: row {k}: rho must be >= 0 m (the line's distance from the sensor; "
                             f"the same line is rho {-rho[k]:g}, alpha + pi), got {rows['lines'][k].tolist()}")
        for name, a in rows.items():
            object.__setattr__(self, name, a)

    @property
    def line_lengths(self) -> np.ndarray:
        e = self.line_ends
        return np.hypot(e[:, 2] - e[:, 0], e[:, 3] - e[:, 1])


#: m^2 (or rad^2, alpha's): the largest covariance entry an Observations built by hand takes, a std of MAX_COORD_M
MAX_OBSERVATION_VARIANCE = MAX_COORD_M**2


def _check_scale(rows: dict[str, np.ndarray]) -> None:
    """InputError naming the first field of an Observations built by hand with a coordinate beyond +-MAX_COORD_M
    (1e9 m, every log reader's and trajectory's bound) or a covariance entry beyond MAX_OBSERVATION_VARIANCE: 1e300
    was taken, and the filter's products overflowed (numpy's RuntimeWarnings, 'overflow encountered in multiply' in
    its determinants, 'invalid value' in its segment projections; fuzz round 10)."""
    for name, bound, unit in (("lines", MAX_COORD_M, "m"), ("line_ends", MAX_COORD_M, "m"), ("corners", MAX_COORD_M, "m"),
                              ("points", MAX_COORD_M, "m"), ("line_cov", MAX_OBSERVATION_VARIANCE, "m^2 / rad^2"),
                              ("corner_cov", MAX_OBSERVATION_VARIANCE, "m^2")):
        if name not in rows:
            continue
        a = rows[name][:, :1] if name == "lines" else rows[name]  # a line's alpha is an angle, within +-pi or wrapped
        if a.size and np.abs(a).max() > bound:
            k = int(np.flatnonzero((np.abs(a) > bound).reshape(len(a), -1).any(axis=1))[0])
            raise InputError(f"observations.{name}: row {k} holds {shown(float(np.abs(a[k]).max()))} {unit}, beyond "
                             f"{bound:g} {unit} (slam.observations: every log's and trajectory's bound)")


def from_features(fs: FeatureSet, config: SlamConfig, scan: Scan | None = None) -> Observations:
    """Keep the lines with enough support; their covariance is the extractor's (where finite and
    positive definite) plus the floor ``diag(sigma_rho^2, sigma_alpha_obs^2)``. With ``scan``, its
    valid points (every ``point_stride``-th) come along for checking pre-alignments.

    Raises:
        InputError / ScanTypeError: ``fs`` is no FeatureSet, ``config`` no SlamConfig, ``scan``
            neither None nor a Scan (each was an AttributeError inside; found by fuzzing), or a
            scan that has fewer beams than ``fs``'s lines and corners reach (features of another
            scan: its points were taken beside them, silently).
    """
    check_features(fs)
    if not isinstance(config, SlamConfig):
        raise InputError(f"config: must be a slam.SlamConfig, got {type(config).__name__}")
    if scan is not None:
        check_scan_of(fs, scan)
    floor = np.diag([config.observations.sigma_rho**2, config.observations.sigma_alpha_obs**2])
    ln = fs.lines
    keep = ~((ln.n_points > 0) & (ln.n_points < config.observations.min_line_points)) & ~(ln.length < config.observations.min_line_length)
    c = ln.cov[keep]
    sym = 0.5 * (c + c.transpose(0, 2, 1))
    good = np.isfinite(c).all(axis=(1, 2))  # finite and a covariance (features.types.not_covariance), else the floor alone
    good[good] = ~not_covariance(c[good])
    covs = np.where(good[:, None, None], sym, 0.0) + floor
    lines = np.column_stack((ln.rho[keep], ln.alpha[keep]))
    ends = ln.values[keep, 2:6]
    corners = fs.corners.values[:, :2] if config.observations.use_corners else np.zeros((0, 2))
    ccov = np.broadcast_to(np.eye(2) * config.observations.sigma_corner**2, (corners.shape[0], 2, 2)).copy()
    return Observations._built(
        lines, covs, ends.copy(), corners.copy(), ccov,
        scan_points(scan, config.observations.point_stride) if scan is not None else np.zeros((0, 2)),
    )


def check_scan_of(fs: FeatureSet, scan: object) -> None:
    """ScanTypeError unless ``scan`` is a Scan, InputError unless it has every beam ``fs``'s lines
    (``first`` .. ``last``) and corners (``index``) name: the features were found on another scan."""
    if not isinstance(scan, Scan):
        raise not_a_scan(scan, "from_features")
    beams = np.concatenate((fs.lines.beams[:, :2].ravel(), fs.corners.beams[:, 0]))
    if beams.size and int(beams.max()) >= len(scan):
        raise InputError(f"scan: has {len(scan)} beams, but fs's features reach beam {int(beams.max())} "
                         f"(features of another scan?)")


def scan_points(scan: Scan, stride: int = 2) -> np.ndarray:
    """(p, 2) valid points of the scan in the sensor frame (m), every ``stride``-th beam.

    Raises:
        ScanTypeError: ``scan`` is no Scan. ConfigError: ``stride`` is no integer >= 1 (0 was
            Python's "slice step cannot be zero", -1 the points in reverse, 2.5 a TypeError).
    """
    if not isinstance(scan, Scan):
        raise not_a_scan(scan, "scan_points")
    integer("stride", stride, 1)
    pts = scan.points[::stride]
    return pts[np.isfinite(pts[:, 0])]
