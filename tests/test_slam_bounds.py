"""Bounds of SLAM on hostile input: an endless iterator of records (run_slam), a scan of very
many lines (the paper preset's EKF)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from lms200 import Record, Scan
from slam import SlamConfig, SlamInputError, run_slam


def _records(n: int, beams: int = 181) -> list[Record]:
    """``n`` scans 0.1 s apart of a robot standing in a square room (ranges to its walls)."""
    bearings = np.linspace(-np.pi / 2, np.pi / 2, beams)
    with np.errstate(divide="ignore"):
        ranges = np.minimum(3.0 / np.maximum(np.cos(bearings), 1e-9), 2.0 / np.abs(np.sin(bearings)))
    return [Record(Scan(np.minimum(ranges, 7.9), -np.pi / 2, np.pi / (beams - 1), 0.0, 8.0, stamp=0.1 * k))
            for k in range(n)]


def test_an_endless_iterator_is_refused_at_the_beam_bound(monkeypatch: pytest.MonkeyPatch) -> None:
    """Defect: run_slam(itertools.repeat(record)) never ended, its trajectory growing; an iterator
    is now read up to MAX_ITERATOR_BEAMS beams (made 20 scans' worth here), then refused."""
    import slam.run

    rec = _records(1)[0]
    monkeypatch.setattr(slam.run, "MAX_ITERATOR_BEAMS", 20 * rec.scan.ranges.size)
    read = itertools.count()

    def endless():
        for _ in itertools.repeat(None):
            assert next(read) < 100, "read on past the bound"
            yield rec

    for preset in ("default", "paper"):
        with pytest.raises(SlamInputError, match=r"^records: an iterator or generator that yielded more than 3,620 "
                                                 r"beams \(21 scans\) without ending"):
            run_slam(endless(), SlamConfig(preset=preset))
    # a list is taken whole (it is held already), max_scans reads no further than it says
    records = _records(25)
    assert run_slam(records, SlamConfig(preset="paper")).trajectory.shape == (25, 4)
    assert run_slam(itertools.repeat(rec), SlamConfig(preset="paper"), max_scans=30).trajectory.shape == (30, 4)
    it = iter(records)
    assert run_slam(it, SlamConfig(preset="paper"), max_scans=5).trajectory.shape == (5, 4)
    assert next(it) is records[5]  # the source is not read past max_scans
    for bad in (0, -1, True, 2.5, "3"):
        with pytest.raises(SlamInputError, match=r"^max_scans: must be an integer >= 1 \(or None\), got "):
            run_slam(records, max_scans=bad)
