"""Scoring extracted lines on real scans, where there is no ground truth.

The measures a line-extraction paper reports on real data (Schaefer et al. 2018, "A maximum-likelihood
approach to extracting polylines from 2-D laser range scans", report the ray-path error):

- **Ray residual** of a valid beam: ``|r - rho / cos(b - alpha)|``, the distance along the beam
  between its reading and the point where it meets a line (m); of the lines whose beam span
  [first, last] covers the beam, the closest counts. A beam no line covers has no residual (inf).
- **Explained fraction**: share of valid beams whose ray residual is within a tolerance: a fixed one
  (``tolerance_m``, 3 cm) and ``n_sigma`` (3) times the range noise sigma (estimated from the data
  with :func:`lms200.noise.estimate_range_noise` where it is not known).
- **Ray RMSE**: RMS ray residual of the beams explained at the fixed tolerance (m).
- **Lines per scan** and **mean segment length** (m, end point to end point).
- **References for the ray RMSE**: the ray RMSE depends on the range noise as much as on the
  lines: under Gaussian noise of std sigma, exact lines score :func:`truncated_normal_rms` (the RMS
  of the noise within the tolerance: 0.63 sigma at sigma = 25 mm and 3 cm). In simulation the exact
  lines themselves can be scored (:func:`truth_lines`): a method that scores well below them covers
  only the beams whose noise happened to be small.
- **Repeatability**, where a log carries corrected poses (Radish's ``*-corrected`` logs): the share
  of the lines of scan t, still in view at scan t+1, that scan t+1 finds again: a line of t+1 within
  ``repeat_distance_m`` (5 cm) in rho and ``repeat_angle_rad`` (2 deg) in alpha after moving the line
  of t through the world frame into t+1's sensor frame. A line of t is still in view when the
  midpoint of its segment, seen from t+1, lies in t+1's field of view and t+1's beam at that bearing
  reads its range within ``repeat_distance_m`` (so a line now occluded or out of range is not
  counted).

Everything is in the sensor frame (x ahead, y left, m, rad); poses are (x, y, theta) in the world.
Pure functions: arrays in, numbers out.
"""

from __future__ import annotations

from collections.abc import Mapping
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from lms200 import Scan

from lms200.errors import InputError

from .baselines import checks
from .errors import not_a_scan
from .types import FeatureSet, check_line_rows


TRUTH_FIELDS = ("segments", "segment_beams", "corners", "corner_beams")  # sim.VisibleTruth's, as the scoring reads them


@dataclass(frozen=True)
class RealDataConfig:
    """Tolerances of the real-data measures (see the module docstring).

    Attributes:
        tolerance_m: fixed ray-residual tolerance of the explained fraction (m).
        n_sigma: noise-scaled tolerance, in range-noise sigmas.
        repeat_distance_m: rho tolerance of a line found again, and of the in-view test (m).
        repeat_angle_rad: alpha tolerance of a line found again (rad), in (0, pi].

    Raises:
        ConfigError: (an ``LmsbenchError``) naming the field, for a value that is not a finite
            number > 0 (an angle in (0, pi] rad for ``repeat_angle_rad``): ``tolerance_m=-1``
            explained nothing, ``"x"`` was a TypeError deep in the measures, both silently built.
    """

    tolerance_m: float = 0.03
    n_sigma: float = 3.0
    repeat_distance_m: float = 0.05
    repeat_angle_rad: float = math.radians(2.0)

    def __post_init__(self) -> None:
        checks.positive("tolerance_m", self.tolerance_m, "m")
        checks.positive("n_sigma", self.n_sigma, "range-noise sigmas")
        checks.positive("repeat_distance_m", self.repeat_distance_m, "m")
        checks.angle("repeat_angle_rad", self.repeat_angle_rad, math.pi)


def _lines(fs: FeatureSet | np.ndarray, name: str = "fs") -> np.ndarray:
    """(k, 8) rho, alpha, x0, y0, x1, y1, first, last of a FeatureSet (or such an array);
    InputError naming ``name`` for anything else (None was an AttributeError: no line_array)."""
    if not isinstance(fs, np.ndarray):
        check_features(fs, name)
        rows = np.asarray(fs.line_array(), dtype=np.float64).reshape(-1, 8)
    else:
        if fs.dtype.kind not in "iuf" or fs.size % 8 or fs.ndim > 2 or (fs.ndim == 2 and fs.shape[1] != 8):
            raise InputError(f"{name}: a line array must be (k, 8) numbers (rho, alpha, x0, y0, x1, y1, first, last: "
                             f"FeatureSet.line_array()), got shape {fs.shape} of {fs.dtype}")
        rows = np.asarray(fs, dtype=np.float64).reshape(-1, 8)
    check_line_rows(rows, name)
    return rows


