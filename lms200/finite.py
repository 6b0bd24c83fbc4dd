"""One conversion of a user's number to a float, shared by every package's argument checks."""

from __future__ import annotations

import math
import numbers
from typing import Any, Iterable

import numpy as np

from .errors import InputError


def float_of(value: object, name: str, error: type[Exception]) -> float:
    """``float(value)``; ``error`` naming ``name`` for an int beyond float64 (10**400: float()
    raises OverflowError). The message does not print the value: Python refuses to turn an int of
    more than 4,300 digits into text (a ValueError). A complex number is ``error`` too: numpy's
    (``np.complex128(1+1j)``) gave its real part, with a warning (Python's was float()'s TypeError)."""
    if isinstance(value, (complex, np.complexfloating)):
        raise error(f"{name}: must be a real number, got {type(value).__name__} {value!r}")
    try:
        return float(value)  # type: ignore[arg-type]
    except OverflowError:
        raise error(f"{name}: must be finite, got {overflow_text(value)}") from None


def printable(text: str) -> str:
    """``text`` with each lone surrogate (an undecodable byte of a path, as ``os.fsdecode`` gives it)
    written as its escape (``\\udcff``), as stderr shows it: UTF-8 (a report, a YAML header, a table's
    text column, a figure's title) cannot hold one, and a run on ``b<0xff>.clf`` failed after its work."""
    return text.encode("utf-8", "backslashreplace").decode("utf-8")


def shown(value: object, most: int = 60) -> str:
    """A user's value for a one-line message: its repr on one line (a 2-D array's took two), cut
    to its start and end and its length past ``most`` characters (as the command line's
    ``shorten_quoted``: a 400-digit address was echoed whole). An int too long to print (more
    than 4,300 digits: Python refuses) is named by its size."""
    try:
        text = " ".join(repr(value).split())
    except ValueError:
        kind = type(value).__name__
        return f"{'an' if kind[0] in 'aeiou' else 'a'} {kind} of more than 4300 digits"
    return text if len(text) <= most else f"{text[:40]}...{text[-8:]} ({len(text)} characters)"


#: magnitude from which :func:`fixed` writes a number with an exponent: a float64 holds no digit after
#: the point there (its spacing at 1e15 is 0.125), and a stamp of 1e308 written with 6 decimals was 315 characters
FIXED_MAX = 1e15


def fixed(value: float, decimals: int = 6) -> str:
    """A number for a message as ``f"{value:.{decimals}f}"`` (a stamp 1700000000.123456 s), but with
    an exponent from ``FIXED_MAX`` on (``1e+308``, ``%.{decimals}g``): a stamp near 1e308 was
    quoted with its 309 digits (nan and inf as such); and a value not 0 that so many decimals show
    as 0 in significant digits (``1e-288``, ``%.{decimals}g``): an angle increment of 1e-290 rad was
    "0.0000 deg", a value no one had given."""
    value = float(value)
    if math.isfinite(value) and (abs(value) >= FIXED_MAX or 0 < abs(value) < 0.5 * 10.0 ** -decimals):
        return f"{value:.{max(decimals, 1)}g}"
    return f"{value:.{decimals}f}"


def underflow_problem(text: str, value: float) -> str | None:
    """Why the number ``text``, which ``float()`` read as ``value``, is refused, or None: written
    nonzero (a digit 1-9 before its exponent) but read as 0.0, being below float64's smallest
    nonzero magnitude (4.9e-324): ``noise_sigma: 1e-400`` in a settings file, or ``--clutter
    1e-400``, ran as 0 without a word (a noise-free run, an empty office)."""
    if value != 0.0:
        return None
    written = text.strip()
    mantissa = written.lower().split("e", 1)[0]
    if not any(c in "123456789" for c in mantissa):
        return None
    return f"{written} rounds to 0 in float64 (its smallest nonzero number is 4.9e-324); write 0 for zero"


def overflow_text(value: object) -> str:
    """How a value beyond float64 is named in a message: by its type, never printed ("an int", "a Fraction")."""
    name = type(value).__name__
    return f"{'an' if name[:1].lower() in 'aeiou' else 'a'} {name} beyond float64's range"


#: the largest seed anything takes (64 bits): a world.json's seed must be one the simulator wrote,
#: and a seed of 400 digits was kept and written again (the command line's --seed stays 32 bits)
MAX_SEED = 2**64 - 1


def check_seed(seed: object) -> None:
    """A seed is a whole number in [0, ``MAX_SEED``] (numpy's Generators take no other sign or
    kind); InputError naming it. The simulator's, and the bootstrap's of ``lms200.noise`` and
    ``lms200.calibration`` (there a text or float seed was numpy's TypeError, -1 its ValueError:
    found by fuzzing)."""
    problem = seed_problem(seed)
    if problem is not None:
        raise InputError(f"seed: {problem}")


def seed_problem(seed: object) -> str | None:
    """Why ``seed`` is no seed (``check_seed``'s rule), or None."""
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or seed < 0:
        return f"must be a whole number >= 0, got {shown(seed)}"
    if seed > MAX_SEED:
        return f"must be a whole number >= 0 and at most 2^64 - 1 (64 bits), got {shown(seed)}"
    return None


