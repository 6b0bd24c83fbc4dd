"""The batch API and the array FeatureSet: ``extract_many`` equals ``extract`` scan by scan for
every method (to 1e-12), refuses mixed geometries, and ``fs.lines[i]`` / ``fs.corners[i]`` are the
rows of the arrays with the record field names."""

from __future__ import annotations

import copy
import pickle
import re

import numpy as np
import pytest

from features import ConfigError, Corner, ScanTypeError, FeatureSet, Line, available_methods, extract, extract_many, make_config
from lms200 import Scan
from sensor_geometry import room


def batch(n: int = 12) -> list[Scan]:
    scans = [room(seed) for seed in range(n)]
    ranges = scans[3].ranges.copy()
    ranges[::7] = np.nan
    scans[3] = scans[3].replace(ranges=ranges)
    scans[5] = scans[5].replace(ranges=np.full(361, np.inf))  # no features at all
    return scans


def assert_equal_sets(a: FeatureSet, b: FeatureSet) -> None:
    assert a.method == b.method
    np.testing.assert_array_equal(a.lines.beams, b.lines.beams)
    np.testing.assert_array_equal(a.corners.beams, b.corners.beams)
    np.testing.assert_allclose(a.lines.values, b.lines.values, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.corners.values, b.corners.values, rtol=0, atol=1e-12)


@pytest.mark.parametrize("method", ["sensor", "split_merge", "iepf", "hough", "ransac"])
def test_extract_many_equals_extract_on_each_scan(method: str) -> None:
    scans = batch()
    many = extract_many(scans, method=method)
    assert len(many) == len(scans)
    found = 0
    for scan, fs in zip(scans, many):
        assert_equal_sets(fs, extract(scan, method=method))
        found += len(fs.lines)
    assert found > len(scans)
    assert extract_many([], method=method) == []
    # a batch's FeatureSet (views cut from the batch rows on first read) pickles and copies as a FeatureSet
    again = pickle.loads(pickle.dumps(many[2]))
    assert type(again) is FeatureSet and again == many[2] == copy.deepcopy(many[2])


def test_extract_many_takes_a_config_or_params() -> None:
    scans = batch(6)
    cfg = make_config("sensor", k=5, corners=False)
    for fs, scan in zip(extract_many(scans, config=cfg), scans):
        assert_equal_sets(fs, extract(scan, k=5, corners=False))
        assert len(fs.corners) == 0
    for fs, scan in zip(extract_many(scans, "split_merge", split_threshold=0.05), scans):
        assert_equal_sets(fs, extract(scan, "split_merge", split_threshold=0.05))
    with pytest.raises(ConfigError, match="no_such"):
        extract_many(scans, no_such=1)
    with pytest.raises(ConfigError, match="config"):
        extract_many(scans, "iepf", config=cfg)


def test_extract_many_refuses_mixed_geometry() -> None:
    scans = batch(6)[:3] + [room(9, n=181, increment=np.deg2rad(1.0))]
    for method in available_methods():
        with pytest.raises(ValueError, match=r"scans\[3\]: geometry"):
            extract_many(scans, method=method)
    with pytest.raises(ValueError, match=r"scans\[1\]"):
        extract_many([scans[0], scans[0].replace(range_max=81.83)])


def test_something_other_than_a_scan_is_refused_with_the_fix() -> None:
    from types import SimpleNamespace

    from lms200 import LmsbenchError

    scan = room(0)
    record = SimpleNamespace(scan=scan, timestamp=0.0)  # what read_log yields carries .scan
    cases = [
        (lambda: extract(record), "extract: expected an lms200.Scan, got SimpleNamespace (a log record: pass record.scan)"),
        (lambda: extract(scan.ranges), "got ndarray (build one with lms200.Scan.lms200(ranges)"),
        (lambda: extract_many([scan, record]), "scans[1]: expected an lms200.Scan, got SimpleNamespace (a log record"),
        (lambda: extract_many(scan), "got one Scan (use extract, or [scan])"),
    ]
    for call, text in cases:
        with pytest.raises(ScanTypeError, match=re.escape(text)) as info:
            call()
        assert isinstance(info.value, LmsbenchError) and isinstance(info.value, TypeError)


