"""The compiler of the extractors: numba, a required dependency. ``kernel`` compiles a function
once and caches the machine code on disk between processes; division follows IEEE (x / 0 gives
inf or nan, as in numpy, never an exception). Compiled code runs without Python's GIL, so that
``features.extract_many``'s threads extract in parallel (a kernel touches no Python object)."""

from __future__ import annotations

from lms200.angles import wrap_scalar
from lms200.errors import in_chain
from lms200.numba_required import numba

kernel = numba.njit(cache=True, error_model="numpy", nogil=True)
# a small helper called per run, per line or per partition round: inlined into its callers in
# numba's IR, so that the arrays it is passed are not reference-counted at each call (two atomic
# operations per array argument: ~11 % of the sensor kernel's time went to NRT_incref / NRT_decref)
inline_kernel = numba.njit(cache=True, error_model="numpy", nogil=True, inline="always")
#: the project's one angle wrap (``lms200.angles.wrap_scalar``) compiled, for every kernel: the
#: extractors' and the scan matcher's; a float in (rad), a float out in (-pi, pi]
wrap_one = kernel(wrap_scalar)



#: a stop signal's handler (``experiments.cli``) that landed in numba's own Python code inside a
#: compiled call sets this: the next FixedTypeCall to return raises the KeyboardInterrupt, outside
#: the compiled code (one global read per call), and clears it (``raise_pending_stop``)
stop_pending = False


def raise_pending_stop() -> None:
    """Raise the stop a signal handler left pending (``stop_pending``), once: the flag is cleared first."""
    global stop_pending
    stop_pending = False
    raise KeyboardInterrupt


class FixedTypeCall:
    """A compiled kernel called at one call site whose argument types never change (the
    extractors' ``extract_scan``: a Scan's read-only float64 ranges, Python floats, the records).
    The first call goes through numba's dispatcher and keeps the compiled entry point of those
    types; later calls go to it directly, skipping the per-call type dispatch (~3 us, a tenth of
    a fast extraction). The caller guarantees the types (floats as ``float``, arrays as built).
    A stop left pending while the call ran (``stop_pending``) is raised as it returns."""

    __slots__ = ("dispatcher", "entry")

    def __init__(self, dispatcher: numba.core.registry.CPUDispatcher) -> None:
        self.dispatcher = dispatcher
        self.entry = None

    def __call__(self, *args: object) -> object:
        try:
            out = self.entry(*args) if self.entry is not None else self._first(*args)
        except SystemError as exc:
            ki = interrupted(exc)
            if ki is exc:  # a genuine SystemError: as it was, its cause and context kept
                raise
            raise ki from None
        if stop_pending:
            raise_pending_stop()
        return out

    def _first(self, *args: object) -> object:
        """The call through the dispatcher, which keeps the compiled entry point of these types."""
        out = self.dispatcher(*args)
        types = tuple(self.dispatcher.typeof_pyval(a) for a in args)
        compiled = self.dispatcher.overloads.get(types)
        if compiled is not None:
            self.entry = compiled.entry_point
        return out


def interrupted(exc: SystemError) -> BaseException:
    """What a compiled call's SystemError stands for: Ctrl-C landing while the kernel ran Python code
    of numba's (``_numba_unpickle``) came out as "SystemError: <built-in method extract_batch ...> returned
    a result with an exception set", five chained tracebacks over the KeyboardInterrupt (more than half
    of the Ctrl-Cs during ``extract_many``): that KeyboardInterrupt itself; any other SystemError as it is."""
    cause = in_chain(exc, KeyboardInterrupt)
    return cause if cause is not None else exc
