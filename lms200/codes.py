"""SICK LMS200 distance codes and their REP-117 meaning.

A raw LMS200 value carries the distance in bits 0-12 (units of 1 mm or 1 cm, set by the device's
unit mode) and field-A/B/dazzle flags in bits 13-15. Codes 8183-8191 are not distances:
8183 "measured value above the maximum" means no return within range (REP-117: ``+inf``);
8186, 8187, 8189, 8190 and 8191 are invalid readings (REP-117: ``nan``). The largest valid
distance code is 8182.
"""

from __future__ import annotations

import math
from typing import Iterable, Literal

import numpy as np

from .errors import InputError
from .finite import shown

Units = Literal["mm", "cm"]

DISTANCE_MASK = 0x1FFF
CODE_ABOVE_MAXIMUM = 8183  # -> +inf
CODES_INVALID = (8186, 8187, 8189, 8190, 8191)  # -> nan
CODE_NOT_VALID = 8191  # what an invalid range is written back as
MAX_VALID_CODE = 8182
_SPECIAL_CODES = np.array((CODE_ABOVE_MAXIMUM,) + CODES_INVALID, dtype=np.float64)
METRES_PER_UNIT = {"mm": 0.001, "cm": 0.01}
# Range of the "above maximum" code (8183) in each unit mode: the LMS200's maximum range (m).
LMS200_MAX_RANGE = {"mm": 8.183, "cm": 81.83}


def check_units(units: object) -> Units:
    """``units`` if it is 'mm' or 'cm'; InputError naming ``units`` otherwise (a list or an array
    was Python's "unhashable type" TypeError, found by fuzzing ``encode_scan``)."""
    if not isinstance(units, str) or units not in METRES_PER_UNIT:
        raise InputError(f"units: must be 'mm' or 'cm', got {shown(units)}")
    return units  # type: ignore[return-value]


def metres_per_unit(units: Units) -> float:
    """Size of one distance unit in metres; raises InputError (a ValueError) for an unknown unit."""
    return METRES_PER_UNIT[check_units(units)]


def codes_to_ranges(codes: np.ndarray, units: Units = "mm") -> np.ndarray:
    """Raw LMS200 values (flag bits are masked off) to ranges in metres, the REP-117 way.

    8183 -> +inf, 8186/8187/8189/8190/8191 (and any other code above 8182) -> nan.

    Raises:
        InputError: for codes that are not raw 16-bit values (whole numbers 0..65535: nan became
            0 m, -1 nan, 1.5 1 mm, True 1 mm, 2**40 0 m, silently) or an unknown unit.
    """
    scale = metres_per_unit(units)
    c = check_codes(codes).astype(np.int64) & DISTANCE_MASK
    r = c * scale
    r = np.where(c > MAX_VALID_CODE, np.nan, r)
    return np.where(c == CODE_ABOVE_MAXIMUM, np.inf, r)


def unmasked(value: object) -> object:
    """``value`` with the masked items of a numpy masked array as nan, anything else as given: the one
    reading of a masked array wherever lms200 reads numbers (a Scan's ranges, codes, poses, trajectory rows,
    bearings, the Gymnasium env's action). A masked item has no value: nan, an invalid reading (REP-117) in
    ranges and refused where a value is needed. ``np.asarray`` drops the mask and reads the hidden data,
    silently (fuzz round 10: a Record's odometry ``[1, --, 0.5]`` read as (1.0, 0.0, 0.5), a masked action or
    trajectory row as its data). Another dtype than numbers (bool, text) is its plain array, for the caller's
    own refusal of that dtype."""
    if not isinstance(value, np.ma.MaskedArray):
        return value
    if value.dtype.kind == "f":  # in its own float type: a long double beyond float64 meets the caller's refusal as
        return np.ma.filled(value, np.nan)  # unmasked (a cast first overflowed to inf under numpy's warning)
    if value.dtype.kind in "iu":  # nan needs a float
        return np.ma.filled(value.astype(np.float64), np.nan)
    if value.dtype.kind == "O":  # masked items become nan whatever they hold; the others are checked as items
        return np.ma.filled(value, np.nan)
    return np.asarray(value.data)