def test_feature_set_arrays_and_record_views() -> None:
    fs = extract(room(2))
    lines, corners = fs.lines, fs.corners
    assert len(lines) >= 3 and len(corners) >= 1
    assert lines.values.shape == (len(lines), 10) and lines.beams.shape == (len(lines), 3)
    for i, line in enumerate(lines):
        assert isinstance(line, Line)
        assert (line.rho, line.alpha) == (lines.rho[i], lines.alpha[i])
        assert line.start == tuple(lines.start[i]) and line.end == tuple(lines.end[i])
        assert (line.first, line.last, line.n_points) == tuple(lines.beams[i])
        np.testing.assert_array_equal(line.cov, lines.cov[i])
        assert line.length == pytest.approx(lines.length[i])
        assert -np.pi < line.alpha <= np.pi
    for i, c in enumerate(corners):
        assert isinstance(c, Corner)
        assert (c.x, c.y, c.angle) == (corners.x[i], corners.y[i], corners.angle[i])
        assert c.index == corners.beam[i] and c.lines == tuple(corners.line_pair[i])
    np.testing.assert_array_equal(fs.line_array()[:, 6:], lines.beams[:, :2])
    # built from records, the same arrays; pickled, the same set
    again = FeatureSet(list(lines), list(corners), fs.method)
    assert again == fs and pickle.loads(pickle.dumps(fs)) == fs
    assert FeatureSet().lines == [] and len(FeatureSet().corners) == 0


def test_a_batch_row_has_the_numba_type_of_a_scans_ranges() -> None:
    """The batch kernels call the single-scan kernel on each row of the stacked ranges; a row typed
    like a Scan's (read-only) ranges reuses the single call's machine code, where a writable row
    made numba compile the whole extractor a second time (~30 s of a fresh checkout's first run)."""
    import numba

    from features.batch import stacked_ranges

    scans = batch(6)
    rows = stacked_ranges(scans)
    assert numba.typeof(rows[1]) == numba.typeof(scans[1].ranges)
    np.testing.assert_array_equal(rows[1], scans[1].ranges)


def test_extract_many_equals_extract_with_the_noise_estimated_per_scan() -> None:
    """cm-mode scans (range_max 81.83 m) take the default noise "auto": a batch estimates it from
    each scan, as a single call does. Scans of 5 mm and 30 mm noise side by side: a noise pooled
    over the batch gave other lines (16 of 20 MIT CSAIL scans differed in their line count)."""
    rng = np.random.default_rng(11)
    scans = []
    for k, sigma in enumerate((0.005, 0.03, 0.005, 0.03, 0.012, 0.005)):
        clean = room(k).ranges
        scans.append(Scan.lms200(np.round(clean + sigma * rng.standard_normal(clean.size), 2), range_max=81.83))
    many = extract_many(scans, method="sensor")
    singles = [extract(s, method="sensor") for s in scans]
    for a, b in zip(many, singles):
        assert_equal_sets(a, b)
    assert {len(fs.lines) for fs in singles} != {0}


