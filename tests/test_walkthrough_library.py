"""A researcher's walkthrough of lmsbench as a Python library (README and docs/*.md alone, no
command line), 2026-12-05: what the docs said that the code did not do, one test each."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_features_page_states_the_iterator_cap_extract_many_applies() -> None:
    """docs/features.md said an iterator is read up to 92,948 scans of 361 beams (2^25 beams, the
    cap before a review raised it); the code's cap is 2^27 beams, 371,794 such scans."""
    from features import batch

    text = " ".join((ROOT / "docs" / "features.md").read_text().split())
    scans = batch.MAX_ITERATOR_BEAMS // 361
    assert scans == 371_794
    assert f"{scans:,} scans of 361" in text
    assert "92,948" not in text


def test_records_in_memory_measure_repeatability_through_their_corrected_poses() -> None:
    """``Source.from_records(records)`` without truths is "like a log", but it left its records'
    corrected poses unused: ``read_log`` of Intel into it gave repeatability nan where ``compare``
    of the file gives 0.82. Now the corrected poses count, giving what the same poses give as true
    poses to a source with truths."""
    import numpy as np

    from experiments.compare import Source, compare
    from lms200 import Record
    from sim import simulate_records, visible_truth
    from sim.worlds import make_world

    sim_recs = simulate_records("office", seed=2, duration=2.0, rate_hz=5)
    world = make_world("office", 2)
    truths = [visible_truth(world, r.truth) for r in sim_recs]
    as_log = [Record(r.scan, corrected=r.truth) for r in sim_recs]
    with_truth = compare([Source.from_records(sim_recs, truths, name="run")], ["split_merge"], sigma=0.005)
    from_log = compare([Source.from_records(as_log, name="run")], ["split_merge"], sigma=0.005)
    assert from_log["repeat_in_view"].sum() > 10  # was nan on every row
    np.testing.assert_array_equal(from_log["repeat_found"].to_numpy(), with_truth["repeat_found"].to_numpy())
    np.testing.assert_array_equal(from_log["repeat_in_view"].to_numpy(), with_truth["repeat_in_view"].to_numpy())
    without = compare([Source.from_records([Record(r.scan) for r in sim_recs], name="run")], ["split_merge"], sigma=0.005)
    assert without["repeat_in_view"].isna().all()  # no pose to trust: not measured, as before


def test_a_corrected_log_read_into_memory_scores_as_the_file_does() -> None:
    """The first 40 scans of Intel: ``from_records(read_log(...))`` and ``log_source`` give the same
    repeatability counts (the walkthrough's case; skipped without the real logs)."""
    import dataclasses
    import itertools

    import numpy as np
    import pytest

    from experiments.compare import Source, compare, log_source
    from lms200 import read_log

    path = ROOT.parent / "shared" / "data" / "carmen" / "intel-corrected.log.gz"
    if not path.exists():
        pytest.skip(f"{path} is absent")
    recs = list(itertools.islice(read_log(path), 40))
    in_memory, from_file = Source.from_records(recs, name=path.name), log_source(path, max_scans=40)
    for field in dataclasses.fields(Source):  # the noise of the whole log, as the file's source estimates it
        if field.name.startswith("estimate_"):
            setattr(in_memory, field.name, getattr(from_file, field.name))
    mem = compare([in_memory], ["split_merge"], sigma=0.01)
    log = compare([from_file], ["split_merge"], sigma=0.01)
    assert mem["repeat_in_view"].sum() > 50
    np.testing.assert_array_equal(mem["repeat_found"].to_numpy(), log["repeat_found"].to_numpy())
    np.testing.assert_array_equal(mem["repeat_in_view"].to_numpy(), log["repeat_in_view"].to_numpy())


def test_log_source_reads_at_most_max_scans(tmp_path) -> None:
    """``log_source(path, max_scans=N)`` took N as the progress bar's total only and gave every scan
    of the log (Intel: 910 for max_scans=40); now it gives at most N, every ``stride``-th."""
    from experiments.compare import log_source
    from lms200 import write_log
    from sim import simulate_records

    recs = simulate_records("office", seed=1, duration=2.0, rate_hz=10)
    path = tmp_path / "run.clf"
    write_log(path, recs)
    stamps = [r.scan.stamp for r in recs]
    assert [r.scan.stamp for r in log_source(path, max_scans=4).records] == stamps[:4]
    assert [r.scan.stamp for r in log_source(path, stride=3, max_scans=4).records] == stamps[::3][:4]
    assert len(list(log_source(path).records)) == len(recs) > 12