def truth_arrays(truth: Any, need: tuple[str, ...] = TRUTH_FIELDS, finite: bool = True) -> dict[str, np.ndarray]:
    """The fields ``need`` of a ground truth (``sim.VisibleTruth``'s: segments (k, 4) with
    segment_beams (k, 2), corners (m, 4) with corner_beams (m,)) as float64 arrays, checked: there,
    numeric, of consistent shapes and (``finite``) finite. Reshape them as the scoring reads them.

    Raises:
        InputError: naming ``truth`` or the field (another object, None included, was an
            AttributeError deep in the scoring; nan faces were counted as missed, silently).
    """
    missing = [name for name in need if not hasattr(truth, name)]
    if missing:
        keys = isinstance(truth, Mapping) and all(name in truth for name in need)  # "dict lacks segments" of a dict that held it
        raise InputError(f"truth: must have the fields of sim.VisibleTruth ({', '.join(need)}); "
                         f"{type(truth).__name__} lacks {', '.join(missing)}"
                         + (" as attributes (a mapping's keys are not read: pass types.SimpleNamespace(**truth))" if keys else ""))
    try:
        arrays = {name: np.asarray(getattr(truth, name), dtype=np.float64) for name in need}
    except (TypeError, ValueError) as exc:
        raise InputError(f"truth: its fields must be numeric arrays ({exc})") from None
    for name in ("segments", "corners"):
        a = arrays.get(name)
        if a is not None and (a.size % 4 or (a.ndim == 2 and a.shape[1] != 4) or a.ndim > 2):
            raise InputError(f"truth.{name}: must be (k, 4) rows, got shape {a.shape}")
    k = arrays["segments"].size // 4 if "segments" in arrays else 0
    m = arrays["corners"].size // 4 if "corners" in arrays else 0
    shapes = {"segments": (k, 4), "segment_beams": (k, 2), "corners": (m, 4), "corner_beams": (m,)}
    for name, a in arrays.items():
        shape = shapes[name]
        if a.size != math.prod(shape):  # math.prod: np.prod was 4 us a call, 4 calls a scored scan
            raise InputError(f"truth.{name}: must be {shape} to match truth.segments / truth.corners, got shape {a.shape}")
        if finite and not np.isfinite(a).all():
            raise InputError(f"truth.{name}: must be finite (sim.visible_truth leaves out faces it does not see)")
    return arrays


def truth_lines(truth: Any) -> np.ndarray:
    """(k, 8) the visible faces of a simulated scan's ground truth in this module's line layout
    (rho m, alpha rad, x0, y0, x1, y1 m, first, last beam): the lines an exact extractor reports.

    Args:
        truth: a ``sim.VisibleTruth`` (its ``segments`` (k, 4) x1, y1, x2, y2 in the sensor frame
            and ``segment_beams`` (k, 2) first and last beam); faces without a visible part (nan
            rows) are left out.

    Raises:
        InputError: naming ``truth`` or its field, for anything else (None was an AttributeError).
    """
    arrays = truth_arrays(truth, ("segments", "segment_beams"), finite=False)
    seg, beams = arrays["segments"].reshape(-1, 4), arrays["segment_beams"].reshape(-1, 2)
    keep = np.all(np.isfinite(seg), axis=1) & np.all(np.isfinite(beams), axis=1)
    seg, beams = seg[keep], beams[keep]
    nx, ny = -(seg[:, 3] - seg[:, 1]), seg[:, 2] - seg[:, 0]  # a normal of each face
    alpha = np.arctan2(ny, nx)
    rho = seg[:, 0] * np.cos(alpha) + seg[:, 1] * np.sin(alpha)
    alpha = np.angle(np.exp(1j * np.where(rho < 0, alpha + math.pi, alpha)))
    return np.column_stack((np.abs(rho), alpha, seg, beams))


def check_features(fs: object, name: str = "fs") -> None:
    """InputError naming ``name`` unless ``fs`` is a FeatureSet (was an AttributeError deep inside)."""
    if not isinstance(fs, FeatureSet):
        raise InputError(f"{name}: expected a features.FeatureSet, got {type(fs).__name__}")


