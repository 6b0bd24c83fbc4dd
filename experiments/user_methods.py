"""A user's own extractor in the comparison: ``lmsbench compare office --methods sensor
mypkg.lines:extract`` runs ``extract(scan) -> features.FeatureSet`` beside the built-in methods,
timed and scored the same way.

A name ``MODULE:FUNCTION`` is imported (the current folder first on the path, so a file
``./myext.py`` is ``myext:FUNCTION``; the folder is searched after every other place for the run,
so a sibling module the function imports when it is called is found: :func:`import_named`) and registered in ``features.registry`` under that name, with
an empty config; the function receives the ``lms200.Scan`` and returns a ``FeatureSet`` (lines and
corners in the sensor frame). A function with a ``config_type`` attribute (a dataclass) is called
``fn(scan, config)`` and its config's fields can be set with ``--set extractor.MODULE:FUNCTION.FIELD=V``.
``compare`` sets the fields of that config named ``sigma``, ``sigma_r``, ``sigma_r_cm`` (the
source's range noise), ``sigma_fit`` and ``sigma_bearing`` (a log's fit scatter and bearing noise)
per source, as it does the built-in methods' (``experiments.compare._with_noise``); a function
without a config gets none of them (docs/baselines.md).

An exception the function raises on a scan is the user's code failing, not lmsbench: it comes out
as :class:`UserMethodFailed` (an ``LmsbenchError``, its ``__cause__`` the user's exception), which
the drivers that know where the scan came from place (``.at(source, index)``); the command line
says it in one line, exit 2, and shows the user's traceback under ``LMSBENCH_TRACEBACK=1``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import importlib
import importlib.abc
import importlib.machinery
import os
import sys
from typing import TYPE_CHECKING, Any, Callable, Iterable, Iterator, Sequence

if TYPE_CHECKING:
    import numpy as np

from lms200 import LmsbenchError
from lms200.errors import one_line
from lms200.finite import fixed


class UserMethodError(LmsbenchError, ValueError):
    """A ``MODULE:FUNCTION`` extractor that cannot be loaded or returns the wrong thing."""


class UserMethodFailed(UserMethodError):
    """A ``MODULE:FUNCTION`` extractor that failed on a scan: it raised an exception (``raised``;
    the exception is ``__cause__``: the user's code, not lmsbench's) or returned something other
    than a FeatureSet. ``at(source, index)`` names the scan; until then it is named by its stamp."""

    def __init__(self, method: str, what: str, scan: Any, raised: bool) -> None:
        self.method, self.what, self.scan, self.raised = method, what, scan, raised
        self.place: str | None = None
        super().__init__(self._message())

    def _message(self) -> str:
        stamp = getattr(self.scan, "stamp", None)
        where = self.place or (f"on the scan stamped {fixed(stamp)} s" if isinstance(stamp, float) else "on a scan")
        return f"your extractor {self.method} {self.what} {where}"

    def at(self, source: str, index: int) -> "UserMethodFailed":
        """This error, naming its scan as ``index`` (0-based) of ``source`` (a driver that knows
        the source better than the one it called names it again: the last place given stays)."""
        self.place = f"on {source} scan {index}"
        self.args = (one_line(self._message()),)  # one line, as LmsbenchError makes every message
        return self

    def at_scan_of(self, source: str, scans: Iterable[Any], numbers: "Sequence[int] | np.ndarray | None" = None) -> "UserMethodFailed":
        """This error, naming its scan by its index in ``scans`` (scans or records, found by
        identity, else by stamp: a driver that passed copies, e.g. de-skewed ones), or by ``numbers``
        at that index (the log's own scan number of each, where ``scans`` are some of a log's). A
        ``scans`` that finds a scan itself (``index_of``: ``experiments.slamrun.LogScans``, which holds no
        scan) is asked, not read through."""
        stamp = getattr(self.scan, "stamp", None)
        index_of = getattr(scans, "index_of", None)
        if index_of is not None:
            k = index_of(self.scan)
        else:
            items = [getattr(s, "scan", s) for s in scans]
            k = next((i for i, s in enumerate(items) if s is self.scan), None)
            if k is None and stamp is not None:
                k = next((i for i, s in enumerate(items) if getattr(s, "stamp", None) == stamp), None)
        if k is not None and numbers is not None and len(numbers):
            k = int(numbers[k])
        return self.at(source, k) if k is not None else self


@contextlib.contextmanager
def scans_of(source: str, scans: Iterable[Any], numbers: "Sequence[int] | np.ndarray | None" = None) -> Iterator[None]:
    """Within it, a user extractor's failure names its scan by its index in ``scans`` (scans or
    records) of ``source``, or by ``numbers`` at that index (the log's own scan numbers): for a driver
    that hands a whole run to a library call (``run_slam``)."""
    try:
        yield
    except UserMethodFailed as exc:
        raise exc.at_scan_of(source, scans, numbers)


@dataclasses.dataclass(frozen=True)
class NoConfig:
    """The config of a user extractor that takes none."""


def is_user_method(name: str) -> bool:
    return ":" in name


def ensure_method(name: str) -> None:
    """Register the user extractor ``MODULE:FUNCTION`` (once per process); built-in names pass."""
    from features import registry

    if not is_user_method(name) or name in registry._REGISTRY:  # noqa: SLF001 - the registry's own table
        return
    fn = _load(name)
    config_type = getattr(fn, "config_type", None)
    takes_config = config_type is not None
    if takes_config and not dataclasses.is_dataclass(config_type):
        raise UserMethodError(f"{name}: its config_type must be a dataclass, got {config_type!r}")
    registry.register(name, config_type or NoConfig, _checked(name, fn, takes_config), backend="python")


def _load(name: str) -> Callable[..., Any]:
    return import_named(name, name, UserMethodError)


class FolderFinder(importlib.abc.MetaPathFinder):
    """Finds top-level modules in one folder, asked after every other finder of ``sys.meta_path``.

    The folder was appended to ``sys.path`` instead, "last, so it shadows nothing"; but the path's
    finder runs before the finder of an editable install (``make setup``: setuptools appends it to
    ``sys.meta_path``), so a folder ``slam/`` in the current folder (an earlier ``slam --out slam``)
    became lmsbench's ``slam`` wherever it was imported after a user's module: ``lmsbench bench``
    there failed "internal error: ImportError: cannot import name 'SlamConfig' from 'slam'
    (unknown location)", exit 1."""

    def __init__(self, folder: str) -> None:
        self.folder = folder

    def find_spec(self, name: str, path: Any = None, target: Any = None) -> Any:
        if path is not None:  # a submodule: its package's own __path__ finds it
            return None
        return importlib.machinery.PathFinder.find_spec(name, [self.folder])


def search_last(folder: str) -> None:
    """Search ``folder`` for top-level modules after every other place (:class:`FolderFinder`)."""
    if not any(isinstance(f, FolderFinder) and f.folder == folder for f in sys.meta_path):
        sys.meta_path.append(FolderFinder(folder))


def import_named(target: str, what: str, error: type[LmsbenchError] = UserMethodError) -> Callable[..., Any]:
    """The callable ``MODULE:ATTR`` names (ATTR may be dotted), MODULE imported with the current
    folder first on the path, so a file ``./myext.py`` is ``myext:ATTR`` (as with PYTHONPATH=.):
    the one rule for a user's extractor (``compare --methods``, ``slam --extractor``, an extract
    sweep's ``method``) and a sweep's cell ``kind`` (which needed PYTHONPATH=.: "cannot import
    mysw:cell: No module named 'mysw'"). After the import the current folder is searched for the
    run, after every other place (:class:`FolderFinder`): a module that imports a sibling lazily
    (``import helper`` inside its function) finds it when it is called (the folder was removed, and
    such a call failed with "No module named 'helper'"), and the folder's files do not shadow
    lmsbench's own modules or installed ones (``./sim.py`` beside a user's extractor, a ``slam/``
    output folder), which lmsbench imports lazily too.

    Raises:
        error: naming ``what``, when ``target`` is not MODULE:ATTR (a part empty: a sweep's ``kind: ":"``
            was "importing '' failed: ValueError: Empty module name", ``os:`` "module 'os' has no ''"),
            MODULE cannot be imported (with the hint "importable from the current folder or
            PYTHONPATH"), fails while importing, has no ATTR, or ATTR is not callable.
    """
    module_name, _, attr = target.partition(":")
    if not all(module_name.split(".")) or not all(attr.split(".")):  # '.m', 'm.', 'a..b': raw import errors
        raise error(f"{what if what != target else repr(target)}: not MODULE:FUNCTION, a module and a callable of it "
                    "(e.g. myext:extract)")
    cwd = os.getcwd()
    added = cwd not in sys.path
    if added:
        sys.path.insert(0, cwd)
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise error(f"{what}: cannot import module {module_name!r} ({exc}); it must be importable "
                    "from the current folder or PYTHONPATH") from None
    except (Exception, SystemExit, GeneratorExit) as exc:  # noqa: BLE001 - the user's module failed while importing
        # (sys.exit() at import time ended the command silently, exit 0: found by the wrong-input hunt)
        raise error(f"{what}: importing {module_name!r} failed: {raised_text(exc)}") from None
    finally:
        if added:  # off the path, searched last instead: found for lazy sibling imports, shadowing nothing
            sys.path.remove(cwd)
            search_last(cwd)
    fn = module
    for part in attr.split("."):
        if not hasattr(fn, part):
            raise error(f"{what}: module {module_name!r} has no {attr!r}")
        fn = getattr(fn, part)
    if not callable(fn):
        raise error(f"{what}: {attr!r} is not callable")
    return fn


def _checked(name: str, fn: Callable[..., Any], takes_config: bool) -> Callable[[Any, Any], Any]:
    """``fn`` as a registry run function whose result must be a FeatureSet."""
    from features import FeatureSet

    def run(scan: Any, config: Any) -> Any:
        try:
            out = fn(scan, config) if takes_config else fn(scan)
        except (Exception, SystemExit, GeneratorExit) as exc:  # noqa: BLE001 - the user's code: said as such, not as a bug in lmsbench
            # sys.exit() in the function ended `compare` silently with its status (0: as if it had
            # finished, nothing written), GeneratorExit with a traceback: found by the wrong-input hunt
            raise UserMethodFailed(name, f"raised {raised_text(exc)}", scan, True) from exc
        if not isinstance(out, FeatureSet):
            raise UserMethodFailed(name, f"returned {type(out).__name__}, not a features.FeatureSet", scan, False)
        return out

    run.__name__ = getattr(fn, "__name__", "run")
    return run


def raised_text(exc: BaseException) -> str:
    """What a user's code raised, for a message: ``RuntimeError: x``, ``SystemExit: 0`` (its
    ``sys.exit()``; ``sys.exit()`` without a status says ``SystemExit: None``)."""
    if isinstance(exc, SystemExit):
        return f"SystemExit: {exc.code!r} (it called sys.exit)"
    return type(exc).__name__ + (f": {exc}" if str(exc) else "")
