"""numba, loaded once for every module that compiles with it (the extractors, the simulator's ray
caster and world generator, the scan matcher): ``from lms200.numba_required import numba``. Where
it cannot be loaded, the import raises the one-line ``NumbaUnavailableError`` with the fix."""

from __future__ import annotations

import os

from .errors import NumbaUnavailableError

# numba colours its error messages with colorama where that is installed (evo requires it): its first
# typing error (built while numba.cpython.listobj is imported, at the first compile) calls
# colorama.init(), whose exit handler writes "ESC[0m" to stdout when it is a terminal: a stray
# colour reset after the last line of every command that compiles (simulate, slam, figures, sweep).
# Off unless the user set it: the messages lmsbench shows are plain text anyway.
os.environ.setdefault("NUMBA_DISABLE_ERROR_MESSAGE_HIGHLIGHTING", "1")

try:
    import numba as numba  # re-exported
except Exception as exc:  # ImportError, or a broken install (llvmlite / numpy mismatch)
    raise NumbaUnavailableError(
        "the extractors, the simulator and the scan matcher are compiled with numba, which cannot be loaded "
        f"({type(exc).__name__}: {exc}); install it with: pip install 'numba>=0.61'"
    ) from exc