@pytest.mark.parametrize("method", ["sensor", "split_merge", "iepf"])
def test_a_large_batch_runs_in_chunks_with_the_same_result(method: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """A batch stacks its scans' ranges into one array: 50,000 scans took a second 144 MB copy of
    them (peak RSS +166 MB, now +70 MB at BATCH_CHUNK = 4096). Chunked, each compiled call sees at
    most BATCH_CHUNK scans (here 5), the result is extract's on each scan, in order, and an error
    names the scan's index in the whole batch."""
    import features.registry as registry

    monkeypatch.setattr(registry, "BATCH_CHUNK", 5)
    m = registry.get_method(method)
    sizes: list[int] = []

    def spy(scans, cfg):
        sizes.append(len(scans))
        return m.run_many(scans, cfg)

    monkeypatch.setitem(registry._REGISTRY, method, registry.Method(m.name, m.config_type, m.run, m.default,
                                                                    m.backend, spy))
    scans = batch(12)
    many = extract_many(iter(scans), method=method)  # a generator, as a log's reader gives them
    assert sizes == [5, 5, 2] and len(many) == 12
    for scan, fs in zip(scans, many):
        assert_equal_sets(fs, extract(scan, method=method))
    odd = scans[:7] + [room(9, n=181, increment=np.deg2rad(1.0))] + scans[8:]
    with pytest.raises(ValueError, match=r"^scans\[7\]: geometry"):  # in the second chunk: index 7, not 2
        extract_many(odd, method=method)
    with pytest.raises(ScanTypeError, match=r"^scans\[9\]"):
        extract_many(scans[:9] + ["not a scan"], method=method)


def _wall(n: int, amin: float, inc: float, rmin: float = 0.0, rmax: float = 8.183, scale: float = 1.0) -> Scan:
    """A wall 2 m (x scale) away with its normal at 0.3 rad; +inf beyond range_max."""
    c = np.cos(amin + np.arange(n) * inc - 0.3)
    r = 2.0 * scale / np.where(c > 0, c, np.nan)  # behind the wall: no return
    return Scan(np.where(r * (1 + 1e-12) < rmax, r, np.inf), amin, inc, rmin, rmax)


TWO_PI = 2 * np.pi
#: geometries at the edges of what a Scan accepts (issue 12): name -> (scan, lines of the wall
#: each method finds: None = none expected, "wall" = at least one, all on the wall)
EDGE_SCANS = {
    "one beam": (lambda: Scan(np.array([2.0]), 0.0, 0.1, 0.0, 8.0), None),
    "one beam, 1e300 rad step": (lambda: Scan(np.array([2.0]), -TWO_PI, 1e300, 0.0, 8.0), None),
    "two beams 1e300 rad apart": (lambda: Scan(np.array([2.0, 3.0]), TWO_PI, 1e300, 0.0, 8.0), None),
    "5e-324 rad step": (lambda: _wall(361, 0.2, 5e-324), None),
    "angle_min -2 pi, a full turn": (lambda: _wall(720, -TWO_PI, TWO_PI / 720), "wall"),
    "angle_min +2 pi": (lambda: _wall(361, TWO_PI, np.deg2rad(0.5)), "wall"),
    "16,384 beams over 360 deg": (lambda: _wall(1 << 14, -np.pi, TWO_PI / (1 << 14), rmax=80.0), "wall"),
    "ranges of 1e-300 m": (lambda: _wall(361, -np.pi / 2, np.deg2rad(0.5), 1e-300, 2e-299, scale=1e-300), None),
    "range_max 1.8e308": (lambda: _wall(361, -np.pi / 2, np.deg2rad(0.5), 0.0, 1.7976931348623157e308), "wall"),
    "all nan": (lambda: Scan(np.full(361, np.nan), -np.pi / 2, np.deg2rad(0.5), 0.0, 8.0), None),
    "all 0 m": (lambda: Scan(np.zeros(361), -np.pi / 2, np.deg2rad(0.5), 0.0, 8.0), None),
}
#: the geometries a method refuses, by name, with a ScanGeometryError (a ValueError) naming why
REFUSED = {("sensor", "5e-324 rad step"): "angle_increment: 4.94e-324 rad",
           ("hough", "range_max 1.8e308"): "hough: the accumulator"}


@pytest.mark.parametrize("method", ["sensor", "split_merge", "iepf", "hough", "ransac"])
def test_edge_geometries_give_the_wall_or_a_clear_error_and_batches_agree(method: str) -> None:
    """Checked by fuzzing (26,000 calls a method, 0 failures after the fixes of this session);
    this pins the hand-picked edge cases: lines only on the wall (rho 2 m, alpha 0.3 rad), none
    where there is no wall to find, extract_many equal to extract."""
    from features.errors import ScanGeometryError

    for name, (make, want) in EDGE_SCANS.items():
        scan = make()
        if (method, name) in REFUSED:
            with pytest.raises(ScanGeometryError, match="^" + re.escape(REFUSED[(method, name)])):
                extract(scan, method)
            continue
        fs = extract(scan, method)
        assert extract_many([scan, scan], method) == [fs, fs], name
        if want is None:
            assert len(fs.lines) == 0, name
        else:
            assert len(fs.lines) >= 1, name
            np.testing.assert_allclose(fs.lines.rho, 2.0, atol=0.05, err_msg=name)
            np.testing.assert_allclose(fs.lines.alpha, 0.3, atol=0.02, err_msg=name)


@pytest.mark.parametrize("method", ["sensor", "split_merge", "iepf"])
def test_threads_give_the_same_features_bit_for_bit(method: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """``extract_many(threads=N)`` runs pieces of the batch on N threads at once; each scan is
    extracted by itself, so every array equals the one-thread result exactly (not to 1e-12), and
    the pieces really ran on several threads."""
    import threading

    import features.batch as fbatch
    import features.registry as registry

    scans = batch(40)
    ref = extract_many(scans, method=method, threads=1)
    monkeypatch.setattr(fbatch, "MIN_SCANS_PER_THREAD", 4)  # 40 scans: pieces of 14, 14, 12 on 3 threads
    m = registry.get_method(method)
    assert m.thread_safe
    threads_seen: set[int] = set()
    sizes: list[int] = []
    gate = threading.Barrier(3, timeout=30)  # each piece waits for the other two: they run at once

    def spy(piece, cfg):
        threads_seen.add(threading.get_ident())
        sizes.append(len(piece))
        gate.wait()
        return m.run_many(piece, cfg)

    monkeypatch.setitem(registry._REGISTRY, method, registry.Method(m.name, m.config_type, m.run, m.default,
                                                                    m.backend, spy, True))
    many = extract_many(scans, method=method, threads=3)
    assert sorted(sizes) == [12, 14, 14] and len(threads_seen) == 3
    assert len(many) == len(ref)
    for a, b in zip(many, ref):
        np.testing.assert_array_equal(a.lines.values, b.lines.values)
        np.testing.assert_array_equal(a.lines.beams, b.lines.beams)
        np.testing.assert_array_equal(a.corners.values, b.corners.values)
        np.testing.assert_array_equal(a.corners.beams, b.corners.beams)


def test_the_batch_kernels_release_the_gil() -> None:
    """Threads only run at once if the compiled batch calls let go of Python's lock."""
    from features.baselines import engine as baseline_engine
    from features.sensor import engine as sensor_engine

    assert sensor_engine.extract_batch.targetoptions["nogil"] is True
    assert baseline_engine.extract_batch.targetoptions["nogil"] is True


def test_thread_counts_are_checked(monkeypatch: pytest.MonkeyPatch) -> None:
    import os

    from features.batch import THREADS_ENV, available_cpus, default_threads

    scans = batch(6)
    for bad in (0, -1, 1.5, True, "2", 10**6):
        with pytest.raises(ConfigError, match=r"^threads: must be a whole number from 1 to 1024"):
            extract_many(scans, threads=bad)
    monkeypatch.setenv(THREADS_ENV, "3")
    assert default_threads() == 3
    monkeypatch.setenv(THREADS_ENV, " 2 ")  # spaces around it, as a shell may leave them
    assert default_threads() == 2
    for text in ("all", "1_0", "\uff12", "\u0663"):  # int() read "1_0" as 10, fullwidth 2 and Arabic-Indic 3 as digits
        monkeypatch.setenv(THREADS_ENV, text)
        with pytest.raises(ConfigError, match=rf"^LMSBENCH_THREADS: must be a whole number from 1 to 1024, got '{text}'"):
            extract_many(scans)
    monkeypatch.setenv(THREADS_ENV, "9" * 5000)  # int()'s limit of 4,300 digits: an internal ValueError (review)
    with pytest.raises(ConfigError, match=r"^LMSBENCH_THREADS: must be a whole number from 1 to 1024, got '9{39}\.\.\."):
        extract_many(scans)
    monkeypatch.delenv(THREADS_ENV)
    assert default_threads() == 1  # asked for, not assumed
    assert available_cpus() == len(os.sched_getaffinity(0))


def test_pieces_run_in_order_on_at_most_the_threads_asked_and_errors_come_through(monkeypatch: pytest.MonkeyPatch) -> None:
    """``features.batch.run_pieces`` with stand-in scans: every result in the scans' order, pieces
    of at most ``chunk``, never more threads at once than asked (each call has its own, so a
    smaller count after a larger one holds), a piece's error raised as itself, and a piece that
    calls ``run_pieces`` again (nested) finishes instead of waiting on a shared pool."""
    import threading

    import features.batch as fbatch

    monkeypatch.setattr(fbatch, "MIN_SCANS_PER_THREAD", 4)
    lock = threading.Lock()
    active = {"now": 0, "most": 0}
    idents: set[int] = set()

    def echo(piece, cfg):
        with lock:
            active["now"] += 1
            active["most"] = max(active["most"], active["now"])
            idents.add(threading.get_ident())
        assert len(piece) <= 7 and cfg == "cfg"
        out = [x * 10 for x in piece]
        with lock:
            active["now"] -= 1
        return out

    items = list(range(100))
    assert fbatch.run_pieces(echo, items, "cfg", 8, 7) == [x * 10 for x in items]
    assert active["most"] <= 8 and len(idents) <= 8
    active["most"] = 0
    idents.clear()
    assert fbatch.run_pieces(echo, items, "cfg", 2, 7) == [x * 10 for x in items]  # after 8: still 2
    assert active["most"] <= 2 and len(idents) <= 2

    def fails(piece, cfg):
        if 50 in piece:
            raise ZeroDivisionError("piece with 50")
        return list(piece)

    with pytest.raises(ZeroDivisionError, match="piece with 50"):
        fbatch.run_pieces(fails, items, "cfg", 4, 10)

    def nested(piece, cfg):
        return fbatch.run_pieces(echo, list(piece), cfg, 2, 7)

    assert fbatch.run_pieces(nested, items, "cfg", 3, 50) == [x * 10 for x in items]


def test_an_endless_iterator_is_refused_not_read_until_memory_runs_out(monkeypatch) -> None:
    """``extract_many(itertools.repeat(scan))`` (or a generator that never ends) read on until
    memory ran out (a MemoryError under a 3 GB address-space limit; without one, the machine's).
    An iterator is read up to features.batch.MAX_ITERATOR_BEAMS beams; more is a BatchSizeError
    (an LmsbenchError and a ValueError) saying to pass a list; lists, tuples and finite
    generators give what they gave."""
    import itertools

    from features import batch as batch_module
    from features.errors import BatchSizeError
    from lms200 import LmsbenchError

    assert batch_module.MAX_ITERATOR_BEAMS == 1 << 27  # 371,794 scans of 361 beams: a 45 min log's 101,250 pass
    scan = room(0)
    assert len(scan) == 361

    def endless():
        while True:
            yield scan

    for method, scans in (("sensor", itertools.repeat(scan)), ("split_merge", endless()), ("hough", endless())):
        with pytest.raises(BatchSizeError, match=re.escape(
                f"scans: an iterator or generator ({type(scans).__name__}) that yielded more than 134,217,728 beams "
                "(371,795 scans) without ending: extract_many returns one FeatureSet a scan, so it takes a finite batch; "
                "pass a list or tuple of scans, or call it on pieces of the iterator (itertools.islice(scans, 4096))")) as info:
            extract_many(scans, method=method)
        assert isinstance(info.value, LmsbenchError) and isinstance(info.value, ValueError)
    with pytest.raises(ScanTypeError, match=r"^scans\[0\]: expected an lms200.Scan, got int$"):
        extract_many(itertools.count())  # an endless iterator of something else: its first item says so
    monkeypatch.setattr(batch_module, "MAX_ITERATOR_BEAMS", 361 * 5)  # the bound itself is taken
    scans = batch(12)[:5]
    want = [extract(s) for s in scans]
    for given in (iter(scans), (s for s in scans), tuple(scans), scans):
        got = extract_many(given)
        assert len(got) == 5
        for fs, ref in zip(got, want):
            assert_equal_sets(fs, ref)
    assert len(extract_many(scans * 2)) == 10  # a list is taken whole, whatever the bound
    with pytest.raises(BatchSizeError, match=r"more than 1,805 beams \(6 scans\)"):
        extract_many(iter(scans + scans[:1]))


@pytest.mark.parametrize("method", available_methods())
def test_an_empty_batch_on_several_threads_is_an_empty_list(method: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """extract_many([], threads=2), and extract_many([]) with $LMSBENCH_THREADS=2, was an IndexError
    from the geometry check of the (empty) batch; one thread gave []."""
    from features.batch import THREADS_ENV

    assert extract_many([], method=method, threads=2) == []
    assert extract_many(iter(()), method=method, threads=4) == []
    monkeypatch.setenv(THREADS_ENV, "2")
    assert extract_many((), method=method) == []


def test_a_registered_run_many_is_given_scans_of_one_geometry_only() -> None:
    """Fuzz round 10: a user's run_many was handed a batch of one piece unchecked (a str among the scans, or scans of
    two range_max, went in, exit 0; None a raw TypeError after it ran); the built-in methods and a batch in pieces
    refused them."""
    import dataclasses

    from features import FeatureSet, register
    from features.errors import ScanTypeError
    from features.registry import _REGISTRY

    @dataclasses.dataclass(frozen=True)
    class Cfg:
        a: int = 1

    given: list[list[object]] = []
    register("fuzz_geometry", Cfg, lambda scan, cfg: FeatureSet(),
             run_many=lambda scans, cfg: given.append(list(scans)) or [FeatureSet() for _ in scans])
    scan = room(0)
    try:
        with pytest.raises(ValueError, match=r"^scans\[1\]: geometry"):
            extract_many([scan, scan.replace(range_max=81.83)], method="fuzz_geometry")
        for item in ("x", None):
            with pytest.raises(ScanTypeError, match=r"^scans\[1\]: expected an lms200.Scan"):
                extract_many([scan, item], method="fuzz_geometry")  # type: ignore[list-item]
        assert given == []
        assert len(extract_many([scan, scan], method="fuzz_geometry")) == 2 and given == [[scan, scan]]
    finally:
        _REGISTRY.pop("fuzz_geometry", None)
