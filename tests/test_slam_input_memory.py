"""``lmsbench slam``'s input stage keeps a compact row a scan, not the scans: ``load_input`` held every
record of the log (3.5 KB a scan of MIT CSAIL's 361 beams, 10x what the SLAM run keeps), now it keeps stamps, numbers,
poses and a CRC of the ranges, and each pass over ``data.records`` reads the log again."""

from __future__ import annotations

import gc
import tracemalloc

import numpy as np
import pytest

from experiments.slamrun import load_input
from lms200 import LmsbenchError

N_SCANS = 60  # the logs hold N_SCANS and 2 * N_SCANS scans: the memory a scan is their difference over N_SCANS
BEAMS = 61


def _flaser(k: int, stamp: float, beams: int = BEAMS, x: float | None = None) -> str:
    """Scan ``k``'s FLASER line: its laser pose and odometry at ``x`` m (0.01 k m by default)."""
    ranges = " ".join(f"{2.0 + 0.01 * ((k + b) % 97):.2f}" for b in range(beams))
    x = 0.01 * k if x is None else x
    return f"FLASER {beams} {ranges} {x:.4f} 0 0 {x:.4f} 0 0 {stamp:.6f} host {stamp:.6f}\n"


def _memory(path) -> tuple[int, int, int]:
    """Bytes traced: held by load_input's result, its peak while reading, and a pass's peak over its records."""
    gc.collect()
    tracemalloc.start()
    try:
        data = load_input(path)
        loading = tracemalloc.get_traced_memory()[1]
        gc.collect()  # the garbage left, cycles among it, is no scan's
        held = tracemalloc.get_traced_memory()[0]
        tracemalloc.reset_peak()
        assert sum(1 for _ in data.records) == len(data.records)
        passing = tracemalloc.get_traced_memory()[1] - held
    finally:
        tracemalloc.stop()
    return held, loading, passing


def test_the_input_stage_keeps_a_compact_row_a_scan(tmp_path):
    """What load_input holds, and its peak, a scan: the difference between logs of N_SCANS and 2 * N_SCANS
    scans over N_SCANS, so that the fixed part (a reader's buffers, the rows' first numpy blocks of 4,096 rows,
    ~200 KB) cancels. The list of records load_input held was 1,110 B a scan here (61 beams: the ranges
    alone are 488 B), its peak 1,100-1,180 B; the rows held are 48 B a scan with odometry (0-50 B measured,
    allocator noise of ~2 KB a call), their peak within the fixed blocks, and a pass holds a scan at a time
    (its list of the scans' numbers: ~36 B a scan)."""
    paths = []
    for n in (N_SCANS, 2 * N_SCANS):
        paths.append(tmp_path / f"log{n}.clf")
        paths[-1].write_text("".join(_flaser(k, 10.0 + 0.1 * k) for k in range(n)))
    list(load_input(paths[0]).records)  # untraced: the first call's imports and caches are no scan's
    (held1, loading1, passing1), (held2, loading2, passing2) = (_memory(p) for p in paths)
    held, loading, passing = ((b - a) / N_SCANS for a, b in ((held1, held2), (loading1, loading2), (passing1, passing2)))
    assert held < 250, f"load_input holds {held:.0f} B a scan"
    assert loading < 400, f"load_input peaked at {loading:.0f} B a scan"
    assert passing < 150, f"a pass over the records peaked at {passing:.0f} B a scan"
    data = load_input(paths[0])
    stamps = [rec.scan.stamp for rec in data.records]
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


def test_taken_builds_its_log_scans_from_the_rows_directly(tmp_path, monkeypatch):
    """LogScans.taken made an empty ScanRows (a LogScans of no rows) only to write its arrays over; it is
    now built from the kept rows themselves: no ScanRows made, the same rows, the same scans read."""
    import experiments.slamrun

    path = tmp_path / "log.clf"
    path.write_text("".join(_flaser(k, 10.0 + 0.1 * k) for k in range(8)))
    data = load_input(path)
    monkeypatch.setattr(experiments.slamrun, "ScanRows", lambda *a, **k: pytest.fail("a ScanRows was made"))
    part = data.records.taken([1, 4, 6])
    assert part.numbers.tolist() == [1, 4, 6] and part.stamps.tolist() == [10.1, 10.4, 10.6]
    assert part.odom is not None and part.odom[:, 0].tolist() == [0.01, 0.04, 0.06]
    assert part.truth is None and part.geometries == data.records.geometries and part.read_seconds == 0.0
    assert [r.scan.stamp for r in part] == [10.1, 10.4, 10.6]
    assert [r.scan.stamp for r in data.records[2:8:3]] == [10.2, 10.5]