def _checked_lines(fs: FeatureSet | np.ndarray, scan: Scan, name: str = "fs", scan_name: str = "scan") -> np.ndarray:
    """``_lines(fs)`` of lines within ``scan``'s beams; ScanTypeError / InputError naming the argument."""
    if not isinstance(scan, Scan):
        raise not_a_scan(scan, scan_name)
    lines = _lines(fs, name)
    if lines.shape[0] and not (np.all(lines[:, 6] >= 0) and np.all(lines[:, 7] < len(scan))):
        raise InputError(f"{name}: its lines span beams {int(lines[:, 6].min())}..{int(lines[:, 7].max())}, "
                         f"the scan has {len(scan)} (features of another scan?)")
    return lines


def _config(config: object) -> RealDataConfig:
    """``config`` or the default; InputError naming it unless a RealDataConfig (or None)."""
    if config is None:
        return RealDataConfig()
    if not isinstance(config, RealDataConfig):
        raise InputError(f"config: must be a features.realdata.RealDataConfig or None, got {type(config).__name__}")
    return config


def check_measure_args(fs: FeatureSet | np.ndarray, scan: Scan, sigma: object, sigma_name: str) -> np.ndarray:
    """The arguments of the real-data measures: ``fs`` a FeatureSet (or its ``line_array()``) of
    lines within ``scan``'s beams, ``scan`` a Scan, ``sigma`` (m) a number in (0, MAX_SIGMA_M] (the range noise; 0
    explained only beams a line predicts to the last bit: (0.0, nan) on any real scan). Returns the
    lines as the measures read them (``_lines``), made once.

    Raises:
        InputError: naming the argument (a nan, zero or negative sigma explained no beam, an
            infinite one every covered beam; lines past the scan's last beam came from another scan, and
            were clipped onto its last beam, silently).
        ScanTypeError: ``scan`` is not an lms200.Scan.
    """
    if not isinstance(scan, Scan):
        raise not_a_scan(scan, "scan")
    if not isinstance(fs, np.ndarray):
        check_features(fs)
    if isinstance(sigma, (bool, np.bool_)) or not isinstance(sigma, (int, float, np.integer, np.floating)) \
            or not (checks.finite(sigma) and 0 < sigma <= checks.MAX_SIGMA_M):  # checks.finite: 10**400 is no OverflowError
        # above MAX_SIGMA_M, 3 sigma overflowed: sigma = 1e308 explained every covered beam, rms inf (fuzzing)
        raise InputError(f"{sigma_name}: must be a finite number in (0, {checks.MAX_SIGMA_M:g}] m (the range noise), "
                         f"got {sigma!r}")
    return _checked_lines(fs, scan)


TRUNCATION_NONE = 40.0  # sigmas beyond which a truncation leaves the RMS unchanged in float64 (phi(40) = 0)


def truncated_normal_rms(sigma: float, tolerance: float) -> float:
    """RMS (m) of a zero-mean normal of std ``sigma`` (m) over its values within +-``tolerance``
    (m): the ray RMSE that exact lines score under Gaussian range noise, ``sigma sqrt(1 - 2 c
    phi(c) / (2 Phi(c) - 1))`` with c = tolerance / sigma."""
    if not all(checks.is_real(v) and checks.finite(v) and v > 0 for v in (sigma, tolerance)):  # None: TypeError;
        # inf (or 10**400) sigma: ZeroDivisionError; inf tolerance: nan
        raise InputError(f"sigma, tolerance: must be finite numbers > 0 m, got {sigma!r} and {tolerance!r}")
    c = min(tolerance / sigma, TRUNCATION_NONE)  # tolerance 1e308 or sigma 5e-324: inf * phi(inf) was nan
    inside = math.erf(c / math.sqrt(2.0))  # 2 Phi(c) - 1
    density = math.exp(-0.5 * c * c) / math.sqrt(2.0 * math.pi)  # phi(c)
    return sigma * math.sqrt(max(1.0 - 2.0 * c * density / inside, 0.0))


def ray_residuals(fs: FeatureSet | np.ndarray, scan: Scan) -> np.ndarray:
    """(n,) ray residual of every beam (m): the smallest ``|r - rho / cos(b - alpha)|`` over the
    lines whose beam span covers it; inf for beams no line covers and for beams that are not valid.

    Raises:
        InputError: an ``fs`` that is no FeatureSet or (k, 8) line array (None was an
            AttributeError), or whose lines reach past the scan's beams (features of another scan:
            they were clipped onto its last beam). ScanTypeError: a ``scan`` that is no lms200.Scan.
    """
    return _ray_residuals(_checked_lines(fs, scan), scan)