def check_codes(codes: object) -> np.ndarray:
    """``codes`` as an array of raw 16-bit LMS200 values; InputError naming ``codes`` otherwise."""
    try:
        c = np.asarray(unmasked(codes))
    except (TypeError, ValueError) as exc:
        raise InputError(f"codes: must be raw LMS200 values (whole numbers 0..65535) ({exc})") from None
    if c.dtype in (np.uint16, np.uint8):  # what the protocol gives: nothing to check
        return c
    if c.dtype.kind not in "iuf":
        raise InputError(f"codes: must be raw LMS200 values (whole numbers 0..65535), got dtype {c.dtype}")
    if c.size and not (np.all(np.isfinite(c)) and np.all(c == np.rint(c)) and c.min() >= 0 and c.max() <= 0xFFFF):
        finite = c[np.isfinite(c)]  # .item(): Python numbers, not numpy 2's "np.int64(-1)" in the message
        got = f"values from {finite.min().item()!r} to {finite.max().item()!r}" if finite.size else "only nan / inf"
        raise InputError(f"codes: must be raw LMS200 values (whole numbers 0..65535), got {got}"
                         f"{' and nan / inf' if 0 < finite.size < c.size else ''}")
    return c


def real_ranges(ranges: object) -> np.ndarray:
    """``ranges`` (m) as a float64 copy; InputError naming ``ranges`` for values that are not real
    numbers (complex lost its imaginary part with a warning, text was numpy's ValueError)."""
    return float64_copy(real_numbers(ranges))


RAW_BYTE_FORMATS = ("B", "b", "c")  # a memoryview of bytes (struct formats): not numbers of metres


def real_numbers(ranges: object, error: type[Exception] = InputError) -> np.ndarray:
    """``ranges`` as an array (not copied) of real numbers: ints, floats or objects; ``error``
    naming ``ranges`` for bool, complex, text or dates (cast silently: 1+1j to 1.0, True to 1.0 m)
    and for what numpy cannot read. ``lms200.Scan`` and the code conversions read ranges by it.
    Raw bytes are refused too: a bytearray (or a memoryview of bytes) read as one metre per byte
    value, silently, while bytes were refused as text."""
    if isinstance(ranges, bytearray) or (isinstance(ranges, memoryview) and ranges.format in RAW_BYTE_FORMATS):
        raise error(f"ranges: must be real numbers (m), got {type(ranges).__name__} of raw bytes (read them as "
                    "numbers first, e.g. np.frombuffer(data, '<f4'))")
    ranges = unmasked(ranges)
    try:
        a = ranges if isinstance(ranges, np.ndarray) else np.asarray(ranges)
    except (TypeError, ValueError, OverflowError) as exc:
        raise error(f"ranges: cannot be read as float64 numbers ({exc})") from None
    check_real_kind(a.dtype, error)
    if a.dtype.kind == "O":
        check_real_items(a.flat, error)
    elif isinstance(ranges, (list, tuple)):  # [True, 1.0] is a float64 array: its True is gone
        check_real_items(ranges, error)
    return a


def real_rows(value: object, name: str, columns: int, what: str, finite: bool = True, wider: bool = False) -> np.ndarray:
    """``value`` as a float64 (k, ``columns``) array; InputError naming ``name`` for what is no
    array of real numbers of that shape, or (``finite``) holds nan / inf. Found by fuzzing the
    Python API: ``slam.metrics`` read its arrays by ``reshape(-1, 4)``, so a (12, 3) trajectory
    was scored as nine garbled (t, x, y, theta) rows, silently, and text, None or an (n, 5) array
    was numpy's bare ValueError; ``write_tum`` wrote (3k, 4) poses as 4k garbled rows. With
    ``wider``, rows may have more columns (the caller reads the first ``columns``)."""
    try:
        if value is None:  # np.asarray(None).astype(float) is nan
            raise TypeError
        a = np.asarray(unmasked(value))
        check_real_kind(a.dtype, InputError)
        a = a.astype(np.float64)
    except (InputError, TypeError, ValueError, OverflowError):
        shape = f"(k, >= {columns})" if wider else f"(k, {columns})"
        raise InputError(f"{name}: must be a {shape} array of real numbers ({what}), got "
                         f"{type(value).__name__}") from None
    if a.shape == (0,):  # an empty list: no rows (a review: map_error([], walls) was refused)
        a = a.reshape(0, columns)
    if a.ndim != 2 or a.shape[1] < columns or (a.shape[1] > columns and not wider):
        shape = f"(k, >= {columns})" if wider else f"(k, {columns})"
        raise InputError(f"{name}: must be a {shape} array ({what}), got shape {a.shape}")
    if finite and not np.isfinite(a).all():
        raise InputError(f"{name}: must be finite ({what}); row {int(np.nonzero(~np.isfinite(a).all(1))[0][0])} is not")
    return a


