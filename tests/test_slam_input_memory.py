"""``lmsbench slam``'s input stage keeps a compact row a scan, not the scans: ``load_input`` held every
record of the log (4.0 KB a scan of 361 beams, 10x what the SLAM run keeps), now it keeps stamps, numbers,
poses and a CRC of the ranges, and each pass over ``data.records`` reads the log again."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from experiments.slamrun import load_input
from lms200 import LmsbenchError

N_SCANS = 800
BEAMS = 181


def _flaser(k: int, stamp: float, beams: int = BEAMS, x: float | None = None) -> str:
    """Scan ``k``'s FLASER line: its laser pose and odometry at ``x`` m (0.01 k m by default)."""
    ranges = " ".join(f"{2.0 + 0.01 * ((k + b) % 97):.2f}" for b in range(beams))
    x = 0.01 * k if x is None else x
    return f"FLASER {beams} {ranges} {x:.4f} 0 0 {x:.4f} 0 0 {stamp:.6f} host {stamp:.6f}\n"


@pytest.fixture(scope="module")
def long_log(tmp_path_factory):
    path = tmp_path_factory.mktemp("memory") / "long.clf"
    path.write_text("".join(_flaser(k, 10.0 + 0.1 * k) for k in range(N_SCANS)))
    return path


def test_the_input_stage_keeps_a_compact_row_a_scan(long_log, monkeypatch):
    """Peak traced memory of load_input and of a pass over its records, per scan: the records' ranges
    alone are 181 * 8 = 1,448 B a scan (the list of records load_input held peaked at 2.1 KB a scan
    here); the rows held are 48 B a scan with odometry, and a pass holds a scan at a time. The rows'
    numpy blocks are cut to 256 rows (4,096: ~200 KB whatever the log, the most of 800 scans' peak)."""
    from slam.run import Column

    monkeypatch.setattr(Column, "BLOCK_ROWS", 256)
    tracemalloc.start()
    try:
        data = load_input(long_log)
        loaded = tracemalloc.get_traced_memory()[1]
        tracemalloc.reset_peak()
        base = tracemalloc.get_traced_memory()[0]
        stamps = [rec.scan.stamp for rec in data.records]
        passed = tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()
    # about what a SLAM run keeps a scan (slam.run.MAX_SLAM_SCANS: 356 B at its peak, the default preset)
    assert loaded / N_SCANS < 400, f"load_input peaked at {loaded / N_SCANS:.0f} B a scan"
    # the pass: the stamps list itself (~32 B a scan) and the reader's own buffers, no scan kept
    assert passed / N_SCANS < 400, f"a pass over the records peaked at {passed / N_SCANS:.0f} B a scan"
    assert len(data.records) == N_SCANS and data.numbers[-1] == N_SCANS - 1
    assert stamps == [float(f"{10.0 + 0.1 * k:.6f}") for k in range(N_SCANS)]  # the stamps as written
    np.testing.assert_array_equal(data.stamps, stamps)
    assert data.odometry is not None and data.odometry[-1, 1] == pytest.approx(0.01 * (N_SCANS - 1))


def test_a_log_changed_between_passes_is_refused(tmp_path):
    """A pass reads the log again: a scan that is not the one read first (its ranges or its odometry
    rewritten in place, or the log cut) is an error naming the file, not a run on other scans than the checks saw."""
    path = tmp_path / "log.clf"
    path.write_text("".join(_flaser(k, 10.0 + 0.1 * k, 11) for k in range(20)))
    data = load_input(path, every=2)
    assert [r.scan.stamp for r in data.records] == pytest.approx(10.0 + 0.2 * np.arange(10))
    assert data.records[-1].scan.stamp == pytest.approx(11.8) and data.records[3].scan.stamp == pytest.approx(10.6)
    lines = path.read_text().splitlines(keepends=True)
    path.write_text("".join(lines[:6]) + _flaser(7, 10.6, 11) + "".join(lines[7:]))  # scan 6's ranges: scan 7's
    changed = r"log.clf: scan 6 is not the one read before \(its stamp 10.600000 s, first read 10.600000 s, or its " \
              r"ranges, beam geometry or poses differ\): the file changed"
    with pytest.raises(LmsbenchError, match=changed):
        list(data.records)
    # its odometry alone: the raw odometry was scored from the first read, the odometry baseline ran on the new
    path.write_text("".join(lines[:6]) + _flaser(6, 10.6, 11, x=5.0) + "".join(lines[7:]))
    with pytest.raises(LmsbenchError, match=changed):
        list(data.records)
    path.write_text("".join(lines[:9]))
    with pytest.raises(LmsbenchError, match=r"log.clf: ended after 9 records on reading it again, before its scan 10 "
                                            r"read before: the file changed"):
        list(data.records)


def test_index_of_names_no_scan_at_a_freed_scans_address(tmp_path):
    """A user extractor's failure names its scan by identity among a pass's scans: a scan freed since, its
    address taken by a new object (CPython reuses it), was named as the freed one's index."""
    import dataclasses

    path = tmp_path / "log.clf"
    path.write_text("".join(_flaser(k, 10.0 + 0.1 * k, 11) for k in range(8)))
    records = load_input(path).records
    kept = [rec.scan for rec in records]
    assert [records.index_of(s) for s in kept] == list(range(8))  # alive: by identity
    freed = {id(s) for s in kept}
    template = kept[0]
    del kept
    fresh = []  # new scans of a stamp no scan has, until one lands at a freed scan's address
    for _ in range(1000):
        fresh.append(dataclasses.replace(template, stamp=99.0))
        if id(fresh[-1]) in freed:
            break
    else:
        pytest.skip("no new scan took a freed scan's address")
    assert records.index_of(fresh[-1]) is None


def test_records_slice_as_a_list_did(tmp_path):
    """load_input's records are read again at each pass; a slice of them (records[1:3], a list of records
    before) is those scans, read from the log likewise, not a TypeError."""
    path = tmp_path / "log.clf"
    path.write_text("".join(_flaser(k, 10.0 + 0.1 * k, 11) for k in range(8)))
    data = load_input(path, every=2)  # scans 0, 2, 4, 6 of the log
    held = list(data.records)
    part = data.records[1:3]
    assert len(part) == 2 and part.numbers.tolist() == [2, 4]
    assert [r.scan.stamp for r in part] == [r.scan.stamp for r in held[1:3]]
    assert [r.scan.stamp for r in data.records[::2]] == [r.scan.stamp for r in held[::2]]
    assert part[-1].scan.stamp == held[2].scan.stamp
    with pytest.raises(ValueError, match="run forward"):
        data.records[::-1]
