"""The extractors' beam limit (``features.baselines.checks.MAX_BEAMS``, what ``features.extract``
refuses) in the drivers that call a method's ``run`` directly to time it: ``compare``, ``sim2real``,
``experiments.evaluate.extract_timed`` and the baselines benchmark ran scans of more beams
unchecked (``lmsbench compare`` on a 20,000-beam log: exit 0, a table of 20,000-beam scans).
``slam``, through ``extract``, refused it after a note on the input's beam timing, naming no file."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from experiments.cli import main
from features.baselines.checks import MAX_BEAMS
from features.errors import ScanGeometryError
from lms200 import Record, Scan, write_log

WIDE = MAX_BEAMS + 1


def _scan(n: int, k: int) -> Scan:
    return Scan(np.full(n, 3.0), -math.pi, 2 * math.pi / n, 0.0, 30.0, stamp=float(k))


def _records(widths) -> list[Record]:
    return [Record(scan=_scan(n, k), odom=(0.1 * k, 0.0, 0.0)) for k, n in enumerate(widths)]


@pytest.mark.parametrize("command, index", [("compare", 0), ("sim2real", 0), ("slam", 0)])
@pytest.mark.parametrize("name, fmt", [("wide.clf", "robotlaser1"), ("wide.bag", "bag")])
def test_a_log_of_wider_scans_is_refused_before_any_work(tmp_path, capsys, command, index, name, fmt):
    log = tmp_path / name
    write_log(log, _records([WIDE, WIDE]), fmt=fmt)
    out = tmp_path / "out"
    assert main([command, str(log), "--out", str(out)]) == 2  # compare old: 0, its table written
    lines = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert lines == [f"lmsbench {command}: error: {log}: scan {index}: {WIDE} beams is more than the extractors "
                     f"handle ({MAX_BEAMS}, a 0.022 deg step over 360 deg); split the scan into sectors"]
    assert not out.exists()


def test_compare_refuses_a_wider_scan_within_a_source_as_extract_does():
    from experiments.compare import Source, compare

    src = Source.from_records(_records([361, 361, WIDE]), name="mixed")
    with pytest.raises(ScanGeometryError, match=rf"^mixed: scan 2: {WIDE} beams is more than the extractors handle "
                                                rf"\({MAX_BEAMS},"):
        compare([src], methods=["split_merge"], sigma=0.01)  # old: three rows, the last a 16,385-beam scan's


def test_the_timed_runs_refuse_wider_scans_before_timing():
    from experiments.benchmarks.baselines import time_methods
    from experiments.evaluate import extract_timed

    scans = [_scan(361, 0), _scan(WIDE, 1)]
    with pytest.raises(ScanGeometryError, match=rf"^scan 1: {WIDE} beams is more than the extractors handle"):
        time_methods(scans, ["split_merge"], 1)
    with pytest.raises(ScanGeometryError, match=rf"^scan 1: {WIDE} beams is more than the extractors handle"):
        extract_timed(scans, "split_merge")
    _, times = extract_timed(scans[:1], "split_merge")
    assert times.shape == (1,)


@pytest.mark.parametrize("command, thinning, damaged", [("slam", "--every", True), ("compare", "--stride", False)])
def test_a_wider_scan_is_named_by_the_logs_own_scan_number_as_it_is_read(tmp_path, capsys, command, thinning, damaged):
    """A review: with --every 2, slam named the wider scan by the index of the scans kept (scan 2 for
    the log's scan 4), and refused it only after the whole log was read (a damaged line after it was
    the error instead); compare --stride named it so, and by the log's base name where its first scan
    was named by the path given (compare reads the whole log first, for its noise: no damaged line for it).
    Scans are numbered as read from the log, from 0, in every command."""
    log = tmp_path / "wide.clf"
    write_log(log, _records([361, 361, 361, 361, WIDE, 361]), fmt="robotlaser1")
    if damaged:
        with open(log, "a", encoding="utf-8") as f:
            f.write("ROBOTLASER1 damaged\n")  # after the wider scan: never read
    assert main([command, str(log), thinning, "2", "--out", str(tmp_path / "out")]) == 2
    lines = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert lines == [f"lmsbench {command}: error: {log}: scan 4: {WIDE} beams is more than the extractors "
                     f"handle ({MAX_BEAMS}, a 0.022 deg step over 360 deg); split the scan into sectors"]


def test_compare_from_python_refuses_a_log_of_wider_scans_before_reading_it_for_its_noise(tmp_path, monkeypatch):
    """A review: the CLI checks a log's first scan while parsing its sources, but compare() called from
    Python estimated the log's range noise (sigma "auto": a pass over the whole log) before it refused
    scan 0. Each source's first scan is now checked before any work."""
    import lms200.noise
    from experiments.compare import Source, compare, log_source

    log = tmp_path / "wide.clf"
    write_log(log, _records([WIDE, WIDE, WIDE]), fmt="robotlaser1")
    estimated = []
    real = lms200.noise.estimate_range_noise
    monkeypatch.setattr(lms200.noise, "estimate_range_noise", lambda scans: (estimated.append(1), real(scans))[1])
    with pytest.raises(ScanGeometryError, match=rf"^{re.escape(str(log))}: scan 0: {WIDE} beams is more than the "
                                                rf"extractors handle \({MAX_BEAMS},"):
        compare([log_source(log)], methods=["split_merge"])
    assert estimated == []  # old: [1], the whole log read for its noise first
    with pytest.raises(ScanGeometryError, match=rf"^mixed: scan 0: {WIDE} beams"):
        compare([Source.from_records(_records([WIDE, 361]), name="mixed")], methods=["split_merge"])
    assert estimated == []  # old: [1]


