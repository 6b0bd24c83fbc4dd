"""A log's last stamp, found without reading its records (``reader.last_stamp()``), against the stamps
its records carry: `slam LOG --relations OTHER --max-scans N` compares the relations with the whole
log's time span, which a cut read does not reach."""

from __future__ import annotations

import numpy as np
import pytest

from lms200 import Record, Scan, read_log, write_log


def _records(n: int, t0: float = 10.0) -> list[Record]:
    return [Record(Scan.lms200(np.full(361, 2.0 + 0.001 * k), stamp=t0 + 0.1 * k), odom=(0.01 * k, 0.0, 0.0))
            for k in range(n)]


@pytest.mark.parametrize("name", ["log.clf", "log.clf.gz", "log.clf.bz2", "log.bag"])
def test_the_last_stamp_is_the_last_records(tmp_path, name):
    """Plain (read from its end over several 64 KiB blocks: 60 scans of 361 beams), compressed (one
    decompressing pass) and a bag (header stamps from the bytes): the last record's stamp."""
    path = tmp_path / name
    write_log(path, _records(60))
    reader = read_log(path)
    assert reader.last_stamp() == pytest.approx([r.scan.stamp for r in reader][-1], abs=1e-9) == pytest.approx(15.9)


def test_a_cut_or_malformed_last_line_and_trailing_lines_are_passed_over(tmp_path):
    """A log cut mid-line (a killed logger), then comments and other messages: the last laser line
    that adds up gives the stamp; a log of no laser line gives None."""
    path = tmp_path / "cut.clf"
    write_log(path, _records(5))
    text = path.read_text()
    last = text.rstrip("\n").splitlines()[-1]
    path.write_text(text + "ODOM 0 0 0 0 0 0 99.0 host 99.0\n# a comment\n" + last[: len(last) // 2])
    assert read_log(path).last_stamp() == pytest.approx(10.4)
    (tmp_path / "none.clf").write_text("ODOM 0 0 0 0 0 0 1.0 host 1.0\n")
    assert read_log(tmp_path / "none.clf").last_stamp() is None


def test_the_real_logs_last_stamps(shared_data):
    """FLASER (MIT CSAIL, Intel) and ROBOTLASER1 (CSAIL) logs, gzipped: as their last records."""
    for name in ("mit-csail.clf.gz", "csail-robotlaser1.log.gz"):
        reader = read_log(shared_data / name)
        assert reader.last_stamp() == [r.scan.stamp for r in reader][-1]


def _flaser(k: int, stamp: float, beams: int = 361, announced: int | None = None) -> str:
    """A FLASER line of scan ``k``: ``beams`` ranges, announcing ``announced`` (default ``beams``)."""
    ranges = " ".join([f"{2.0 + 0.001 * k:.3f}"] * beams)
    x = 0.01 * k
    return f"FLASER {announced or beams} {ranges} {x} 0 0 {x} 0 0 {stamp:.6f} host {stamp:.6f}\n"


@pytest.mark.parametrize("name", ["long.clf", "long.clf.gz"])
def test_a_last_line_longer_than_the_reader_takes_gives_no_stamp(tmp_path, monkeypatch, name):
    """A last laser line that adds up but is longer than MAX_LINE_CHARS (here 4000, the line ~6000), which
    the reader refuses: read back from a plain file's end it gave its stamp (99 s), the reader's last
    scan being at 10.4 s."""
    import gzip

    from lms200 import carmen

    monkeypatch.setattr(carmen, "MAX_LINE_CHARS", 4000)
    text = "".join(_flaser(k, 10.0 + 0.1 * k) for k in range(5)) + _flaser(5, 99.0, beams=1000)
    assert len(text.splitlines()[-1]) > carmen.MAX_LINE_CHARS
    path = tmp_path / name
    with (gzip.open(path, "wt") if name.endswith(".gz") else open(path, "w")) as f:
        f.write(text)
    stamps = [r.scan.stamp for r in read_log(path, skip_bad_lines=True)]
    assert read_log(path).last_stamp() == pytest.approx(stamps[-1]) == pytest.approx(10.4)


def test_a_compressed_logs_damaged_tail_gives_the_last_sound_lines_stamp(tmp_path):
    """40 scans, then 20 lines announcing 362 beams with 361 values (more than the 16 a compressed log's
    pass keeps): the last sound line's stamp, as the plain file's (the compressed one gave None, and
    another log's relations ran the whole SLAM under --max-scans)."""
    import gzip

    text = "".join(_flaser(k, 10.0 + 0.1 * k) for k in range(40))
    text += "".join(_flaser(k, 10.0 + 0.1 * k, announced=362) for k in range(40, 60))
    (tmp_path / "tail.clf").write_text(text)
    with gzip.open(tmp_path / "tail.clf.gz", "wt") as f:
        f.write(text)
    for name in ("tail.clf", "tail.clf.gz"):
        assert read_log(tmp_path / name).last_stamp() == pytest.approx(13.9), name


def test_a_backwards_last_stamp_does_not_refuse_the_logs_own_relations(tmp_path):
    """60 scans stamped 10.0 to 15.9 s, then a 61st stamped 5.0 s (dropped by --skip-bad-lines): the last
    line's stamp is 5.0 s, the largest 15.9 s. A run cut at 5 scans refused relations at 14-15 s as
    outside "10.000000 to 10.400000 s"; relations past the whole log are still refused, naming its span."""
    from itertools import islice

    from experiments.slamrun import _check_relations_span
    from lms200 import LmsbenchError

    path = tmp_path / "back.clf"
    path.write_text("".join(_flaser(k, 10.0 + 0.1 * k) for k in range(60)) + _flaser(60, 5.0))
    reader = read_log(path, skip_bad_lines=True)
    records = list(islice(iter(reader), 5))
    own = np.array([[14.0, 15.0, 0.1, 0, 0, 0, 0, 0]])
    _check_relations_span(own, records, "mid.relations", 5, reader.last_stamp)  # no error
    assert reader.last_stamp() == pytest.approx(5.0)
    assert reader.last_stamp(largest=True) == pytest.approx(max(r.scan.stamp for r in read_log(path, skip_bad_lines=True)))
    with pytest.raises(LmsbenchError, match=r"the whole log's scans 10\.000000 to 15\.900000 s"):
        _check_relations_span(own + [20.0, 20.0, 0, 0, 0, 0, 0, 0], records, "late.relations", 5, reader.last_stamp)


@pytest.mark.parametrize("name", ["indent.clf", "indent.clf.gz"])
def test_indented_laser_lines_give_their_stamps(tmp_path, name):
    """Laser lines after leading whitespace, which the reader reads: the last stamp and the largest are
    theirs (16.9 s), not the last unindented line's (15.9 s), which refused the log's own relations at
    16.5 s under --max-scans."""
    import gzip

    text = "".join(_flaser(k, 10.0 + 0.1 * k) for k in range(60)) + "".join(
        " " + _flaser(k, 10.0 + 0.1 * k) for k in range(60, 70))
    path = tmp_path / name
    path.write_bytes(gzip.compress(text.encode()) if name.endswith(".gz") else text.encode())
    reader = read_log(path)
    assert [r.scan.stamp for r in reader][-1] == pytest.approx(16.9)
    assert reader.last_stamp() == pytest.approx(16.9)
    assert reader.last_stamp(largest=True) == pytest.approx(16.9)