def _hokuyo_room(range_max: float):
    """A 1081-beam, 270 deg scan (0.25 deg) of a room's three walls with 2 cm noise."""
    import numpy as np

    from lms200 import Scan

    n, amin, inc = 1081, -3 * np.pi / 4, np.radians(0.25)
    b = amin + inc * np.arange(n)
    walls = []
    for rho, alpha in ((3.0, 0.0), (2.0, np.pi / 2), (2.5, -np.pi / 2)):
        c = np.cos(b - alpha)
        walls.append(np.where(c > 1e-9, rho / np.where(c > 1e-9, c, 1.0), np.inf))
    r = np.min(walls, axis=0) + np.random.default_rng(0).normal(0.0, 0.02, n)
    return Scan(r, angle_min=amin, angle_increment=inc, range_min=0.02, range_max=range_max)


def test_a_noise_field_the_scan_does_not_read_is_said() -> None:
    """A 30 m scanner's scan reads ``sigma_r_cm`` (range_max > 10 m), so ``extract(scan,
    sigma_r=0.005)`` ran with "auto", silently (the walkthrough's Hokuyo-like scan of one wall: 1 line
    for any sigma_r, 8 for sigma_r_cm=0.005). Now a one-line LmsbenchWarning names the field to set; the
    features are what they were."""
    import warnings

    import pytest

    from features import extract, extract_many
    from lms200.errors import LmsbenchWarning

    far, near = _hokuyo_room(30.0), _hokuyo_room(5.6)
    with pytest.warns(LmsbenchWarning, match=r"^extract: sigma_r=0.005 is not read: a scan whose range_max is above "
                      r"10 m \(SICK cm codes\), as this one's 30 m, reads sigma_r_cm \(now 'auto'\); set sigma_r_cm for it$"):
        fs = extract(far, sigma_r=0.005)
    assert fs.lines == extract(far).lines
    with pytest.warns(LmsbenchWarning, match=r"^extract_many: sigma_r_cm=0.02 is not read: a scan whose range_max is "
                      r"of 10 m or less \(SICK mm codes\), as this one's 5.6 m, reads sigma_r \(now 0.005\)"):
        extract_many([near, near], sigma_r_cm=0.02)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert extract(far, sigma_r_cm=0.005).lines != fs.lines  # the field it reads (no warning) counts
        extract(near, sigma_r=0.02)
        extract(far, sigma_r=0.005, sigma_r_cm=0.005)
        extract(far, method="split_merge", sigma=0.02)  # no such pair of fields
        extract_many([far], sigma_r_cm=0.005)


def test_a_virtual_device_fed_records_says_so_when_built() -> None:
    """``VirtualLMS200(read_log(path))`` (records, not scans) was taken, and its first scan telegram
    failed in the adapter's thread: a traceback on stderr and, for the host, a driver timeout after
    4.4 s. The device takes its first item when built, so it now says it there."""
    import numpy as np
    import pytest

    from lms200 import InputError, Record, Scan
    from lms200.virtual import VirtualLMS200

    scan = Scan.lms200(np.full(361, 2.0))
    with pytest.raises(InputError, match=r"^source: item 0 is a Record, not an lms200.Scan \(a log's records: pass "
                       r"their scans, rec.scan for rec in read_log\(path\)\)$"):
        VirtualLMS200([Record(scan)])
    with pytest.raises(InputError, match=r"^source: item 0 is a ndarray, not an lms200.Scan$"):
        VirtualLMS200([scan.ranges])
    VirtualLMS200([scan])  # a Scan is taken


def test_an_adapter_raises_what_stopped_its_device_at_close() -> None:
    """A source whose second item is no Scan stopped the adapter's thread with a traceback on
    stderr; the host's driver timed out and the ``with`` block ended without an error from the
    adapter. Now ``close()`` (the block's end) raises the device's error, once."""
    import numpy as np
    import pytest

    from lms200 import LMS200, InputError, Scan
    from lms200.adapters import PtyAdapter
    from lms200.errors import LmsDeviceError
    from lms200.virtual import VirtualLMS200

    scan = Scan.lms200(np.full(361, 2.0))
    got = []
    with pytest.raises(InputError, match=r"^source: item 1 is a ndarray, not an lms200.Scan$") as caught:
        with PtyAdapter(VirtualLMS200(iter([scan, scan.ranges]), time_scale=0.01)) as pty:
            with LMS200(pty.path, baud=38400, timeout=0.1, mode_timeout=0.3, retries=1) as dev:
                for s in dev.scans(stall_timeout=0.5):
                    got.append(s)
    assert len(got) == 1 and np.array_equal(got[0].ranges, scan.ranges)
    assert isinstance(caught.value.__context__, LmsDeviceError)  # the host's timeout, behind it
    assert pty.error is None  # raised once
    pty.close()