def real_vector(value: object, name: str, what: str, finite: bool = True) -> np.ndarray:
    """``value`` (any shape: a list, a column, a scalar) as a flat float64 array, by
    :func:`real_rows`'s checks."""
    column = value
    if value is not None and not isinstance(value, (str, bytes)):  # those refused by type name
        try:
            column = np.reshape(value, (-1, 1))  # type: ignore[call-overload]
        except (TypeError, ValueError):  # a ragged list: refused by real_rows, naming it
            pass
    return real_rows(column, name, 1, what, finite).reshape(-1)


REFUSED = "(bool, complex, text and dates are refused)"
#: float() takes them: True as 1.0 m, "2" as 2.0 m; numpy's complex as its real part, numpy's dates
#: and durations as their count of units (an object array's np.datetime64('2020-01-01') was 18262 m)
NOT_NUMBER_ITEMS = (bool, np.bool_, str, bytes, np.str_, np.bytes_, complex, np.complexfloating, np.datetime64,
                    np.timedelta64)


def check_real_kind(dtype: np.dtype, error: type[Exception] = InputError) -> None:
    """``error`` naming ``ranges`` unless ``dtype`` holds real numbers (int, float or object)."""
    if dtype.kind not in "iufO":
        raise error(f"ranges: must be real numbers (m), got dtype {dtype} {REFUSED}")


def check_real_items(items: Iterable[object], error: type[Exception] = InputError) -> None:
    """``error`` naming ``ranges`` and the first item that is a bool, text or None: the items of an
    object array, or of a list or tuple, which numpy casts to float64 silently (True became 1.0 m,
    "2" 2.0 m), while a bool or text array is refused by its dtype (:func:`check_real_kind`).
    Nested lists are left to the shape check."""
    for i, v in enumerate(items):
        if isinstance(v, np.ndarray) and v.ndim == 0:  # a 0-d array (np.array(True)) is its one item
            v = v.item()
        if isinstance(v, NOT_NUMBER_ITEMS):
            raise error(f"ranges: must be real numbers (m), got {type(v).__name__} {v!r} at index {i} {REFUSED}")
        if v is None:  # numpy casts it to nan: Scan([1.0, None]), decode_logged_ranges(None) passed, silently
            raise error(f"ranges: must be real numbers (m), got None at index {i} (an invalid reading is nan)")


def float64_copy(a: np.ndarray, error: type[Exception] = InputError) -> np.ndarray:
    """A private float64 copy of ``a``; ``error`` naming ``ranges`` for an object item that is no
    number, and for a finite number beyond float64's range (a long double's 1e4000, an object
    array's ``Decimal("1e400")``), which the cast made +inf, REP-117's no return, silently (the
    CARMEN reader refuses its 1e400 so)."""
    try:
        # a float32's (a long double's) signalling nan casts to a nan, REP-117's invalid reading, but numpy
        # warned "invalid value encountered in cast" (two lines on stderr) for it: ignored
        if a.dtype.kind == "O" or a.dtype.itemsize > 8:  # a long double beyond float64: FloatingPointError, not inf
            with np.errstate(over="raise", invalid="ignore"):
                r = np.array(a, dtype=np.float64)
        elif a.dtype.kind == "f" and a.dtype.itemsize < 8:  # float32, float16: no cast overflows
            with np.errstate(invalid="ignore"):
                r = np.array(a, dtype=np.float64)
        else:  # float64, ints: no cast overflows nor warns (and no errstate, on every scan read)
            r = np.array(a, dtype=np.float64)
    except FloatingPointError:
        raise error(f"ranges: a number beyond float64's range (dtype {a.dtype}) would read as inf") from None
    except (TypeError, ValueError, OverflowError) as exc:
        raise error(f"ranges: cannot be read as float64 numbers ({exc})") from None
    if a.dtype.kind == "O" and a.size and np.isinf(r).any():  # float(Decimal("1e400")) is inf, silently
        for i in np.flatnonzero(np.isinf(r)):
            item = a.flat[i]
            if not _is_infinite(item):
                raise error(f"ranges: {type(item).__name__} at index {i} is beyond float64's range "
                            "(it would read as inf)")
    return r


def _is_infinite(item: object) -> bool:
    """Whether an object array's item is itself infinite (``float("inf")``, ``Decimal("Infinity")``),
    not a finite number that float() makes infinite."""
    try:
        return bool(item == math.inf or item == -math.inf)
    except (TypeError, ValueError):
        return False


