"""numba, loaded once for every module that compiles with it (the extractors, the simulator's ray
caster and world generator, the scan matcher): ``from lms200.numba_required import numba``. Where
it cannot be loaded, the import raises the one-line ``NumbaUnavailableError`` with the fix."""

from __future__ import annotations

from .errors import NumbaUnavailableError

try:
    import numba as numba  # re-exported
except Exception as exc:  # ImportError, or a broken install (llvmlite / numpy mismatch)
    raise NumbaUnavailableError(
        "the extractors, the simulator and the scan matcher are compiled with numba, which cannot be loaded "
        f"({type(exc).__name__}: {exc}); install it with: pip install 'numba>=0.61'"
    ) from exc
