"""Ranges in millimetres given as metres (lms200.units): every reading beyond range_max, so every
beam read as no return and no line found, without a word. Told from a source's first scans by the
log readers and compare; open space (REP-117: beyond range_max is no return) is not taken for it."""

from __future__ import annotations

import itertools
import warnings
from pathlib import Path

import numpy as np
import pytest

from lms200 import Record, Scan, read_log, write_log
from lms200.bag import write_bag
from lms200.units import RangeUnitsWarning, WatchedPasses, units_problem


def _room_mm(n: int = 3) -> list[Scan]:
    """An office's ranges, 2-5 m, written in millimetres."""
    rng = np.random.default_rng(0)
    return [Scan.lms200(1000.0 * (2.0 + rng.uniform(0.0, 3.0, 361)), stamp=0.1 * k) for k in range(n)]


def test_scans_in_millimetres_are_told_and_open_space_is_not() -> None:
    said = units_problem(_room_mm())
    # divided by 100, 20-50 m: beyond the range_max (8.183 m) but within an LMS200's reach in centimetres (81.83 m),
    # which a range_max set short does not bound: the text said "ranges in millimetres", centimetres ruled out
    assert said == ("none of the first 3 scans has a valid beam: all 1,083 finite readings lie beyond range_max (8.183 m), "
                    "from 2000.57 to 4998.5, and 100 % of them would be in range divided by 1000, 100 % within an "
                    "LMS200's reach divided by 100: ranges in millimetres or centimetres given as metres? A Scan's ranges "
                    "are metres (a reading beyond "
                    "range_max is no return, REP-117)")
    # the same room in centimetres fires it too (divided by 1000: 0.2-0.5 m), and so does a room 5-30 m across in
    # centimetres under a range_max of 4 m: the data cannot tell them from millimetres
    in_cm = [s.replace(ranges=s.ranges / 10.0) for s in _room_mm()]
    assert units_problem(in_cm) == said.replace("from 2000.57 to 4998.5", "from 200.057 to 499.85")
    far_cm = [Scan.lms200(np.linspace(500.0, 3000.0, 361), range_max=4.0)]
    assert units_problem(far_cm).endswith("from 500 to 3000, and 100 % of them would be in range divided by 1000, 100 % "
                                          "within an LMS200's reach divided by 100: ranges in millimetres or centimetres given as metres? A Scan's "
                                          "ranges are metres (a reading beyond range_max is no return, REP-117)")
    # millimetres alone where divided by 100 they lie beyond both the range_max and an LMS200's reach: 9-30 m in
    # millimetres under a range_max of 30 m (divided by 100: 90-300 m); under one of 120 m, 90-110 m lie within it
    far_mm = [Scan.lms200(np.linspace(9000.0, 30000.0, 361), range_max=30.0)]
    assert units_problem(far_mm).endswith("from 9000 to 30000, and 100 % of them would be in range divided by 1000: "
                                          "ranges in millimetres given as metres? A Scan's ranges are metres (a reading "
                                          "beyond range_max is no return, REP-117)")
    long_reach = [Scan.lms200(np.linspace(9000.0, 11000.0, 361), range_max=120.0)]
    assert "100 % within an LMS200's reach divided by 100: ranges in millimetres or centimetres" in str(units_problem(long_reach))
    in_metres = [s.replace(ranges=s.ranges / 1000.0) for s in _room_mm()]
    assert all(s.valid.all() for s in in_metres) and units_problem(in_metres) is None
    quiet = {
        "open space, +inf": [Scan.lms200(np.full(361, np.inf))],
        "a no-return code (81.91 m) beyond a cm scanner's 81.83": [Scan.lms200(np.full(361, 81.91), range_max=81.83)],
        "far readings past a range_max set short": [Scan.lms200(np.linspace(10.0, 30.0, 361))],
        "one valid beam": [Scan.lms200(np.r_[2.0, _room_mm(1)[0].ranges[1:]])],
        "too few readings": [Scan.lms200(np.r_[np.linspace(2000, 3000, 9), np.full(352, np.inf)])],
        "no scan": [],
    }
    for why, scans in quiet.items():
        assert units_problem(scans) is None, why


def test_a_log_in_millimetres_is_said_once_a_pass_by_its_reader(tmp_path: Path) -> None:
    log = tmp_path / "mm.clf"
    write_log(log, [Record(s) for s in _room_mm(60)])
    with pytest.warns(RangeUnitsWarning, match=rf"^{log}: none of the first 50 scans has a valid beam: .* millimetres") as said:
        assert sum(1 for _ in read_log(log)) == 60
    assert len([w for w in said if issubclass(w.category, RangeUnitsWarning)]) == 1  # once a pass
    with warnings.catch_warnings():  # a pass stopped before its 50th scan says nothing
        warnings.simplefilter("error", RangeUnitsWarning)
        assert len(list(itertools.islice(read_log(log), 10))) == 10