def finite_negative(ranges: np.ndarray) -> np.ndarray:
    """Mask of the ranges that are negative numbers, which no reader or Scan takes (REP-117's
    -inf, an object too close to measure, is not one of them; nan and +inf neither)."""
    r = np.asarray(ranges, dtype=np.float64)
    return np.isfinite(r) & (r < 0)


def ranges_to_codes(ranges: np.ndarray, units: Units = "mm") -> np.ndarray:
    """Ranges in metres to LMS200 distance codes (uint16), the inverse of :func:`codes_to_ranges`.

    +inf and ranges beyond the largest code -> 8183; nan and -inf (REP-117: too close to
    measure, which the LMS200 has no code for: it reads such an object as not valid) -> 8191.
    Ranges are rounded to the unit.

    Raises:
        InputError: (a ValueError) for finite negative ranges, ranges that are not real numbers, an unknown unit.
    """
    scale = metres_per_unit(units)
    r = real_ranges(ranges)
    if np.any(finite_negative(r)):
        raise InputError("ranges: negative ranges have no LMS200 code")
    with np.errstate(invalid="ignore", over="ignore"):
        c = np.rint(np.where(np.isfinite(r), r, 0.0) / scale)
    c = np.where(c > MAX_VALID_CODE, CODE_ABOVE_MAXIMUM, c)
    c = np.where(np.isposinf(r), CODE_ABOVE_MAXIMUM, c)
    c = np.where(np.isnan(r) | np.isneginf(r), CODE_NOT_VALID, c)
    return c.astype(np.uint16)


#: m: the largest range an mm-mode reading can hold (code 8191 of the special band, plus rounding)
MM_MODE_MAX_READING = 8.1915
#: Readings above MM_MODE_MAX_READING that an mm-mode scan may hold as junk (a logger's over-range
#: value, a damaged number): more than this many, and more than MM_JUNK_SHARE of the readings, make
#: the scan cm mode. One such reading read a whole mm-mode line in cm (8.183 m no-returns as echoes).
MM_JUNK_READINGS = 3
MM_JUNK_SHARE = 0.02


def infer_units(values: np.ndarray) -> Units:
    """Guess the LMS unit mode of logged ranges (m) that carry no unit field, by the bulk of the
    readings (the finite ones > 0: a 0 is no reading and lies on every grid), not by one of them.

    cm mode when most readings sit on the 1 cm grid (a SICK in cm mode writes nothing else; an
    mm-mode scan has about one in ten there by chance), or when more than a few (MM_JUNK_READINGS
    and MM_JUNK_SHARE of them) lie above the mm-mode maximum (> 8.1915 m: a foreign scanner's log
    in mm steps to 30 m); mm mode otherwise (readings with millimetre digits, all but a few junk
    ones below 8.192 m), and for no reading at all, cm. Before, one reading above 8.1915 m made a
    scan cm mode, and one reading off the cm grid an mm-mode one.
    """
    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v) & (v > 0.0)]
    if v.size == 0:
        return "cm"
    with np.errstate(over="ignore", invalid="ignore"):  # 1e308 m in cm is inf: off the grid
        on_cm_grid = np.abs(v * 100.0 - np.rint(v * 100.0)) <= 1e-4
    if 2 * np.count_nonzero(on_cm_grid) > v.size:
        return "cm"
    over = np.count_nonzero(v > MM_MODE_MAX_READING)
    return "cm" if over > max(MM_JUNK_READINGS, MM_JUNK_SHARE * v.size) else "mm"


def decode_logged_ranges(ranges: np.ndarray, units: Units | None = None) -> np.ndarray:
    """Map SICK special codes stored as plain ranges in logs (CARMEN) to REP-117 values.

    CARMEN loggers write the raw code times the unit: 81.83 / 81.91 m in cm mode, 8.183 / 8.191 m
    in mm mode. A range that is exactly such a code of ``units`` (inferred with
    :func:`infer_units` when None) becomes +inf (8183) or nan (8186, 8187, 8189, 8190, 8191);
    every other range is returned unchanged.
    """
    values = real_ranges(ranges)
    scale = metres_per_unit(units or infer_units(values))
    with np.errstate(invalid="ignore", over="ignore"):  # 1e308 m / 1 cm is inf: not a code, kept as it is
        code_float = values / scale
        code = np.rint(code_float)
        special = (np.abs(code_float - code) < 1e-3) & np.isin(code, _SPECIAL_CODES)
    out = values.copy()
    out[special] = np.where(code[special] == CODE_ABOVE_MAXIMUM, np.inf, np.nan)
    return out
