"""The Scan type: one 2-D laser scan in sensor coordinates, with ROS ``sensor_msgs/LaserScan`` names.

Conventions (REP-117 and REP-103):
- ``ranges`` in metres, beam 0 first; ``+inf`` = no return within range, ``nan`` = invalid reading.
- Bearing of beam i is ``angle_min + i * angle_increment`` (rad), counter-clockwise, 0 = straight
  ahead (sensor x axis), y to the left.
"""

from __future__ import annotations

import functools
import math

from dataclasses import dataclass, field

import numpy as np

from .codes import NOT_NUMBER_ITEMS, finite_negative, float64_copy, real_numbers, unmasked
from .errors import InputError, ScanError
from .finite import fixed, overflow_text, shown

LMS200_BEAMS = 361
LMS200_RESOLUTION_RAD = np.deg2rad(0.5)
LMS200_ANGLE_MIN_RAD = -np.pi / 2
LMS200_RANGE_MAX_MM_MODE = 8.183  # m: SICK code 8183 in mm units = "above maximum"
LMS200_RANGE_MAX_CM_MODE = 81.83  # m: SICK code 8183 in cm units
ANGLE_GRID_DEG = 0.05  # every LMS2xx start angle and resolution is a multiple of 0.05 deg


#: rad: what writing an angle with 6 decimals (CARMEN loggers: -1.570796, 0.008727) can move it by, half
#: a unit of the last decimal; float32 (a bag's LaserScan) moves it by at most 2**-24 of its value
SNAP_TEXT_ERROR_RAD = 5e-7
SNAP_RELATIVE_ERROR = 1e-6  # of the value: float32 (6e-8) with room to spare
#: s: the latest stamp a Scan takes, and every log reader and writer (``lms200.records.MAX_STAMP_S``); the earliest
#: is 0. A clock is UNIX time or seconds since a run's start, and 2^32 s (2106-02-07) is the end of ROS 1's time: a
#: Scan stamped 1e300 s or -1e300 s was taken, and failed only where a log was written or SLAM's motion model stepped
MAX_STAMP_S = float(2**32)
MAX_SNAP_RAD = 4 * np.pi  # rad: larger angles are left as given (a Scan refuses them: bearings within +-2 pi)


def stamp_problem(t: float, what: str) -> str | None:
    """Why ``t`` (s) is no stamp (nan, infinite, negative or after :data:`MAX_STAMP_S`), as a message
    beginning with ``what``; None for a stamp in [0, MAX_STAMP_S]. The one wording of the rule, for a
    Scan and every log reader and writer (``lms200.records.stamp_problem``, the same function): the Scan's
    said "stamp: must be in 0 .. 2^32 s ..., as every log reader and writer takes it (...), got V s"."""
    if 0.0 <= t <= MAX_STAMP_S:
        return None
    return (f"{what} {fixed(t)} s is outside 0 .. 2^32 s ({MAX_STAMP_S:.0f} s, 2106-02-07), the stamps every log "
            "reader and writer takes: a clock's UNIX time, or seconds since the run's start")


def snap_angle(value: float) -> float:
    """Snap an angle (rad) stored with limited precision (text with 6 decimals, float32) onto the
    exact 0.05 deg grid when only that rounding can explain its distance from the grid: within
    ``SNAP_TEXT_ERROR_RAD`` + ``SNAP_RELATIVE_ERROR`` x |value|. Otherwise the value is returned
    unchanged. (A rule that also kept increments whose last beam would move by 0.1 beam or more
    kept CARMEN's 6-decimal 0.1 deg over 1801 beams off the grid, its last beam at 89.966 deg: the
    rounding of the text is the whole of that drift, and the grid value is the increment.)

    Before (a fixed 2e-5 rad), angles genuinely off the grid were snapped onto it (a review's
    reproduction): a 720-beam scan at 2 pi / 719 rad (RPLIDAR style) read as 0.5 deg, its last
    bearing 179.50 deg instead of 180.00 deg; 0.5 deg + 1.5e-5 rad lost 5.4 mrad at beam 360.
    """
    if not abs(value) <= MAX_SNAP_RAD:  # no bearing or increment a Scan takes (nan too): as given; 1e308 / step
        return float(value)  # overflowed, a RuntimeWarning on stderr above a reader's one-line error
    step = np.deg2rad(ANGLE_GRID_DEG)
    snapped = float(np.round(value / step) * step)
    if snapped == 0.0 and value != 0.0:  # 0 is exact in 6-decimal text and in float32: neither rounding
        return float(value)  # moves it; an increment of 1e-9 rad read back as 0, refused by Scan
    error = abs(snapped - value)
    if error <= 4 * np.spacing(abs(snapped)):  # on the grid to float64 precision: kept exactly as given
        return float(value)
    if error > SNAP_TEXT_ERROR_RAD + SNAP_RELATIVE_ERROR * abs(value):
        return float(value)
    return snapped