@pytest.mark.parametrize("name", ["mm.clf", "mm.bag"])
def test_a_readers_tally_of_its_pass_is_exposed(tmp_path: Path, name: str) -> None:
    """reader.units: the UnitsTally of its last pass's first 50 scans (calibrate tallied them a second
    time beside the reader, which kept its own to itself), as units_problem tells them; the CARMEN and
    the bag reader watch their passes by one piece of code (each repeated it), which says the bag's too."""
    log = tmp_path / name
    (write_bag if name.endswith(".bag") else write_log)(log, [Record(s) for s in _room_mm(60)])
    reader = read_log(log)
    assert isinstance(reader, WatchedPasses) and type(reader).__iter__ is WatchedPasses.__iter__
    assert reader.units.scans == 0 and reader.units is reader.units  # before any pass: an empty tally
    with pytest.warns(RangeUnitsWarning, match=rf"^{log}: none of the first 50 scans"):
        scans = [rec.scan for rec in reader]
    assert reader.units.scans == 50 and reader.units.problem() == units_problem(scans[:50])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RangeUnitsWarning)
        assert len(list(itertools.islice(reader, 3))) == 3
    assert reader.units.scans == 3 and reader.units.problem() == units_problem(scans[:3])  # a new pass, a new tally


def test_compare_says_it_of_scans_of_the_users_own() -> None:
    from experiments.compare import Source, compare

    records = [Record(s) for s in _room_mm()]
    with pytest.warns(RangeUnitsWarning, match=r"^mine: none of the first 3 scans has a valid beam"):
        table = compare([Source.from_records(records, name="mine")], ["split_merge"], sigma=0.01)
    assert table.n_lines.sum() == 0 and table.n_valid.sum() == 0  # what it says: no beam read, no line found
    # a stream of the user's is read no further for it than the run takes (max_scans 2: it took 50)
    pulled = []

    def stream():
        for rec in records * 30:
            pulled.append(rec)
            yield rec

    with pytest.warns(RangeUnitsWarning, match=r"^live: none of the first 2 scans has a valid beam"):
        compare([Source("live", "log", None, stream(), None, None)], ["split_merge"], sigma=0.01, max_scans=2)
    assert len(pulled) <= 3


def test_run_slam_says_it_of_scans_of_the_users_own_and_a_readers_once(tmp_path: Path) -> None:
    """A hand-built Scan in millimetres given straight to slam.run_slam ran with every beam a no return,
    without a word; now its first scans are looked at as they come (a live iterator read no further than
    the run: max_scans 2 pulls 2), and a log reader given to it says it once, itself."""
    from slam import SlamConfig, run_slam

    moving = [s.replace(stamp=0.1 * k) for k, s in enumerate(_room_mm(4))]
    with pytest.warns(RangeUnitsWarning, match=r"^records: none of the first 4 scans has a valid beam") as said:
        run_slam([Record(s) for s in moving], SlamConfig())
    assert len([w for w in said if issubclass(w.category, RangeUnitsWarning)]) == 1
    pulled = []

    def stream():
        for rec in [Record(s) for s in moving] * 30:
            pulled.append(rec)
            yield rec

    with pytest.warns(RangeUnitsWarning, match=r"^records: none of the first 2 scans"):
        run_slam(stream(), SlamConfig(), max_scans=2)
    assert len(pulled) == 2
    with warnings.catch_warnings():  # metres: nothing said
        warnings.simplefilter("error", RangeUnitsWarning)
        run_slam([Record(s.replace(ranges=s.ranges / 1000.0)) for s in moving], SlamConfig())
    log = tmp_path / "mm.clf"
    write_log(log, [Record(s) for s in moving])
    with pytest.warns(RangeUnitsWarning) as said:
        run_slam(read_log(log), SlamConfig())
    assert [str(w.message).split(":")[0] for w in said if issubclass(w.category, RangeUnitsWarning)] == [str(log)]


@pytest.mark.shared_data
def test_no_real_log_is_taken_for_millimetres(shared_data: Path) -> None:
    for log in sorted(shared_data.glob("*.gz")):
        assert units_problem([rec.scan for rec in itertools.islice(read_log(log), 50)]) is None, log.name
