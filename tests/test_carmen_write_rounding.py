"""The CARMEN writer's rounding keeps every beam's meaning (REP-117, docs/data.md): written with
``write_log`` and read back with ``read_log``, a valid reading stays valid and within half a unit
(1 mm in mm mode, 1 cm in cm mode); one that is not valid stays not valid; +inf (no return) stays
+inf, nan stays nan. Rounding to the unit alone broke it at range_max, range_min, 0 and the
special band (8183 .. 8191 units)."""

from __future__ import annotations

import os
import tempfile

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lms200 import Record, Scan, read_log, write_log


def _round_trip(path, ranges, range_min: float, range_max: float, fmt: str = "robotlaser1") -> Scan:
    scan = Scan(np.asarray(ranges, dtype=np.float64), -np.pi / 2, np.pi / max(len(ranges) - 1, 1), range_min, range_max, stamp=1.0)
    write_log(path, [Record(scan)], fmt=fmt)
    back = next(iter(read_log(path))).scan
    assert back.range_min == range_min and back.range_max == range_max
    return back


def _kept(scan_ranges, back: Scan, range_min: float, range_max: float) -> None:
    scan = Scan(np.asarray(scan_ranges, dtype=np.float64), back.angle_min, back.angle_increment, range_min, range_max)
    unit = 0.001 if range_max <= 8.183 + 1e-9 else 0.01
    assert back.valid.tolist() == scan.valid.tolist()
    v = scan.valid
    assert np.all(np.abs(back.ranges[v] - scan.ranges[v]) <= unit / 2 * (1 + 1e-9))
    assert np.isposinf(back.ranges[np.isposinf(scan.ranges)]).all()
    assert np.isnan(back.ranges[np.isnan(scan.ranges)]).all()


@pytest.mark.parametrize("fmt", ["robotlaser1", "flaser"])
def test_a_valid_reading_just_below_range_max_stays_valid(tmp_path, fmt):
    """range_max 4.9996 m (mm mode): 4.9996 and 4.99955 m were written 5.000, above it: not valid.
    A reading just above range_max (8.0004 m at 8 m, not valid) was written 8.000: valid. A valid
    reading at exactly range_max is written half a unit below it (4.9995, 7.9995): the reader takes a
    reading at a line's declared maximum range for no return (+inf)."""
    back = _round_trip(tmp_path / "a.log", [4.9996, 4.99955, 4.9994, 2.0], 0.0, 4.9996, fmt)
    assert back.ranges.tolist() == [4.9995, 4.99955, 4.999, 2.0] and back.valid.all()
    back = _round_trip(tmp_path / "b.log", [8.0004, 8.0, 2.0], 0.0, 8.0, fmt)
    # 8.0004 m is written 8.000, the line's maximum range, which reads back as no return (+inf): not valid still
    assert back.ranges.tolist() == [np.inf, 7.9995, 2.0] and back.valid.tolist() == [False, True, True]


def test_a_valid_tie_below_the_cm_special_band_is_not_written_as_no_return(tmp_path):
    """81.825 m in cm mode (range_max 81.83 m) was written "81.83", the code 8183: +inf, no return
    (the check rounded half to even, 8182; the text half up)."""
    back = _round_trip(tmp_path / "c.log", [81.825, 81.83, 10.0], 0.0, 81.83)
    assert back.ranges[0] == 81.825 and back.valid.tolist() == [True, True, True]


def test_a_valid_reading_below_half_a_unit_is_not_written_as_no_reading(tmp_path):
    """0.0004 m (mm mode) and 0.004 m (cm mode) were written 0.000 / 0.00: 0, no reading."""
    back = _round_trip(tmp_path / "d.log", [0.0004, 0.0005, 1e-9, 0.0, 1.0], 0.0, 8.183)
    assert back.ranges.tolist() == [0.0004, 0.001, 1e-9, 0.0, 1.0]  # 0.0005: half a unit, rounded up
    assert back.valid.tolist() == [True, True, True, False, True]
    back = _round_trip(tmp_path / "e.log", [0.004, 0.0049, 30.0], 0.0, 30.0)
    assert back.ranges.tolist() == [0.004, 0.0049, 29.995] and back.valid.all()  # at range_max: half a unit below


def test_readings_at_range_min_keep_their_side_of_it(tmp_path):
    """cm mode, range_min 0.0505 m: 0.0545 m (valid) was written 0.05, below it; 0.0504 (not valid) 0.05 too."""
    back = _round_trip(tmp_path / "f.log", [0.0545, 0.0504, 0.06, 20.0], 0.0505, 30.0)
    assert back.valid.tolist() == [True, False, True, True]
    assert back.ranges[0] == pytest.approx(0.0545, abs=0.005) and back.ranges[2] == 0.06


UNITS = {"mm": (0.001, [8.183, 8.0, 4.9996, 1.0]), "cm": (0.01, [81.83, 100.0, 80.0, 29.996])}


@settings(max_examples=60, deadline=None, derandomize=True)
@given(units=st.sampled_from(["mm", "cm"]), which=st.integers(0, 3), range_min_units=st.sampled_from([0.0, 0.4, 5.05, 50.5]),
       offsets=st.lists(st.floats(-1.5, 1.5), min_size=1, max_size=40), small=st.lists(st.floats(0.0, 1.0), max_size=10),
       fmt=st.sampled_from(["robotlaser1", "flaser"]))
def test_a_written_scan_reads_back_with_every_beams_meaning(units, which, range_min_units, offsets, small, fmt):
    """Round-trip property: beams within 1.5 units of range_max and of range_min, below one unit,
    on the special band, +inf / nan; each keeps its meaning."""
    unit, maxima = UNITS[units]
    range_max = maxima[which]
    range_min = range_min_units * unit
    r = [range_max + o * unit for o in offsets] + [range_min + o * unit for o in offsets] + [s * unit for s in small]
    r += [81.83, 81.86, 81.91, 8.183, 8.191, 8.1825, 81.825, np.inf, np.nan, 1.0]
    r = [v for v in r if v >= 0]
    with tempfile.TemporaryDirectory() as tmp:
        back = _round_trip(os.path.join(tmp, "p.log"), r, range_min, range_max, fmt)
    _kept(r, back, range_min, range_max)