def snap_float32_angle(value: float) -> float:
    """:func:`snap_angle` for an angle stored as float32 (a bag's LaserScan): onto the 0.05 deg grid
    only when the grid angle's float32 is ``value``'s own or one float32 step from it (a driver's
    float32 arithmetic), the most float32 rounding explains; else ``value`` as given. snap_angle's
    allowance is that of 6-decimal text (5e-7 rad + 1e-6 of the value): a bag's angle_min 2e-6 rad
    off the grid (a calibrated mount, 17 float32 steps at 90 deg) was snapped onto it."""
    snapped = snap_angle(value)
    if snapped == value:
        return float(value)
    grid, given = np.float32(snapped), np.float32(value)
    if abs(float(given) - float(grid)) <= float(np.spacing(np.abs(grid))):
        return snapped
    return float(value)


@dataclass(frozen=True, eq=False)
class Scan:
    """One laser scan. Fields mirror ROS ``sensor_msgs/LaserScan``.

    Args:
        ranges: 1-D float64 array of ranges in metres, with REP-117's special values: +inf no
            return within range, -inf an object too close to measure, nan an invalid reading;
            none of the three is a valid range (``valid``), and finite negative ranges are refused.
        angle_min: bearing of beam 0 in radians (sensor frame, CCW, 0 = ahead), within +-2 pi.
        angle_increment: bearing step between beams in radians, > 0; the beams span at most 2 pi
            (a full turn), so degrees given as radians are refused.
        range_min: smallest valid range in metres (a range of 0 is never a measurement: loggers
            write 0 for a missing one, so it is invalid whatever range_min says).
        range_max: largest valid range in metres.
        stamp: time of the first beam in seconds, in [0, MAX_STAMP_S] (2^32 s, 2106-02-07), as every log
            reader and writer takes it.

    Raises:
        ScanError: (an ``LmsbenchError`` and a ``ValueError``) naming the field, when the fields are
            inconsistent or ``ranges`` are not real numbers (complex, bool, text, dates are refused,
            bools and text among the items of an object array or list too;
            the masked beams of a numpy masked array become nan, invalid).
    """

    ranges: np.ndarray
    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float
    stamp: float = 0.0
    _angles: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        a = _ranges_view(self.ranges)  # no copy yet: the shape and span are checked first
        if a.ndim != 1:
            raise ScanError(f"ranges: must be 1-D, got shape {a.shape}")
        if a.size == 0:
            raise ScanError("ranges: must hold at least one beam")
        for name in ("angle_min", "angle_increment", "range_min", "range_max", "stamp"):
            object.__setattr__(self, name, _number(name, getattr(self, name)))
        problem = stamp_problem(self.stamp, "stamp")
        if problem is not None:
            raise ScanError(problem)
        if self.angle_increment <= 0:  # a ROS LaserScan of a laser mounted upside down has a negative one
            flip = (" (beams clockwise, a laser mounted upside down: reverse the ranges, ranges[::-1], and start "
                    "at the last beam's bearing, angle_min + (n - 1) * angle_increment)") if self.angle_increment < 0 else ""
            raise ScanError(f"angle_increment: must be > 0, got {self.angle_increment}{flip}")
        if abs(self.angle_min) > MAX_BEARING_RAD:
            raise ScanError(f"angle_min: a bearing within +-2 pi rad (+-360 deg), got {self.angle_min:g} rad"
                            f"{_degrees_hint(self.angle_min, abs(np.deg2rad(self.angle_min)) <= MAX_BEARING_RAD)}")
        span = (a.size - 1) * self.angle_increment
        if span > MAX_SPAN_RAD + self.angle_increment:  # one beam more: some 360 deg drivers repeat the first
            raise ScanError(f"angle_increment: {a.size} beams {self.angle_increment:g} rad apart span {span:g} rad, "
                            f"more than a full turn (2 pi rad)"
                            f"{_degrees_hint(self.angle_increment, np.deg2rad(span) <= 2 * np.pi)}")
        if self.range_min < 0:
            raise ScanError(f"range_min: must be >= 0, got {self.range_min}")
        if self.range_max <= self.range_min:
            raise ScanError(
                f"range_max: must be > range_min ({self.range_min}), got {self.range_max}"
            )
        r = _ranges_copy(a)
        if np.any(finite_negative(r)):  # nan, +inf and -inf (REP-117) pass
            raise ScanError("ranges: negative ranges are not allowed (use nan for invalid readings, "
                            "-inf for objects too close to measure)")
        r.setflags(write=False)
        object.__setattr__(self, "ranges", r)
        object.__setattr__(self, "_angles", _bearings(self.angle_min, self.angle_increment, r.size))

    def __setstate__(self, state: dict) -> None:
        """Unpickling and ``copy.deepcopy``: the fields as pickled, the arrays read-only again as
        ``__post_init__`` left them (pickle restores arrays writable: an unpickled Scan, as a sweep's
        worker process gets it, could be changed in place, and the extractors' compiled calls saw
        a second array type)."""
        for name, value in state.items():
            object.__setattr__(self, name, value)
        for name in ("ranges", "_angles"):
            array = state.get(name)
            if isinstance(array, np.ndarray):
                array.setflags(write=False)

    # -- constructors -------------------------------------------------------------------------
    @classmethod
    def lms200(
        cls,
        ranges: np.ndarray,
        stamp: float = 0.0,
        range_max: float = LMS200_RANGE_MAX_MM_MODE,
        range_min: float = 0.0,
    ) -> "Scan":
        """The LMS200 default: 361 beams at 0.5 deg from -90 deg to +90 deg (mm mode range)."""
        r = _ranges_array(ranges)
        if r.shape != (LMS200_BEAMS,):
            raise ScanError(f"ranges: LMS200 default needs {LMS200_BEAMS} beams, got shape {r.shape}")
        return cls(r, LMS200_ANGLE_MIN_RAD, LMS200_RESOLUTION_RAD, range_min, range_max, stamp)

    # -- derived ------------------------------------------------------------------------------
    def __len__(self) -> int:
        return int(self.ranges.size)

    @property
    def angles(self) -> np.ndarray:
        """Bearing of every beam in radians (read-only array)."""
        return self._angles

    @property
    def angle_max(self) -> float:
        """Bearing of the last beam: ``angle_min + (n-1) * angle_increment`` (rad)."""
        return self.angle_min + (self.ranges.size - 1) * self.angle_increment

    @property
    def valid(self) -> np.ndarray:
        """Mask of beams with a finite return inside [range_min, range_max], and > 0 m."""
        return valid_ranges(self.ranges, self.range_min, self.range_max)

    def beam_of(self, bearings: np.ndarray) -> np.ndarray:
        """The beam index (int64) of each bearing (rad, sensor frame), counted from the first beam
        modulo a full turn (a bearing within half a beam before the first is the first's); an index
        outside [0, len(self)) is a bearing the scan does not cover. arctan2's bearings lie in
        (-pi, pi]: taken as they were, a 360 deg scan from 0 to 2 pi covered none of -pi .. 0.

        Raises:
            InputError: bearings that are not finite numbers (fuzzing: nan gave beam -2^63 and a
                RuntimeWarning, text numpy's ValueError).
        """
        try:
            b = np.asarray(unmasked(bearings), dtype=float)  # a masked bearing: nan, refused
        except (TypeError, ValueError, OverflowError):
            raise InputError(f"bearings: must be finite numbers (rad), got {shown(bearings)}") from None
        if not np.isfinite(b).all():
            raise InputError(f"bearings: must be finite numbers (rad), got {shown(bearings)}")
        half = 0.5 * self.angle_increment
        offset = np.mod(b - self.angle_min + half, 2 * np.pi) - half
        return np.rint(offset / self.angle_increment).astype(np.int64)

    @property
    def points(self) -> np.ndarray:
        """(n, 2) Cartesian points in the sensor frame (m); nan rows for beams that are not valid."""
        r = np.where(self.valid, self.ranges, np.nan)
        return np.column_stack((r * np.cos(self._angles), r * np.sin(self._angles)))

    def replace(self, **changes: object) -> "Scan":
        """A copy with some fields changed (like ``dataclasses.replace``)."""
        kw = dict(
            ranges=self.ranges,
            angle_min=self.angle_min,
            angle_increment=self.angle_increment,
            range_min=self.range_min,
            range_max=self.range_max,
            stamp=self.stamp,
        )
        unknown = sorted(set(changes) - set(kw))
        if unknown:
            raise ScanError(f"{unknown[0]}: not a Scan field (fields: {', '.join(kw)})")
        kw.update(changes)
        return Scan(**kw)  # type: ignore[arg-type]

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Scan):
            return NotImplemented
        return (
            self.angle_min == other.angle_min
            and self.angle_increment == other.angle_increment
            and self.range_min == other.range_min
            and self.range_max == other.range_max
            and self.stamp == other.stamp
            and self.ranges.shape == other.ranges.shape
            and bool(np.array_equal(self.ranges, other.ranges, equal_nan=True))
        )

    __hash__ = None  # type: ignore[assignment]