def is_number(value: object) -> bool:
    """A real number of any numeric type (int, float, numpy's, ``fractions.Fraction``: any
    ``numbers.Real``), not a bool (``float()`` takes text and bools as well). A review found
    ``frame_seconds(Fraction(1, 2), 9600)`` refused, which worked before the argument checks."""
    if isinstance(value, (int, float, np.integer, np.floating)):
        return not isinstance(value, (bool, np.bool_))
    return isinstance(value, numbers.Real)


def is_one_of(value: object, names: Iterable[str]) -> bool:
    """``value`` is one of ``names`` (a str): ``value in names`` of a numpy array compared item by item, and was numpy's
    "truth value of an array with more than one element is ambiguous" ValueError (fuzz round 10: write_log's ``fmt``,
    SensorConfig's ``units``, SlamConfig's ``preset``, register's ``backend``, sim2real's ``world``)."""
    return isinstance(value, str) and value in names


def digit_limit_problem(exc: BaseException) -> str | None:
    """How to say ``exc`` when it is Python's limit on converting a whole number's digits (``int("9" * 5000)``:
    "Exceeds the limit (4300 digits) for integer string conversion ...; use sys.set_int_max_str_digits()",
    advice to a programmer), else None: the one test of it (world.json, YAML settings)."""
    import sys

    if isinstance(exc, ValueError) and "integer string conversion" in str(exc):
        return f"a whole number of more than {sys.get_int_max_str_digits()} digits"
    return None


def is_integer(value: object) -> bool:
    """A plain or numpy int, not a bool (``0 <= address`` took a float, and 2.5 then failed in struct)."""
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def whole_number(v: object) -> int | None:
    """``v`` as an int when it is a whole number (an int, or a float with a whole value, numpy's
    too; no bool) within int64's range, else None: a count or index held as a float (361.0, a
    hand-built Line's 49.0) is one; 2.5, nan, 10**400 and a bool are not."""
    if isinstance(v, (bool, np.bool_)):
        return None
    if isinstance(v, (int, np.integer)):
        i = int(v)
    elif isinstance(v, (float, np.floating)) and np.isfinite(v) and float(v).is_integer():
        i = int(v)
    else:
        return None
    return i if -2**63 <= i < 2**63 else None


def check_integer(value: object, name: str, lo: int, hi: int | None = None, what: str = "", *,
                  strict: bool = False) -> int:
    """``value`` as an int in [lo, hi] (hi None: int64's bound): a count or index, a whole float
    or numpy int included (:func:`whole_number`: ``scan_geometry(361.0)`` worked before these
    checks); with ``strict``, a plain or numpy int only (a telegram's byte: ``bytes()`` and struct
    took no float before either). InputError naming ``name`` otherwise (2.5, a bool, text, None, a
    list or an array were Python's TypeError or struct.error). Callers use the int returned (a
    float does not pack)."""
    i = whole_number(value) if not strict or is_integer(value) else None
    if i is None or i < lo or (hi is not None and i > hi):
        beyond = (hi is None and not isinstance(value, (bool, np.bool_))
                  and isinstance(value, (int, float, np.integer, np.floating)) and value >= 2**63)
        # int64's bound said where it refused: max_scans=10**29 was "must be an integer >= 1, got 10**29" (round 7)
        span = f"in {lo}..{hi}" if hi is not None else f"in {lo}..2^63 - 1" if beyond else f">= {lo}"
        raise InputError(f"{name}: must be an integer {span}{' ' + what if what else ''}, got {shown(value)}")
    return i


def check_number(value: object, name: str, lo: float, hi: float, *, lo_open: bool = False, unit: str = "",
                 finite: bool = True) -> float:
    """``value`` as a float in [lo, hi] ((lo, hi] with ``lo_open``), finite unless ``finite`` is
    False (then +-inf within the bounds is taken, nan never); InputError naming ``name`` otherwise (a
    bool, text, a list, nan, or an int beyond float's range included)."""
    ok, overflow = is_number(value), False
    try:
        number = float(value) if ok else math.nan  # type: ignore[arg-type]
    except OverflowError:  # 10**400 is no float
        number, overflow = math.nan, True
    inside = not math.isnan(number) and (finite is False or math.isfinite(number)) \
        and (lo < number if lo_open else lo <= number) and number <= hi
    if not inside:
        if hi < math.inf:
            span = f" in {'(' if lo_open else '['}{lo:g}, {hi:g}]{' ' + unit if unit else ''}"
        elif lo > -math.inf:
            span = f" {'>' if lo_open else '>='} {lo:g}{' ' + unit if unit else ''}"
        else:
            span = f" ({unit})" if unit else ""
        kind = "a finite number" if finite else "a number"
        raise InputError(f"{name}: must be {kind}{span}, got {overflow_text(value) if overflow else shown(value)}")
    return number


def check_instance(value: Any, cls: type, name: str, optional: bool = True) -> None:
    """``value`` is a ``cls`` (or None when ``optional``); InputError naming ``name`` otherwise
    (a dict for a SensorConfig was an AttributeError deep inside; an empty dict for an
    OdometryConfig was taken as none, silently; a number for the virtual LMS200's Faults an
    AttributeError). The message names the class by its package (``sim.SensorConfig``)."""
    if (value is None and optional) or isinstance(value, cls):
        return
    raise InputError(f"{name}: must be a {cls.__module__.split('.')[0]}.{cls.__name__}"
                     f"{' or None' if optional else ''}, got {type(value).__name__}")
