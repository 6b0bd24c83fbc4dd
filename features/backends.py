"""The ``backend`` field shared by the extractors' configs: "numba" runs the compiled kernels,
"numpy" the reference, "auto" numba when it is importable. Asking does not import numba."""

from __future__ import annotations

import importlib.util

BACKENDS = ("auto", "numba", "numpy")
_NUMBA: list[bool] = []  # cached answer of numba_available


def numba_available() -> bool:
    """True when numba can be imported (found without importing it)."""
    if not _NUMBA:
        _NUMBA.append(importlib.util.find_spec("numba") is not None)
    return _NUMBA[0]


def use_numba(backend: str) -> bool:
    """Whether a config's ``backend`` ("auto", "numba", "numpy") runs the compiled kernels:
    "auto" does when numba is importable. Raises ValueError for unknown names or a missing numba."""
    if backend == "numpy":
        return False
    if backend not in BACKENDS:
        raise ValueError(f"backend: must be one of {', '.join(BACKENDS)}, got {backend!r}")
    if backend == "numba" and not numba_available():
        raise ValueError("backend: 'numba' asked for but numba is not installed (pip install numba)")
    return numba_available()
