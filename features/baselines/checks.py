"""Value checks for the extractors' configs: each raises ConfigError with a message that starts
with the field's name, so a bad sweep value fails when the config is built, with what to fix,
instead of deep inside an extractor (a ZeroDivisionError, a numpy shape error)."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import math

import numpy as np

from lms200.finite import is_number as is_real  # a plain or numpy number, not a bool
from lms200.finite import shown

from ..errors import ConfigError

MAX_BEAMS = 1 << 14  # most beams of a scan the extractors take (bounds the memory of one call)
#: largest range noise sigma (m) a baseline takes: a line's covariance is sigma^2 over the scatter
#: of its points, and sigma = 1e300 m overflowed it to inf (fuzzing: 6 of 4,000 calls)
MAX_SIGMA_M = 1000.0
#: smallest range noise sigma (m) an extractor takes: a micrometre, far below any rangefinder's
#: (compare floors the simulator's noise here too); sigma_r = 1e-300 m made every noise-scaled
#: threshold 0 and found no line, F1 0, exit 0 (the fuzz round)
MIN_SIGMA_M = 1e-6
#: longest length (m) a length field (min_length, min_range) may give: 10 km, beyond any scanner's
#: reach (the LMS200 reads 81.9 m at most); min_length = 1e300 kept no line, silently
MAX_LENGTH_M = 1e4
#: bounds (m) of a Hough cell or an inlier band (hough rho_step, band_coarse, band_fine; ransac
#: inlier_band): a tenth of the LMS200's 1 mm range step to 1 m, coarser than a wall is thick; a
#: band of 1e-300 m or a cell of 1e300 m found no line, F1 0, exit 0
MIN_BAND_M, MAX_BAND_M = 1e-4, 1.0
#: most noise-scaled multiple (split_merge / iepf split_sigmas, merge_sigmas): 100 standard
#: deviations, far beyond any beam noise reaches; 1e300 made the threshold overflow-capped and every
#: scan one line across its corners (office: F1 0.78, exit 0), and 0 (off, the fixed threshold alone)
#: or at least 1: 1e-300 was 0 in all but name, 0.5 a merge test that noise alone fails
MAX_SIGMAS = 100.0
#: smallest noise-scaled threshold of a test that a line's beams must pass (the sensor method's
#: ad_tau, inlier_tau, curvature_tau in std; max_chi2 in std^2, a mean squared normalised residual):
#: 0 passed no beam and 0.5 too few (inlier_tau 0.5: tp 0, fp 10 on the 3 test rooms; 1.0: tp 13),
#: while each at 1 still finds the room's walls (tests/test_baselines.py)
MIN_TAU = 1.0
#: largest noise-scaled threshold (std; max_chi2 its square): a Gaussian never reaches 100 std, so a
#: larger one means the same; 1e300 passed anything, noise or not (sensor inlier_tau: office line F1
#: 0.77 against 0.99, merge_tau 0.62 and no corner, exit 0)
MAX_TAU = 100.0
#: smallest adaptive breakpoint angle lambda (rad): 1 deg, the LMS200's coarsest beam step; a lambda
#: below a scan's step connects no two beams (1e-300: no line at all, F1 0, exit 0)
MIN_LAMBDA = math.radians(1.0)
#: most rounds in a row without a line (hough, ransac max_failures): each is a full search over the
#: points left, and max_failures = 1.7e8 ran for hours (a 542-beam scan: 34 ms a round at 16,384 beams)
MAX_FAILURES = 100
#: beam counts (min_points, max_skip, max_gap_beams) are capped here before the kernels' int64
#: fields: any count beyond a scan's beams means the same, and 10**30 no longer overflows
BEAM_COUNT_CAP = 2**31


def beams(n: int) -> int:
    """A beam count for the kernels: ``n`` capped at BEAM_COUNT_CAP."""
    return min(int(n), BEAM_COUNT_CAP)


def fail(name: str, requirement: str, value: object) -> None:
    """Raise the ConfigError ``"<name>: <requirement>, got <value>"``, the value on one line
    (``lms200.finite.shown``; a 2-D array's repr spanned lines: ``rpe(delta=trajectory)``, fuzzing)."""
    raise ConfigError(f"{name}: {requirement}, got {shown(value, MAX_SHOWN)}")


MAX_SHOWN = 200  # characters of a value quoted in a ConfigError (longer: its start, end and length)


def finite(value: object) -> bool:
    """``math.isfinite(value)``, False for an int beyond float64 (10**400 raised OverflowError)."""
    try:
        return math.isfinite(value)  # type: ignore[arg-type]
    except OverflowError:
        return False


def integer(name: str, value: object, minimum: int, maximum: int | None = None) -> None:
    """``value`` must be an integer (not a bool) >= ``minimum`` (and <= ``maximum``, if given)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < minimum \
            or (maximum is not None and value > maximum):
        fail(name, f"must be an integer >= {minimum}" + (f" and <= {maximum}" if maximum is not None else ""), value)


def positive(name: str, value: object, unit: str) -> None:
    """``value`` must be a finite number > 0 (in ``unit``)."""
    if not is_real(value) or not (finite(value) and value > 0):
        fail(name, f"must be a finite number > 0 {unit}", value)


def non_negative(name: str, value: object, unit: str = "") -> None:
    """``value`` must be a finite number >= 0 (in ``unit``)."""
    if not is_real(value) or not (finite(value) and value >= 0):
        fail(name, f"must be a finite number >= 0{' ' + unit if unit else ''}", value)


def between(name: str, value: object, low: float, high: float, unit: str = "") -> None:
    """``value`` must be a number in [low, high] (in ``unit``)."""
    if not is_real(value) or not (low <= value <= high):
        fail(name, f"must be a number in [{low:g}, {high:g}]{' ' + unit if unit else ''}", value)


def angle(name: str, value: object, high: float, low_open: bool = True) -> None:
    """``value`` must be an angle in (0, ``high``] rad (``low_open``) or [0, high) rad."""
    ok = is_real(value) and ((0 < value <= high) if low_open else (0 <= value < high))
    if not ok:
        fail(name, f"must be an angle in {'(0' if low_open else '[0'}, {high:.6g}{']' if low_open else ')'} rad", value)


def noise_sigma(name: str, value: object, also: str = "") -> None:
    """``value`` must be a range noise std in [MIN_SIGMA_M, MAX_SIGMA_M] m."""
    if not is_real(value) or not (finite(value) and MIN_SIGMA_M <= value <= MAX_SIGMA_M):
        fail(name, f"must be a range noise std in [{MIN_SIGMA_M:g}, {MAX_SIGMA_M:g}] m{also}", value)


def length(name: str, value: object) -> None:
    """``value`` must be a length in [0, MAX_LENGTH_M] m."""
    if not is_real(value) or not (finite(value) and 0 <= value <= MAX_LENGTH_M):
        fail(name, f"must be a length in [0, {MAX_LENGTH_M:g}] m", value)


def band(name: str, value: object) -> None:
    """``value`` must be a cell or band width in [MIN_BAND_M, MAX_BAND_M] m."""
    if not is_real(value) or not (finite(value) and MIN_BAND_M <= value <= MAX_BAND_M):
        fail(name, f"must be a width in [{MIN_BAND_M:g}, {MAX_BAND_M:g}] m", value)


def sigmas(name: str, value: object) -> None:
    """``value`` must be 0 (off) or a number of standard deviations in [MIN_TAU, MAX_SIGMAS]."""
    if not is_real(value) or not (value == 0 or MIN_TAU <= value <= MAX_SIGMAS):
        fail(name, f"must be 0 (off) or a number in [{MIN_TAU:g}, {MAX_SIGMAS:g}] std", value)


def tau(name: str, value: object, unit: str = "std", high: float = MAX_TAU) -> None:
    """``value`` must be a number in [MIN_TAU, ``high``] (in ``unit``)."""
    if not is_real(value) or not (finite(value) and MIN_TAU <= value <= high):
        fail(name, f"must be a number in [{MIN_TAU:g}, {high:g}] {unit}", value)


def breakpoint_angle(name: str, value: object) -> None:
    """``value`` must be an adaptive breakpoint angle in [MIN_LAMBDA, pi / 2] rad."""
    if not is_real(value) or not (MIN_LAMBDA <= value <= math.pi / 2):
        fail(name, f"must be an angle in [{MIN_LAMBDA:.6g}, {math.pi / 2:.6g}] rad (1 to 90 deg)", value)


def flag(name: str, value: object) -> None:
    """``value`` must be a bool."""
    if not isinstance(value, (bool, np.bool_)):
        fail(name, "must be True or False", value)


def choice(name: str, value: object, allowed: tuple[str, ...]) -> None:
    """``value`` must be one of ``allowed``."""
    if value not in allowed:
        fail(name, f"must be one of {', '.join(allowed)}", value)


def plain_numbers(cfg: object) -> None:
    """Each number field of the dataclass ``cfg`` as a plain Python int or float, called once every
    check of ``cfg`` has run (so that a ConfigError quotes the value given, and a check sees it
    unrounded): an integer of a numpy type as ``int``, any other real number (a numpy float, a
    ``Fraction``) as ``float``, the nearest float64 where it is not exactly one (``Fraction(1, 3)``:
    0.3333333333333333); bools, text and other values kept. A value beyond float64's range, or
    nonzero but rounding to 0 in it, raises ConfigError naming the field (it raised OverflowError,
    or ran as 0, i.e. off). The numpy-vectorised methods (hough, ransac) did their arithmetic in the
    type given: ``hypotheses=np.uint8(3)`` overflowed at the first scan (OverflowError: 361 out of
    bounds for uint8), ``alpha_step`` or ``breakpoint_lambda`` given as a ``Fraction`` made object
    arrays that np.cos / np.sin refused (TypeError), each after the config was taken (a probe of
    odd but valid values)."""
    for f in dataclasses.fields(cfg):  # type: ignore[arg-type]
        value = getattr(cfg, f.name)
        if type(value) in (int, float) or isinstance(value, (bool, np.bool_)) or not is_real(value):
            continue
        if isinstance(value, (int, np.integer)):
            object.__setattr__(cfg, f.name, int(value))
            continue
        try:
            plain = float(value)
        except OverflowError:
            fail(f.name, "must be a number within float64's range (up to 1.8e308)", value)
        if isinstance(value, np.floating) and math.isinf(plain) and np.isfinite(value):  # a longdouble: inf
            fail(f.name, "must be a number within float64's range (up to 1.8e308)", value)
        if plain == 0.0 and value != 0:
            fail(f.name, "is nonzero but rounds to 0 in float64 (its smallest nonzero number is 4.9e-324); "
                 "write 0 for zero", value)
        object.__setattr__(cfg, f.name, plain)


def shared_fields(cfg: object) -> None:
    """The checks of the fields every baseline has: sigma, breakpoint_lambda, min_points, min_length,
    max_skip, runs_z, corners. The caller runs ``plain_numbers`` once its own checks are done."""
    noise_sigma("sigma", cfg.sigma)
    breakpoint_angle("breakpoint_lambda", cfg.breakpoint_lambda)
    integer("min_points", cfg.min_points, 2)
    length("min_length", cfg.min_length)
    integer("max_skip", cfg.max_skip, 1)
    sigmas("runs_z", cfg.runs_z)  # 1e-300 (0.5) dropped straight walls: office line F1 0.77 (0.85), exit 0
    from .common import CornerConfig  # noqa: PLC0415 (common imports this module)

    if isinstance(cfg.corners, Mapping):  # from a YAML config or --set METHOD.corners.FIELD=V: the corner step's fields
        known = [f.name for f in dataclasses.fields(CornerConfig)]
        unknown = [k for k in cfg.corners if k not in known]
        if unknown:
            fail("corners", f"has no field {unknown[0]!r} (its fields: {', '.join(known)})", dict(cfg.corners))
        try:
            corners = CornerConfig(**cfg.corners)
        except ConfigError as exc:  # "sigma: ..." named no step: the method's own sigma has that name too
            raise ConfigError(f"corners.{exc}") from None
        object.__setattr__(cfg, "corners", corners)
    if not isinstance(cfg.corners, CornerConfig):
        fail("corners", "must be a CornerConfig (or a mapping of its fields)", cfg.corners)
