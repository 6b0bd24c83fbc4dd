"""Ranges in millimetres given as metres: told from a source's first scans, once per source.

A ``Scan``'s ranges are metres, and a reading beyond ``range_max`` is no return (REP-117). Ranges
written in millimetres (a user's array, a log or bag written so) lie about 1000x too far: every
one beyond ``range_max``, so every beam reads as no return, no extractor finds a line, and nothing
said why. :func:`units_problem` tells such scans from open space by what their readings would be
in metres, divided by 1000; its text names millimetres where divided by 100 they would lie beyond both
``range_max`` and the farthest an LMS200 reads (``CM_REACH_M``: centimetres ruled out), else millimetres
or centimetres (ranges in centimetres, divided by 1000, lie in range too, and a ``range_max`` set short
does not bound what the scanner read: the data cannot tell them apart). The log readers (``lms200.carmen``, ``lms200.bag``),
``experiments.compare.compare`` and ``slam.run_slam`` (a user's records, which no reader saw; a
reader given to them warns itself) warn with it, once per pass or run, from the scans they read
anyway (none read ahead), never per scan of an extraction: ``features.extract`` does not look (a
single call's hot path).
"""

from __future__ import annotations

import abc
import math
import warnings
from pathlib import Path
from typing import Iterable, Iterator

import numpy as np

from .codes import LMS200_MAX_RANGE
from .errors import LmsbenchWarning
from .records import Record
from .scan import Scan

#: scans of a source's start that are looked at (a log's first 50; all of a shorter one)
UNITS_SCANS = 50
#: finite readings > 0 the rule needs before it says anything (a scan or two of a few beams says nothing)
MIN_READINGS = 10
#: readings of different values the rule needs: a no-return code (81.91 in a cm-mode CARMEN log, the
#: range_max + 1 some drivers write) is one value, however many beams hold it
MIN_DISTINCT = 3
#: m: the nearest reading, once divided by 1000, that a scene in millimetres is taken to hold; the far
#: readings (10-30 m) of a scanner whose range_max was set below its reach lie below it (0.01-0.03 m)
NEAREST_SCENE_M = 0.1
#: share of the readings that must lie within [max(range_min, NEAREST_SCENE_M), range_max] once divided
#: by 1000 (not all: the LMS200's no-return code in mm mode, 8191 mm, divides to 8.191 m, past 8.183);
#: the same share of them divided by 100 leaves centimetres open in the text (:meth:`UnitsTally.evidence`)
IN_RANGE_SHARE = 0.9
#: m: how far a reading in centimetres, divided by 100, may lie and still be one: the farther of a scan's
#: range_max and the LMS200's reach in cm mode (codes.LMS200_MAX_RANGE); a range_max set short (1-8 m) ruled
#: centimetres out of the text for readings of a room 10-30 m across, which it does not bound
CM_REACH_M = LMS200_MAX_RANGE["cm"]


class RangeUnitsWarning(LmsbenchWarning):
    """A source's first scans look like ranges in millimetres (or centimetres) given as metres (:func:`units_problem`)."""


class UnitsTally:
    """What :func:`units_problem` asks of a source's first scans, added up scan by scan (``add``, then
    ``problem``; no scan is held: a pass's first 50 scans of 10,000 beams each held 4 MB, and their
    joined copies 18 MB); callers that read a source themselves (``experiments.calibrate``) tally it."""

    def __init__(self) -> None:
        self.scans = self.readings = self.in_range = 0
        self.in_range_cm = 0  # readings within CM_REACH_M divided by 100 (what the text says, not whether it is said)
        self.valid = False  # a valid beam in some scan: no doubt left
        self.within = False  # a reading > 0 at or below its range_max (below range_min: not valid, not far either)
        self.least = self.most = math.nan  # the smallest and largest reading
        self.range_max = math.inf  # the smallest range_max
        self.values: set[float] = set()  # up to MIN_DISTINCT of the readings' values

    def add(self, scan: Scan) -> None:
        self.scans += 1
        if self.valid:
            return
        ranges = np.asarray(scan.ranges, dtype=float).ravel()
        lo, hi = float(scan.range_min), float(scan.range_max)
        with np.errstate(invalid="ignore"):
            r = ranges[np.isfinite(ranges) & (ranges > 0.0)]
        if not r.size:
            return
        self.valid = bool(np.any((r >= lo) & (r <= hi)))
        self.within = self.within or bool(np.any(r <= hi))
        self.readings += int(r.size)
        near = max(lo, NEAREST_SCENE_M)
        metres = r / 1000.0
        self.in_range += int(np.count_nonzero((metres >= near) & (metres <= hi)))
        metres = r / 100.0
        self.in_range_cm += int(np.count_nonzero((metres >= near) & (metres <= max(hi, CM_REACH_M))))
        self.least, self.most = float(np.fmin(self.least, r.min())), float(np.fmax(self.most, r.max()))
        self.range_max = min(self.range_max, hi)
        if len(self.values) < MIN_DISTINCT:
            self.values.update(np.unique(r)[:MIN_DISTINCT].tolist())

    def problem(self) -> str | None:
        evidence = self.evidence()
        return None if evidence is None else f"none of the first {self.scans} scans has a valid beam: {evidence}"

    def evidence(self) -> str | None:
        """Why the scans added look like millimetres, after "none has a valid beam" (or None): millimetres
        where divided by 100 fewer than IN_RANGE_SHARE of the readings would lie within [near, max(range_max,
        CM_REACH_M)] (farther than any LMS200 reads), else millimetres or centimetres (whenever it is said,
        divided by 1000 they are in range: centimetres are never ruled in)."""
        if self.valid or self.within or self.readings < MIN_READINGS or len(self.values) < MIN_DISTINCT:
            return None
        share = self.in_range / self.readings
        if share < IN_RANGE_SHARE:
            return None
        cm = self.in_range_cm / self.readings
        unit = (f", {100 * cm:.0f} % within an LMS200's reach divided by 100: ranges in millimetres or centimetres"
                if cm >= IN_RANGE_SHARE else ": ranges in millimetres")
        return (f"all {self.readings:,} finite readings lie "
                f"beyond range_max ({self.range_max:g} m), from {self.least:.6g} to {self.most:.6g}, and "
                f"{100 * share:.0f} % of them would be in range divided by 1000{unit} "
                "given as metres? A Scan's ranges are metres (a reading beyond range_max is no return, REP-117)")


