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