MAX_BEARING_RAD = 2 * np.pi + 1e-9  # |angle_min| at most one full turn
MAX_SPAN_RAD = 2 * np.pi * (1 + 1e-6)  # first to last beam: a full turn (a 360 deg lidar; float32 increments)


#: beams up to which the bearings of a geometry are kept and shared by every scan of it (read-only):
#: each scan held its own copy, 2.9 kB a 361-beam scan, half the memory of a run's records
#: (simulate_records of 3,600 s: 135,000 scans, 390 MB of identical bearings)
MAX_SHARED_BEARINGS = 65_536


@functools.lru_cache(maxsize=64)
def _shared_bearings(angle_min_hex: str, angle_increment_hex: str, n: int) -> np.ndarray:
    """Keyed by the floats' exact bits (``float.hex``): -0.0 equals 0.0 as a key, and a scan from
    -0.0 rad would have shared the bearings of one from 0.0, its first bearing's sign decided by
    which came first."""
    angles = float.fromhex(angle_min_hex) + np.arange(n) * float.fromhex(angle_increment_hex)
    angles.setflags(write=False)
    return angles


def _bearings(angle_min: float, angle_increment: float, n: int) -> np.ndarray:
    """The read-only bearings ``angle_min + i * angle_increment`` of n beams (rad), shared by the
    scans of one geometry (:data:`MAX_SHARED_BEARINGS`), computed for each scan beyond it."""
    if n <= MAX_SHARED_BEARINGS:
        return _shared_bearings(angle_min.hex(), angle_increment.hex(), n)
    angles = angle_min + np.arange(n) * angle_increment
    angles.setflags(write=False)
    return angles


