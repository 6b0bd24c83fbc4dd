"""The laser read by default is chosen from laser lines that can be read, not from a damaged one."""

from __future__ import annotations

from pathlib import Path

import pytest

from lms200 import LogFormatError, read_log

RAW = "RAWLASER1 0 -0.017453 0.034906 0.017453 81.83 0.01 0 3 1.00 2.00 3.00 0 {t} host {t}"
FLASER = "FLASER 3 1.00 2.00 3.00 0 0 0 0 0 0 {t} host {t}"


def write(tmp_path: Path, lines: list[str]) -> Path:
    path = tmp_path / "log.clf"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_damaged_line_named_flaser_does_not_hide_the_rawlaser_lines(tmp_path: Path) -> None:
    """A line whose name was damaged into FLASER (found by tests/test_fuzz_carmen.py: ODOM -> FLASER)
    chose FLASER as the laser: under skip_bad_lines that line was skipped and the log's two good
    RAWLASER1 lines were passed over, 0 records; without, the error named the damaged line, not
    the laser the log holds. Now a FLASER / ROBOTLASER line whose fields do not add up (its beam
    count against its fields) chooses no laser: RAWLASER1 is read, and the damaged line is
    another kind's line, counted."""
    path = write(tmp_path, ["ODOM 0 0 0 0 0 0 9.9 host 9.9", RAW.format(t=10.0), "FLASER 0 0 0 0 0 0 10.05 host 10.05",
                            RAW.format(t=10.1), "ODOM 1 0 0 0 0 0 10.2 host 10.2"])
    for skip in (False, True):
        reader = read_log(path, skip_bad_lines=skip)
        recs = list(reader)
        assert [r.scan.stamp for r in recs] == [10.0, 10.1] and reader.stats.laser == "RAWLASER1"
        assert reader.stats.skipped == [] and reader.stats.messages["FLASER"] == 1


@pytest.mark.parametrize("bad", ["FLASER 3 1.00 2.00 0 0 0 0 0 0 10.05 host 10.05",  # a range lost: 13 fields for 3 beams
                                 "ROBOTLASER1 0 -1.570796 3.141593 0.017453 81.83 0.01 0 3 1.00 2.00 3.00 0 0 0"])
def test_the_first_readable_posed_line_chooses_the_laser(tmp_path: Path, bad: str) -> None:
    """A damaged line of a kind with poses before the log's good FLASER lines: FLASER is still read
    (the damaged line is skipped or named, as before, when it is FLASER's own)."""
    path = write(tmp_path, [RAW.format(t=9.0), bad, FLASER.format(t=10.0), FLASER.format(t=10.1)])
    reader = read_log(path, skip_bad_lines=True)
    assert [r.scan.stamp for r in reader] == [10.0, 10.1] and reader.stats.laser == "FLASER"
    if bad.startswith("FLASER"):
        assert reader.stats.skipped == [(2, "FLASER: FLASER with 3 beams needs 14 fields, got 13")]
        with pytest.raises(LogFormatError, match=r"log\.clf:2: malformed FLASER line: FLASER with 3 beams needs 14 fields"):
            list(read_log(path))
    else:
        assert reader.stats.skipped == [] and reader.stats.messages["ROBOTLASER1"] == 1


def test_a_log_of_damaged_flaser_lines_only_still_names_them(tmp_path: Path) -> None:
    """No readable laser line: the first laser line met is the laser, as before, and its error named."""
    path = write(tmp_path, ["FLASER 0 0 0 0 0 0 10.05 host 10.05"])
    with pytest.raises(LogFormatError, match=r"log\.clf:1: malformed FLASER line: FLASER needs at least one beam"):
        list(read_log(path))
