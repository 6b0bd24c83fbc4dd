"""One conversion of a user's number to a float, shared by every package's argument checks."""

from __future__ import annotations

import numpy as np

from .errors import InputError


def float_of(value: object, name: str, error: type[Exception]) -> float:
    """``float(value)``; ``error`` naming ``name`` for an int beyond float64 (10**400: float()
    raises OverflowError). The message does not print the value: Python refuses to turn an int of
    more than 4,300 digits into text (a ValueError)."""
    try:
        return float(value)  # type: ignore[arg-type]
    except OverflowError:
        raise error(f"{name}: must be finite, got {overflow_text(value)}") from None


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


def overflow_text(value: object) -> str:
    """How a value beyond float64 is named in a message: by its type, never printed."""
    return f"a {type(value).__name__} beyond float64's range"


def check_seed(seed: object) -> None:
    """A seed is a whole number >= 0 (numpy's Generators take no other); InputError naming it.
    The simulator's, and the bootstrap's of ``lms200.noise`` and ``lms200.calibration`` (there a
    text or float seed was numpy's TypeError, -1 its ValueError: found by fuzzing)."""
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"seed: must be a whole number >= 0, got {seed!r}")


def is_number(value: object) -> bool:
    """A plain or numpy real number, not a bool (``float()`` takes text and bools as well)."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))