def test_compares_scan_column_is_the_logs_own_scan_number(tmp_path):
    """A review: compare's `scan` column counted the scans kept, so under --stride 2 the log's scan 4
    was row scan 2 (while its messages, and slam's, name the log's own number). It is the log's own."""
    from experiments.compare import compare, log_source

    log = tmp_path / "five.clf"
    write_log(log, _records([361] * 5), fmt="robotlaser1")
    table = compare([log_source(log, stride=2)], methods=["split_merge"], sigma=0.01)
    assert table["scan"].tolist() == [0, 2, 4]  # old: [0, 1, 2]
    assert table["stamp"].tolist() == [0.0, 2.0, 4.0]
    table = compare([log_source(log, stride=2, max_scans=2)], methods=["split_merge"], sigma=0.01)
    assert table["scan"].tolist() == [0, 2]


def test_compare_reads_one_log_at_a_time(tmp_path, monkeypatch):
    """A review: checking each source's first scan before the noise estimates (above) took the first scan
    of every log before any log was compared, so every log's reader stayed open at once (40 logs: 46 open
    files, 7 before; 60 logs under `ulimit -n 50`: "too many open files"). Each source's first scan is
    checked in its own turn, just before its noise is estimated: one log is open at a time."""
    import os

    import experiments.compare as compare_module
    from experiments.compare import compare, log_source

    fd_dir = "/proc/self/fd" if os.path.isdir("/proc/self/fd") else "/dev/fd"
    logs = []
    for i in range(12):
        logs.append(tmp_path / f"l{i:02d}.clf")
        write_log(logs[-1], _records([181] * 2), fmt="robotlaser1")
    open_files = []  # open file descriptors at each scan checked, while every log is being read
    real = compare_module.check_beams
    monkeypatch.setattr(compare_module, "check_beams",
                        lambda scan, where: (open_files.append(len(os.listdir(fd_dir))), real(scan, where))[1])
    before = len(os.listdir(fd_dir))
    table = compare([log_source(log) for log in logs], methods=["split_merge"], sigma=0.01)
    assert len(table) == 24
    assert max(open_files) - before <= 2  # new: 1; old: 12 (every log's reader open at once)
    # a log of too wide scans is still refused before it is read for its noise (test above), in its turn
    write_log(tmp_path / "wide.clf", _records([WIDE]), fmt="robotlaser1")
    with pytest.raises(ScanGeometryError, match=rf"^{re.escape(str(tmp_path / 'wide.clf'))}: scan 0: {WIDE} beams"):
        compare([log_source(logs[0]), log_source(tmp_path / "wide.clf")], methods=["split_merge"])