def valid_ranges(ranges: np.ndarray, range_min: float, range_max: float) -> np.ndarray:
    """Mask of ``ranges`` (m) that are valid readings under ``range_min`` and ``range_max``: finite,
    inside [range_min, range_max] and > 0 m (:attr:`Scan.valid`'s rule, REP-117)."""
    with np.errstate(invalid="ignore"):
        return np.isfinite(ranges) & (ranges >= range_min) & (ranges > 0.0) & (ranges <= range_max)


def _degrees_hint(value: float, fits_as_degrees: bool) -> str:
    """A hint, where the value would fit read as degrees, that degrees were given as radians."""
    if not fits_as_degrees:
        return ""
    return f" (degrees given as radians? {value:g} deg is {np.deg2rad(value):.6g} rad)"


def _number(name: str, value: object) -> float:
    """A scalar field as a finite float; ScanError naming the field for text, bools (True is not
    1 rad or 1 m), non-numbers, ints beyond float64 (10**400) and nan / inf."""
    if isinstance(value, NOT_NUMBER_ITEMS):  # numpy's complex: float() gave its real part
        raise ScanError(f"{name}: must be a number, got {value!r}")
    if isinstance(value, np.ma.MaskedArray):
        if value.size != 1:  # not "a masked value (it has none)", nor numpy's repr over several lines
            raise ScanError(f"{name}: must be a number, got a masked array of {value.size} values")
        if np.ma.is_masked(value):  # float() warned, then gave nan
            raise ScanError(f"{name}: must be a number, got a masked value (it has none)")
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ScanError(f"{name}: must be a number, got {value!r}") from None
    except OverflowError:
        raise ScanError(f"{name}: must be finite, got {overflow_text(value)}") from None
    if not math.isfinite(number):  # math, not np: 12 ns against 390 ns a field (review)
        raise ScanError(f"{name}: must be finite, got {number}")
    return number


def _ranges_view(ranges: object) -> np.ndarray:
    """``ranges`` as an array of real numbers, not yet copied; ScanError naming ``ranges`` for
    values that are not real numbers (a bool, complex, text or date array would otherwise be cast
    silently: 1+1j to 1.0, True to 1.0 m), a masked array's included. The masked beams of a masked
    array become nan (invalid)."""
    return real_numbers(ranges, ScanError)  # a masked array's masked beams as nan (codes.unmasked)


def _ranges_copy(a: np.ndarray) -> np.ndarray:
    """A private float64 copy of the array ``a`` (m); ScanError naming ``ranges`` where it cannot be
    made (an object item that is no number; more beams than memory holds)."""
    try:
        return float64_copy(a, ScanError)  # a private copy: the scan is immutable
    except MemoryError:
        raise ScanError(f"ranges: {a.size} beams need {a.size * 8 / 2**30:.3g} GiB as float64, "
                        "more than this machine can allocate") from None


def _ranges_array(ranges: object) -> np.ndarray:
    """A private float64 copy of ``ranges`` (m), checked as ``Scan`` checks it (real numbers)."""
    return _ranges_copy(_ranges_view(ranges))
