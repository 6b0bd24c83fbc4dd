"""Typed configuration of the paper's sensor-coordinate extractor (method "sensor"), checked once
when it is built."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..baselines import checks
from ..noise_estimate import AUTO
from .engine import Params

CM_MODE_RANGE_MAX = 10.0  # m: a scan with a larger range_max comes in SICK cm codes (1 cm steps)
MAX_HOUGH_ANGLES = 1001  # most normal angles searched per band (bounds the accumulator)
#: acute_min_var's largest (sigma_r^2): a true corner's neighbourhood varies by tens to thousands of
#: sigma_r^2 (60 in tests/test_sensor_lines.py's room; 0.5 m of depth at 5 mm noise is 2,500); 1e300 kept no corner
MAX_ACUTE_MIN_VAR = 1e4
MAX_SIGMA_BEARING = 0.1  # rad (5.7 deg): ten beam steps at 0.5 deg; the logs read 0-5 mrad


@dataclass(frozen=True)
class SensorMethodConfig:
    """Parameters of the sensor-coordinate line and corner extractor.

    Windows and counts are in beams, distances in metres, angles in radians. The noise-scaled
    thresholds (``*_tau``) are in standard deviations of the quantity they test, derived from the
    range noise ``sigma_r``. ``"auto"`` estimates that noise from the scan itself
    (:func:`features.noise_estimate.neighbour_sigma`: the scatter of neighbouring beams about
    straight faces, with the cm codes' quantisation and the interlaced sweeps' offset); it is the
    default for cm-mode scans (range_max > 10 m, the real CARMEN logs), while mm-mode scans (the
    simulator, the LMS200 in mm mode) keep the known 5 mm. ``lmsbench compare`` resolves "auto"
    once per log (pooled over the log's scans) and the simulator's known noise for its runs.

    Raises:
        ConfigError: naming the field, when a value cannot work.
    """

    k: int = 3  # half-width of the AD / slope window (eq. 4, 6), beams
    sigma_r: float | str = 0.005  # range noise std, m (SICK mm mode: range_max <= 10 m), or "auto"
    sigma_r_cm: float | str = "auto"  # ... used instead when range_max > 10 m (SICK cm mode: the real logs), m
    min_range: float = 0.02  # ranges below this (or below the scan's range_min) are invalid, m
    ad_tau: float = 4.0  # |AD - (1 + 2 sum cos jD)| <= ad_tau * sigma_AD(beam) marks a line beam
    psi_split: float = 0.35  # a slope change |psi| above this splits a run (rad; corner_min_turn) ...
    psi_tau: float = 4.0  # ... when it also exceeds psi_tau * its noise std
    hough_subdiv: int = 4  # Log-Hough angle step = angle_increment / hough_subdiv
    hough_angles: int = 7  # number of normal angles searched in each run's band (odd)
    band_tau: float = 4.0  # band half-width in std of the run's mean slope estimate
    band_min: float = 0.004  # smallest band half-width, rad
    bin_tau: float = 3.0  # Log-Hough log-range bin half-width in range-noise std
    inlier_tau: float = 3.0  # |range residual| <= inlier_tau * sigma_r after the weighted fit
    max_chi2: float = 3.0  # largest mean squared normalised residual of an accepted line
    min_inlier_fraction: float = 0.7  # fraction of a run's beams the line must explain
    curvature_tau: float = 4.0  # reject a line whose residuals bend (parabola t-statistic) more
    min_points: int = 8  # fewest supporting beams of a line
    min_length: float = 0.15  # shortest line segment kept, m (the baselines' value)
    merge_gap: int = 4  # neighbouring lines at most this many beams apart may merge ...
    merge_tau: float = 3.0  # ... when their (rho, alpha) agree within merge_tau std
    bridge_invalid: int = 0  # invalid (+inf, nan) beams a merge may bridge; 0: they break segments
    corners: bool = True  # extract corners
    corner_min_turn: float = 0.35  # smallest change of line direction that makes a corner, rad
    corner_psi: float = 0.35  # psi must reach this fraction of the line-to-line turn near the corner
    corner_max_gap: int = 1  # most beams between the two lines' facing ends
    corner_max_dist: float = 0.15  # the intersection must lie this close to both facing ends, m
    acute_check: bool = True  # the paper's remedy: reject a corner when the variance of the ranges
    acute_min_var: float = 1.0  # of the beams within k of it is below acute_min_var * sigma_r**2
    arc_check: bool = True  # drop lines whose neighbourhood is one circle turning >= corner_min_turn (round surfaces)
    sigma_bearing: float = 0.0  # bearing noise std, rad (<= MAX_SIGMA_BEARING): the range error grows as d tan(incidence)

    def __post_init__(self) -> None:
        checks.integer("k", self.k, 1, checks.MAX_BEAMS // 2)  # a window wider than any scan taken: no line
        for name in ("sigma_r", "sigma_r_cm"):
            value = getattr(self, name)
            if not (isinstance(value, str) and value == AUTO):  # an array's != was elementwise: numpy's ValueError
                # 'AUTO' said as no number, with no word of "auto"; 1e300 or 1e-300 found no line, silently
                checks.noise_sigma(name, value, f", or '{AUTO}'")
        checks.length("min_range", self.min_range)  # 1e300: every beam invalid, no line, silently
        for name in ("ad_tau", "inlier_tau", "curvature_tau"):  # tests every line's beams must pass:
            checks.tau(name, getattr(self, name))  # 0 or 1e-300 passed none, F1 0, exit 0
        checks.tau("max_chi2", self.max_chi2, "std^2", checks.MAX_TAU**2)  # a mean squared normalised residual
        for name in ("psi_tau", "band_tau", "bin_tau", "merge_tau"):  # floored by psi_split, band_min, the step:
            checks.between(name, getattr(self, name), 0.0, checks.MAX_TAU, "std")  # any small value works
        checks.between("psi_split", self.psi_split, 0.0, math.pi, "rad")
        checks.integer("hough_subdiv", self.hough_subdiv, 1, checks.BEAM_COUNT_CAP)  # 10**400 overflowed the template size
        checks.integer("hough_angles", self.hough_angles, 1)
        if self.hough_angles % 2 == 0 or self.hough_angles > MAX_HOUGH_ANGLES:
            checks.fail("hough_angles", f"must be an odd integer in [1, {MAX_HOUGH_ANGLES}]", self.hough_angles)
        checks.angle("band_min", self.band_min, math.pi / 2)
        checks.between("min_inlier_fraction", self.min_inlier_fraction, 0.0, 1.0)
        checks.between("min_points", self.min_points, 3, checks.MAX_BEAMS, "beams")  # 1e300: no line, F1 0, exit 0
        checks.length("min_length", self.min_length)
        for name in ("merge_gap", "bridge_invalid", "corner_max_gap"):
            checks.non_negative(name, getattr(self, name), "beams")
        checks.flag("corners", self.corners)
        checks.flag("acute_check", self.acute_check)
        checks.flag("arc_check", self.arc_check)
        checks.between("corner_min_turn", self.corner_min_turn, 0.0, math.pi / 2, "rad")
        checks.between("corner_psi", self.corner_psi, 0.0, 1.0, "(a share of the turn)")  # above 0.9: ~no corner
        # as the baselines' max_distance; 2 m: 42 corners for 22; 0: within the beam spacing only
        checks.between("corner_max_dist", self.corner_max_dist, 0.0, checks.MAX_BAND_M, "m")
        checks.between("acute_min_var", self.acute_min_var, 0.0, MAX_ACUTE_MIN_VAR, "sigma_r^2")  # 1e300: no corner
        checks.between("sigma_bearing", self.sigma_bearing, 0.0, MAX_SIGMA_BEARING,
                       "rad (a bearing error of a few mrad; degrees given as radians?)")
        object.__setattr__(self, "_params", Params(
            int(self.k), float(self.ad_tau), float(self.psi_split), float(self.psi_tau), int(self.hough_subdiv),
            int(self.hough_angles), float(self.band_tau), float(self.band_min), float(self.bin_tau),
            float(self.inlier_tau), float(self.max_chi2), float(self.min_inlier_fraction), float(self.curvature_tau),
            _beams(math.ceil(self.min_points)), float(self.min_length), _beams(math.floor(self.merge_gap)),
            float(self.merge_tau), _beams(math.floor(self.bridge_invalid)), bool(self.corners),
            float(self.corner_min_turn), float(self.corner_psi), _beams(math.floor(self.corner_max_gap)), float(self.corner_max_dist), bool(self.acute_check),
            float(self.acute_min_var), bool(self.arc_check), float(self.sigma_bearing),
        ))

    @property
    def params(self) -> Params:
        """The kernels' typed record of this config (built once, in ``__post_init__``)."""
        return self._params

    def sigma_for(self, range_max: float) -> float | str:
        """The range noise std (m) for a scan with this ``range_max`` (m): ``sigma_r_cm`` for the
        SICK cm codes (range_max > 10 m), else ``sigma_r``; either may be "auto"."""
        return self.sigma_r_cm if self.noise_field(range_max) == "sigma_r_cm" else self.sigma_r

    @staticmethod
    def noise_field(range_max: float) -> str:
        """The name of the range-noise field read for a scan with this ``range_max`` (m):
        "sigma_r_cm" for the SICK cm codes (range_max > 10 m), else "sigma_r". The other field
        changes nothing on such a scan: the drivers warn when a user sets it and no scan reads it."""
        return "sigma_r_cm" if range_max > CM_MODE_RANGE_MAX else "sigma_r"


#: beam counts are capped here before the kernels' int64 fields: every count beyond any scan's
#: beams (MAX_BEAMS, 16,384) means the same, and 1e300 beams no longer overflows (OverflowError)
BEAM_COUNT_CAP = 2**31


def _beams(n: int) -> int:
    """A beam count for the kernels: ``n`` capped at BEAM_COUNT_CAP."""
    return min(n, BEAM_COUNT_CAP)
