"""Line numbers in the CARMEN reader's errors are the file's: lines end at "\\n" (and "\\r\\n")."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from lms200 import LogFormatError, read_log

GOOD = "FLASER 3 1.00 2.00 3.00 0 0 0 0 0 0 {t} host {t}"


def test_a_stray_carriage_return_does_not_split_a_line_or_shift_the_line_numbers(tmp_path: Path) -> None:
    """A byte 0x0d inserted into line 2 (found by tests/test_fuzz_carmen.py) made the reader, which
    split lines the universal-newline way, read it as two lines: its tail was blamed as line 3
    ("it starts with '00', which is no CARMEN message name"), and every later error was one line
    off, the 'x' of line 4 reported at line 5. A lone "\\r" is no line end in a CARMEN log: it
    parts words, as any whitespace does (a CR in place of a space changes nothing)."""
    lines = ["PARAM lmsbench_range_units cm lmsbench 0", GOOD.format(t=10.0).replace("1.00", "1.\r00"),
             GOOD.format(t=10.1).replace(" 0 0 10.1", " 0\r0 10.1"), GOOD.format(t=10.2).replace("3.00", "x"),
             GOOD.format(t=10.3)]
    path = tmp_path / "cr.log"
    path.write_bytes(("\n".join(lines) + "\n").encode())
    reader = read_log(path, skip_bad_lines=True)
    assert [r.scan.stamp for r in reader] == [10.1, 10.3]
    assert reader.stats.skipped == [(2, "FLASER: FLASER with 3 beams needs 14 fields, got 15"),
                                    (4, "FLASER: FLASER ranges: 'x' is not a number")]
    with pytest.raises(LogFormatError, match=r"cr\.log:2: malformed FLASER line: FLASER with 3 beams needs 14 fields, got 15"):
        list(read_log(path))


@pytest.mark.parametrize("end, name", [("\r\n", "crlf"), ("\r", "mac")])
def test_crlf_and_classic_mac_line_ends_still_read(tmp_path: Path, end: str, name: str) -> None:
    """Lines ended by "\\r\\n", or by "\\r" alone throughout (the first 4096 bytes hold no "\\n"):
    read as before the lone "\\r" stopped ending lines, an error naming the line by those ends."""
    path = tmp_path / f"{name}.log"
    path.write_bytes(end.join(GOOD.format(t=t) for t in (1.0, 2.0, 3.0)).encode() + end.encode())
    assert [r.scan.stamp for r in read_log(path)] == [1.0, 2.0, 3.0]
    bad = tmp_path / f"{name}_bad.log"
    bad.write_bytes(end.join([GOOD.format(t=1.0), GOOD.format(t=2.0).replace("2.00", "y")]).encode() + end.encode())
    with pytest.raises(LogFormatError, match=rf"{name}_bad\.log:2: malformed FLASER line: FLASER ranges: 'y' is not a number"):
        list(read_log(bad))


@pytest.mark.parametrize("end, name", [("\r\n", "crlf"), ("\r", "mac"), ("\n", "unix")])
def test_line_ends_are_told_when_the_first_line_passes_4096_bytes(tmp_path: Path, end: str, name: str) -> None:
    """Found by fuzzing: a log of classic Mac line ends whose first line passed the 4096 bytes the
    reader looked at to tell its line ends (a ROBOTLASER1 line of 361 ranges and 361 remissions,
    4,900 bytes) was read as one line, the whole file: 'line 1: ... needs 746 fields, got 2238'.
    The reader looks on to the first line end; CRLF and "\\n" logs read as before."""
    ranges = " ".join(f"{1 + i / 1000:.3f}" for i in range(361))
    remissions = " ".join("0.500000" for _ in range(361))
    lines = [f"ROBOTLASER1 0 -1.570796 3.141593 0.008727 8.183 0.001 0 361 {ranges} 361 {remissions} "
             f"0 0 0 0 0 0 0 0 0 0 0 {t} host {t}" for t in (1.0, 2.0, 3.0)]
    assert len(lines[0]) > 4096
    path = tmp_path / f"{name}.log"
    path.write_bytes(end.join(lines).encode() + end.encode())
    records = list(read_log(path))
    assert [r.scan.stamp for r in records] == [1.0, 2.0, 3.0]
    assert records[2].scan.ranges[[0, 360]].tolist() == [1.0, 1.36]
    path.write_bytes(end.join(lines + [lines[0].replace("1.360", "z")]).encode() + end.encode())
    with pytest.raises(LogFormatError, match=rf"{name}\.log:4: malformed ROBOTLASER1 line: ROBOTLASER1 ranges: 'z' is not a number"):
        list(read_log(path))


@pytest.mark.parametrize("kind", ["tum", "relations"])
def test_a_stray_carriage_return_does_not_shift_the_line_numbers_of_tum_and_relations_files(tmp_path: Path,
                                                                                            kind: str) -> None:
    """The TUM and relations readers (lms200.logs.row_lines) ended a line at a lone "\\r" too, unlike
    the CARMEN reader: a 0x0d in line 1's comment made the bad row of line 3 "line 4". Lines now end
    as in a CARMEN log, numbered as `wc -l`, an editor or `sed -n Np` count them; a lone "\\r" in a row
    is whitespace (a CR in place of a space changes nothing); "\\r\\n" and classic Mac files still read."""
    from lms200 import read_tum
    from slam.metrics import read_relations

    read = read_tum if kind == "tum" else read_relations
    rows = ["# written by\rhand", "1.0 0 0 0 0 0 0 1", "2.0 0 0 0 0 0 0 1", "3.0 0 0 0 0 0 0 x"]
    rows[2] = rows[2].replace(" 0 0 1", " 0\r0 1")
    path = tmp_path / f"cr.{kind}"
    path.write_bytes(("\n".join(rows) + "\n").encode())
    with pytest.raises(LogFormatError, match=rf"cr\.{kind}:4: .*non-number"):  # old: line 5
        read(path)
    for end, name in (("\r\n", "crlf"), ("\r", "mac")):
        good = tmp_path / f"{name}.{kind}"
        good.write_bytes(end.join(["# hand", "1.0 0 0 0 0 0 0 1", "2.0 0 0 0 0 0 0 1"]).encode() + end.encode())
        assert len(read(good)) == 2
        bad = tmp_path / f"{name}_bad.{kind}"
        bad.write_bytes(end.join(["1.0 0 0 0 0 0 0 1", "2.0 0 0 0 0 0 0 1", "3.0 0 0 0 0 0 0 x"]).encode() + end.encode())
        with pytest.raises(LogFormatError, match=rf"{name}_bad\.{kind}:3: "):
            read(bad)


@pytest.mark.parametrize("kind, what", [("tum", "a TUM trajectory"), ("relations", "a relations file")])
def test_a_compressed_or_binary_tum_or_relations_file_is_said_to_be_one(tmp_path: Path, kind: str, what: str) -> None:
    """A gzip-compressed relations file (or a log given as one) was read as text: "line 1: relation rows need
    8 numbers (t1 t2 x y z roll pitch yaw), got 16"; a PNG "got 1", a CARMEN log "line 3: ..., got 3". Refused as
    what it is, naming the file."""
    import gzip
    import lzma

    from lms200 import read_tum
    from lms200.logs import PEEK_BYTES
    from slam.metrics import read_relations

    read = read_tum if kind == "tum" else read_relations
    text = b"1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n"
    log = b"# a log\n\nPARAM laser_front_laser_resolution 1.0\nFLASER 3 1 1 1 0 0 0 0 0 0 1.0 h 1.0\n"
    for name, data, said in (("r.gz", gzip.compress(text), f"gzip-compressed, not {what} (read as plain text); "
                                                           "decompress it first"),
                             ("r.bz2", __import__("bz2").compress(text), "bzip2-compressed, not"),
                             ("r.png", b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + text, f"a binary file, not {what}"),
                             ("r.clf", log, f"a CARMEN log (its line 3 is a PARAM message), not {what}"),
                             # told to be decompressed, as if that would make it a relations file
                             ("r.clf.gz", gzip.compress(log), f"a gzip-compressed CARMEN log (its line 3 is a PARAM "
                                                              f"message), not {what}"),
                             ("r.clf.xz", lzma.compress(log), f"an xz-compressed CARMEN log (its line 3 is a PARAM "
                                                              f"message), not {what}"),
                             ("r.clf.bz2", __import__("bz2").compress(log), "a bzip2-compressed CARMEN log (its line 3"),
                             # only the head's first PEEK_BYTES are decompressed: a message past them is not seen
                             ("r2.clf.gz", gzip.compress(b"#" * PEEK_BYTES + b"\n" + log), "gzip-compressed, not")):
        (tmp_path / name).write_bytes(data)
        with pytest.raises(LogFormatError, match=rf"^{tmp_path / name}: {re.escape(said)}"):
            read(tmp_path / name)
