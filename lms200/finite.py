"""One conversion of a user's number to a float, shared by every package's argument checks."""

from __future__ import annotations


def float_of(value: object, name: str, error: type[Exception]) -> float:
    """``float(value)``; ``error`` naming ``name`` for an int beyond float64 (10**400: float()
    raises OverflowError). The message does not print the value: Python refuses to turn an int of
    more than 4,300 digits into text (a ValueError)."""
    try:
        return float(value)  # type: ignore[arg-type]
    except OverflowError:
        raise error(f"{name}: must be finite, got {overflow_text(value)}") from None


def overflow_text(value: object) -> str:
    """How a value beyond float64 is named in a message: by its type, never printed."""
    return f"a {type(value).__name__} beyond float64's range"
