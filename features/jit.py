"""The compiler of the extractors: numba, a required dependency. ``kernel`` compiles a function
once and caches the machine code on disk between processes; division follows IEEE (x / 0 gives
inf or nan, as in numpy, never an exception)."""

from __future__ import annotations

from .errors import NumbaUnavailableError

try:
    import numba
except Exception as exc:  # ImportError, or a broken install (llvmlite / numpy mismatch)
    raise NumbaUnavailableError(
        f"the extractors are compiled with numba, which cannot be loaded ({type(exc).__name__}: {exc}); "
        "install it with: pip install 'numba>=0.61'"
    ) from exc

kernel = numba.njit(cache=True, error_model="numpy")