def units_problem(scans: Iterable[Scan]) -> str | None:
    """Why ``scans`` (a source's first ones) look like ranges in millimetres given as metres, or None.

    They do when none has a valid beam, they hold at least MIN_READINGS finite readings > 0 of at
    least MIN_DISTINCT values, every one beyond its scan's ``range_max``, and at least IN_RANGE_SHARE
    of them divided by 1000 lie within [max(range_min, NEAREST_SCENE_M), range_max]: a scene in
    metres. Open space (REP-117: beyond ``range_max`` is no return) is not: a no-return code is one
    value, +inf is no finite reading, and real readings beyond a ``range_max`` set short lie within a
    few tens of metres, below NEAREST_SCENE_M once divided; any valid beam in any scan ends the doubt.
    The scans are looked at one by one, none held."""
    return _tallied(scans).problem()


def units_evidence(scans: Iterable[Scan]) -> str | None:
    """:func:`units_problem` without its opening (none of the first N scans has a valid beam), for an
    error that says that itself: ``slam MM_LOG`` said the units warning, then its own 'none of its N
    scans has a valid beam' (two lines for a user error); it says the units in its one line."""
    return _tallied(scans).evidence()


def _tallied(scans: Iterable[Scan]) -> UnitsTally:
    """``scans`` added to a new :class:`UnitsTally`, one by one."""
    tally = UnitsTally()
    for scan in scans:
        tally.add(scan)
    return tally


def warn_units(scans: Iterable[Scan], where: str) -> None:
    """A :class:`RangeUnitsWarning` naming ``where`` (a log's path, a source's name) when
    :func:`units_problem` finds ``scans`` in millimetres (once a process for one text, under Python's
    default warning filter: a log read twice, for its noise and its scans, is said once)."""
    _warn(units_problem(scans), where)


def _warn(problem: str | None, where: str) -> None:
    if problem:  # issued here, whoever reads: Python's default filter says one text once, not once a pass
        warnings.warn(f"{where}: {problem}", RangeUnitsWarning, stacklevel=1)


def reader_watches(records: object) -> bool:
    """Whether ``records`` is a source whose own passes look at their first scans (a log reader: its
    class's ``WATCHES_UNITS``), so that a consumer does not say their units a second time."""
    return bool(getattr(type(records), "WATCHES_UNITS", False))


def units_watched(records: Iterable[Record], where: str, tally: UnitsTally | None = None) -> Iterator[Record]:
    """``records`` as they come, their first UNITS_SCANS scans (all of a pass with fewer, once it
    ends) looked at by :func:`units_problem`, one by one (none held), and said by :func:`warn_units`:
    a reader's pass warns once, and a pass stopped before then does not. ``tally``: the
    :class:`UnitsTally` to add them to (a reader's ``units``, which its caller may ask after the
    pass: ``experiments.calibrate`` tallied the same scans a second time), else a new one."""
    tally = UnitsTally() if tally is None else tally
    for rec in records:
        if tally.scans < UNITS_SCANS:
            tally.add(rec.scan)
            if tally.scans == UNITS_SCANS:
                _warn(tally.problem(), where)
        yield rec
    if tally.scans < UNITS_SCANS:
        _warn(tally.problem(), where)


class WatchedPasses(abc.ABC):
    """A log reader whose every pass (``iter(reader)``) is :func:`units_watched` under its ``path``: the
    pass's first UNITS_SCANS scans looked at for ranges in millimetres, said once a pass. The CARMEN and
    bag readers (``lms200.carmen``, ``lms200.bag``) are; a class gives ``path`` and ``_pass()``."""

    #: each pass looks at its first scans for ranges in millimetres (:func:`reader_watches`)
    WATCHES_UNITS = True
    path: Path
    _units: UnitsTally | None = None

    @property
    def units(self) -> UnitsTally:
        """What the last pass's first UNITS_SCANS scans showed (a new, empty tally before any pass);
        ``experiments.calibrate`` asks it for its millimetres error instead of tallying them again."""
        if self._units is None:
            self._units = UnitsTally()
        return self._units

    def __iter__(self) -> Iterator[Record]:
        """The source's records, one pass; its first scans checked for ranges in millimetres (:attr:`units`:
        this pass's tally, the last pass's once it ends)."""
        self._units = tally = UnitsTally()
        return units_watched(self._pass(), str(self.path), tally)

    @abc.abstractmethod
    def _pass(self) -> Iterator[Record]:
        """One pass's records, as the source holds them (not yet watched)."""
