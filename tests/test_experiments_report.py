"""The demo report says what its timing table measures: each method's backend, from the table."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from experiments.demo import method_table, timing_note
from features.registry import backend_of


def test_the_report_states_each_methods_backend_from_the_summary():
    methods = ["sensor", "split_merge", "iepf", "hough", "ransac"]
    summary = pd.DataFrame({"method": methods, "backend": [backend_of(m) for m in methods],
                            "time_ms_median": [0.07, 0.1, 0.09, 2.0, 3.0], "f1": [0.9, 0.8, 0.8, 0.7, 0.7]})
    shown = method_table(summary)
    assert list(shown.columns[:2]) == ["method", "backend"]
    assert dict(zip(shown["method"], shown["backend"])) == {m: backend_of(m) for m in methods}
    note = timing_note(summary)
    assert "Python + numpy" not in note
    if backend_of("sensor") == "numba":  # the default (backend="auto") where numba is installed
        assert "`sensor`, `split_merge`, `iepf` on numba-compiled kernels" in note
        assert "`hough`, `ransac` on vectorised numpy" in note
        assert "among `sensor`, `split_merge`, `iepf` compare compiled with compiled code" in note


def test_an_all_numpy_summary_says_so_and_claims_no_compiled_comparison():
    summary = pd.DataFrame({"method": ["sensor", "hough"], "backend": ["numpy", "numpy"]})
    note = timing_note(summary)
    assert "`sensor`, `hough` on vectorised numpy" in note and "compiled with compiled" not in note
    mixed = pd.DataFrame({"method": ["sensor", "hough"], "backend": ["numba", "numpy"]})
    assert "not like for like" in timing_note(mixed)


def test_the_copied_report_points_its_larger_sweeps_at_the_checkout_not_into_the_run(tmp_path):
    """results/demo/report.md said `RUN/sweeps/*.yaml` (the copy's links rebased into the run folder),
    where the run holds only sweeps/demo_k_vs_noise/: the larger sweeps are the checkout's sweep files."""
    from experiments.commands.demo import copy_report_up
    from experiments.demo import sweep_note

    run = tmp_path / "2026-01-01_00-00-00"
    run.mkdir()
    (run / "report.md").write_text(sweep_note(9, 0) + "\n")
    (run / "report.html").write_text("<html></html>")
    copy_report_up(run / "report.md")
    copied = (tmp_path / "report.md").read_text()
    assert "`2026-01-01_00-00-00/sweeps/demo_k_vs_noise/results.parquet`" in copied
    assert "2026-01-01_00-00-00/sweeps/*.yaml" not in copied
    assert "`lmsbench sweep sweeps/k_vs_noise.yaml` from the checkout" in copied
    assert (Path(__file__).resolve().parents[1] / "sweeps" / "k_vs_noise.yaml").is_file()


def test_the_sim2real_section_names_the_log_by_a_path_that_runs_from_here(tmp_path, monkeypatch):
    """The demo's report said `lmsbench sim2real mit-csail.clf.gz runs the full comparison`: the
    bare name does not run from the checkout; the section gives the log's path, as its advice does."""
    import os
    from types import SimpleNamespace

    import experiments.sim2real as s2r
    from experiments.demo import _sim2real_section
    from experiments.figures.study import StudyConfig

    log = tmp_path / "logs" / "mit-csail.clf.gz"
    log.parent.mkdir()
    log.write_bytes(b"")
    seen = {}

    def fake_sim2real(path, **kw):
        seen["advice"] = kw["advice"]
        return SimpleNamespace(n_real=40, n_sim=30, probe_seeds=[100], warnings=[])

    monkeypatch.setattr(s2r, "sim2real", fake_sim2real)
    monkeypatch.setattr(s2r, "write_outputs", lambda *a, **k: None)
    monkeypatch.setattr(s2r, "format_report", lambda result, name: "# title\n\nthe tables")
    monkeypatch.chdir(tmp_path)
    cfg = StudyConfig(duration=4.0, rate_hz=10.0)
    cfg.sim2real_log = str(log)
    section = _sim2real_section(cfg, tmp_path / "out", lambda line: None)
    command = f"`lmsbench sim2real {os.path.join('logs', 'mit-csail.clf.gz')}`"
    assert f"no wall relief fitted; {command} runs the full comparison." in section.text[0]
    assert command in seen["advice"]