def _ray_residuals(lines: np.ndarray, scan: Scan) -> np.ndarray:
    """:func:`ray_residuals` of lines already checked (``_checked_lines``)."""
    n = len(scan)
    best = np.full(n, np.inf)
    if lines.shape[0] == 0:
        return best
    first = np.clip(lines[:, 6].astype(np.int64), 0, n - 1)
    last = np.clip(lines[:, 7].astype(np.int64), 0, n - 1)
    length = np.maximum(last - first + 1, 0)
    labels = np.repeat(np.arange(lines.shape[0]), length)
    beam = np.arange(int(length.sum())) - np.repeat(np.cumsum(length) - length - first, length)
    cos = np.cos(scan.angles[beam] - lines[labels, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        predicted = np.where(cos > 1e-6, lines[labels, 0] / cos, np.inf)
        residual = np.abs(scan.ranges[beam] - predicted)
    use = scan.valid[beam] & np.isfinite(residual)
    np.minimum.at(best, beam[use], residual[use])
    return best


@dataclass(frozen=True)
class ScanMeasures:
    """Real-data measures of one scan (nan where undefined: no valid beam, no explained beam).

    Attributes:
        n_valid: valid beams.
        explained_tol: share of valid beams explained at the fixed tolerance.
        explained_sigma: share explained at n_sigma x sigma_r.
        n_explained_tol: beams explained at the fixed tolerance (weights for pooling the RMSE).
        ray_rmse_m: RMS ray residual of the beams explained at the fixed tolerance (m).
        n_lines: extracted lines.
        mean_segment_m: mean segment length (m).
    """

    n_valid: int
    explained_tol: float
    explained_sigma: float
    n_explained_tol: int
    ray_rmse_m: float
    n_lines: int
    mean_segment_m: float

    def as_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


def scan_measures(fs: FeatureSet | np.ndarray, scan: Scan, sigma_r: float,
                  config: RealDataConfig | None = None) -> ScanMeasures:
    """Explained fractions, ray RMSE, line count and mean segment length of one scan's lines.

    Args:
        fs: the extracted lines (a FeatureSet, or its ``line_array()``).
        scan: the scan they were extracted from.
        sigma_r: range noise, 1 sigma (m), for the noise-scaled tolerance.
        config: tolerances.
    """
    cfg = _config(config)
    lines = check_measure_args(fs, scan, sigma_r, "sigma_r")
    n_valid = int(np.count_nonzero(scan.valid))
    lengths = np.hypot(lines[:, 4] - lines[:, 2], lines[:, 5] - lines[:, 3])
    mean_len = float(lengths.mean()) if lengths.size else float("nan")
    if n_valid == 0:
        return ScanMeasures(0, float("nan"), float("nan"), 0, float("nan"), lines.shape[0], mean_len)
    res = _ray_residuals(lines, scan)
    ok = res <= cfg.tolerance_m
    n_ok = int(np.count_nonzero(ok))
    rmse = float(np.sqrt(np.mean(res[ok] ** 2))) if n_ok else float("nan")
    n_sigma = int(np.count_nonzero(res <= cfg.n_sigma * sigma_r))
    return ScanMeasures(n_valid, n_ok / n_valid, n_sigma / n_valid, n_ok, rmse, lines.shape[0], mean_len)


def explained_fraction(fs: FeatureSet, scan: Scan, sigma: float = 0.005) -> tuple[float, float]:
    """Fraction of valid beams whose range some line predicts within 3 ``sigma`` (m), and the RMS
    range residual (m, measured minus predicted along the beam) of those explained beams (the
    inlier RMS, as Open3D's ``fitness`` / ``inlier_rmse`` pair). A beam is explained by the lines
    whose beam span [first, last] covers it; where spans overlap the closest line counts.
    nan where undefined (no valid beam; no explained beam for the RMS).

    Raises:
        InputError: a ``sigma`` that is not a finite number > 0 (nan, zero or a negative one
            explained no beam, silently; inf every covered one), an ``fs`` that is no FeatureSet or whose lines reach past the scan's
            beams (features of another scan). ScanTypeError: a ``scan`` that is no lms200.Scan.
    """
    lines = check_measure_args(fs, scan, sigma, "sigma")
    n_valid = int(np.count_nonzero(scan.valid))
    if n_valid == 0:
        return float("nan"), float("nan")
    best = _ray_residuals(lines, scan)  # inf where no line covers a valid beam
    inlier = best <= 3.0 * sigma
    explained = int(np.count_nonzero(inlier))
    rms = float(np.sqrt(np.mean(best[inlier] ** 2))) if explained else float("nan")
    return explained / n_valid, rms


def _pose(name: str, pose: object) -> tuple[float, float, float]:
    """``pose`` as (x m, y m, theta rad) floats; InputError naming ``name`` unless three finite numbers."""
    try:
        x, y, th = (float(v) for v in pose)  # type: ignore[attr-defined]
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{name}: must be three numbers (x m, y m, theta rad), got {pose!r}") from None
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(th)):
        raise InputError(f"{name}: must be finite (x m, y m, theta rad), got {pose!r}")
    return x, y, th


def _to_frame(lines: np.ndarray, pose_from: tuple[float, float, float],
              pose_to: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lines of the sensor frame at ``pose_from`` in the sensor frame at ``pose_to``: (rho, alpha,
    midpoints (k, 2)); rho >= 0, alpha wrapped to (-pi, pi]."""
    x0, y0, t0 = pose_from
    x1, y1, t1 = pose_to
    dth = t0 - t1
    c, s = math.cos(t1), math.sin(t1)
    # origin of frame `from` expressed in frame `to`
    tx = c * (x0 - x1) + s * (y0 - y1)
    ty = -s * (x0 - x1) + c * (y0 - y1)
    alpha = lines[:, 1] + dth
    rho = lines[:, 0] + tx * np.cos(alpha) + ty * np.sin(alpha)
    flip = rho < 0
    rho = np.abs(rho)
    alpha = np.where(flip, alpha + math.pi, alpha)
    alpha = np.angle(np.exp(1j * alpha))
    mx, my = 0.5 * (lines[:, 2] + lines[:, 4]), 0.5 * (lines[:, 3] + lines[:, 5])
    cd, sd = math.cos(dth), math.sin(dth)
    mid = np.column_stack((cd * mx - sd * my + tx, sd * mx + cd * my + ty))
    return rho, alpha, mid


def repeat_counts(fs_a: FeatureSet | np.ndarray, pose_a: tuple[float, float, float],
                  fs_b: FeatureSet | np.ndarray, pose_b: tuple[float, float, float], scan_b: Scan,
                  config: RealDataConfig | None = None) -> tuple[int, int]:
    """(lines of scan a found again in scan b, lines of a still in view at b); see the module doc.

    Args:
        fs_a, fs_b: lines of two scans (sensor frames).
        pose_a, pose_b: the sensor's world poses (x m, y m, theta rad) at the two scans.
        scan_b: the second scan (for the in-view test).

    Raises:
        InputError: naming the argument: lines that are no FeatureSet or (k, 8) array (None was an
            AttributeError), a pose that is not three finite numbers.
        ScanTypeError: a ``scan_b`` that is no lms200.Scan.
    """
    cfg = _config(config)
    a, b = _lines(fs_a, "fs_a"), _lines(fs_b, "fs_b")  # (their beam spans are not used)
    if not isinstance(scan_b, Scan):
        raise not_a_scan(scan_b, "scan_b")
    pose_a, pose_b = _pose("pose_a", pose_a), _pose("pose_b", pose_b)
    if a.shape[0] == 0:
        return 0, 0
    rho, alpha, mid = _to_frame(a, pose_a, pose_b)
    bearing = np.arctan2(mid[:, 1], mid[:, 0])
    dist = np.hypot(mid[:, 0], mid[:, 1])
    idx = scan_b.beam_of(bearing)  # modulo a full turn: a 360 deg scan from 0 to 2 pi saw nothing at -pi .. 0
    inside = (idx >= 0) & (idx < len(scan_b))
    idx_c = np.clip(idx, 0, len(scan_b) - 1)
    reading = np.where(scan_b.valid[idx_c], scan_b.ranges[idx_c], np.nan)
    with np.errstate(invalid="ignore"):
        in_view = inside & (np.abs(reading - dist) <= cfg.repeat_distance_m)
    if not in_view.any():
        return 0, 0
    if b.shape[0] == 0:
        return 0, int(np.count_nonzero(in_view))
    d_alpha = np.abs(np.angle(np.exp(1j * (alpha[:, None] - b[None, :, 1]))))
    d_rho = np.abs(rho[:, None] - b[None, :, 0])
    found = ((d_alpha <= cfg.repeat_angle_rad) & (d_rho <= cfg.repeat_distance_m)).any(axis=1)
    return int(np.count_nonzero(found & in_view)), int(np.count_nonzero(in_view))