def test_lines_and_corners_take_numpy_style_row_selections() -> None:
    """``fs.lines[fs.lines.length > 0.5]`` (a boolean mask) was numpy's "cannot reshape array of
    size 32 into shape (2,2)", ``fs.lines[[0, 1]]`` "list index out of range" and ``fs.corners[[0]]``
    "not enough values to unpack"; they now select rows as Lines / Corners, the same rows as the
    arrays, and an index of another kind is an InputError naming it."""
    import numpy as np
    import pytest

    from features import extract
    from features.types import Corners, Lines
    from lms200 import InputError

    fs = extract(_hokuyo_room(5.6), sigma_r=0.02)
    lines, corners = fs.lines, fs.corners
    assert len(lines) >= 3 and len(corners) >= 1
    long = lines[lines.length > 4.7]
    assert isinstance(long, Lines) and 0 < len(long) < len(lines)
    np.testing.assert_array_equal(long.values, lines.values[lines.length > 4.7])
    np.testing.assert_array_equal(long.beams, lines.beams[lines.length > 4.7])
    pair = lines[[0, -1]]
    assert len(pair) == 2 and pair[1].first == lines[-1].first and pair[0].rho == lines[0].rho
    assert lines[np.array([], dtype=np.int64)] == Lines.empty()
    assert isinstance(corners[[0]], Corners) and corners[[0]][0] == corners[0]
    assert lines[np.int64(1)].last == int(lines.last[1])
    with pytest.raises(IndexError, match=rf"^lines: index {len(lines)} is out of range for {len(lines)} lines$"):
        lines[len(lines)]
    with pytest.raises(IndexError, match=r"^corners: index 7 is out of range"):
        corners[[7]]
    with pytest.raises(InputError, match=r"^lines: an index must be an int, a slice, .* got float$"):
        lines[1.0]
    with pytest.raises(InputError, match=r"^lines: an index must be .* got ndarray of shape \(2,\) and dtype bool$"):
        lines[np.array([True, False])]  # a mask of another length
    assert [line.first for line in lines] == lines.first.tolist()  # iteration as before


def test_scans_out_of_time_order_are_refused_saying_how_to_go_on() -> None:
    """``run_slam`` of Intel's corrected log stopped at "scan 295: timestamp 940.54 is earlier than
    the previous one (940.654)" with no word of what to do; both presets now name the helper that
    keeps the most scans in order, and the records it keeps run."""
    import pytest

    from experiments.commands.slam import in_time_order
    from lms200 import Record
    from sim import simulate_records
    from slam import SlamConfig, SlamInputError, run_slam

    recs = simulate_records("office", seed=1, duration=2.0, rate_hz=10)
    late = Record(recs[3].scan.replace(stamp=recs[1].scan.stamp - 0.01), truth=recs[3].truth)
    shuffled = recs[:3] + [late] + recs[4:]
    for preset in ("default", "paper"):
        with pytest.raises(SlamInputError, match=r"^scan 3: timestamp .* is earlier than the previous one .*; SLAM "
                           r"needs scans in time order: drop those out of order \(experiments.commands.slam."
                           r"in_time_order\(stamps\) gives the indices of the most scans in order"):
            run_slam(shuffled, SlamConfig(preset=preset))
    keep = in_time_order([r.scan.stamp for r in shuffled])
    assert keep == [k for k in range(len(shuffled)) if k != 3]
    assert run_slam([shuffled[k] for k in keep]).trajectory.shape == (len(recs) - 1, 4)


def test_a_clockwise_scan_and_a_truth_dict_are_refused_saying_what_to_do() -> None:
    """Two refusals of the walkthrough that named the fault but not the way out: a scan of a laser
    mounted upside down (ROS: angle_increment < 0) was "angle_increment: must be > 0, got -0.1",
    and a truth given as a dict of its four arrays "truth: ... dict lacks segments, segment_beams,
    corners, corner_beams" (it held all four). Both now say what to pass instead."""
    import types

    import numpy as np
    import pytest

    from features import extract
    from features.scoring import score_scan
    from lms200 import InputError, Scan, ScanError

    with pytest.raises(ScanError, match=r"^angle_increment: must be > 0, got -0.1 \(beams clockwise, a laser mounted "
                       r"upside down: reverse the ranges, ranges\[::-1\], and start at the last beam's bearing"):
        Scan(np.ones(5), angle_min=0.2, angle_increment=-0.1, range_min=0.0, range_max=10.0)
    with pytest.raises(ScanError, match=r"^angle_increment: must be > 0, got 0.0$"):
        Scan(np.ones(5), angle_min=0.2, angle_increment=0.0, range_min=0.0, range_max=10.0)
    scan = _hokuyo_room(5.6)
    truth = {"segments": [(3.0, -2.5, 3.0, 2.0)], "segment_beams": [(252, 828)], "corners": np.zeros((0, 4)),
             "corner_beams": []}
    fs = extract(scan, sigma_r=0.02)
    with pytest.raises(InputError, match=r"lacks segments, segment_beams, corners, corner_beams as attributes \(a "
                       r"mapping's keys are not read: pass types.SimpleNamespace\(\*\*truth\)\)$"):
        score_scan(fs, truth)
    assert score_scan(fs, types.SimpleNamespace(**truth)).tp == 1  # the wall x = 3 m, as the hint says
    with pytest.raises(InputError, match=r"object lacks segments, segment_beams, corners, corner_beams$"):
        score_scan(fs, object())  # no hint where it does not apply
