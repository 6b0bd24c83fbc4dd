"""Outputs that reproduce and figures without defects: run folders with a `latest` link, the
user's umask on result files, readable log axes, honest sweep error bars, a self-contained report."""

from __future__ import annotations

import datetime
import os
from pathlib import Path

import numpy as np
import pandas as pd

from experiments.figures.draw import fig_sweep
from experiments.provenance import link_latest, new_run_folder, versions
from experiments.report import markdown_to_html
from experiments.style import label_of, log_axis, new_figure
from experiments.sweep.store import write_atomic


def test_runs_without_out_never_overwrite_each_other(tmp_path):
    now = datetime.datetime(2026, 12, 1, 22, 0, 0)
    a = new_run_folder(tmp_path / "compare", now)
    b = new_run_folder(tmp_path / "compare", now)  # the same second: a suffix
    assert a.name == "2026-12-01_22-00-00" and b.name == "2026-12-01_22-00-00-2" and a.is_dir() and b.is_dir()
    latest = tmp_path / "compare" / "latest"
    assert not latest.exists()  # a run folder is linked once its run has finished, not when it is made
    assert link_latest(b) == latest and latest.is_symlink() and latest.resolve() == b.resolve()


def _bench_areas(monkeypatch) -> None:
    import types

    import experiments.commands.bench as bench

    monkeypatch.setattr(bench, "discover", lambda: {"a": types.SimpleNamespace(run=lambda quick: [{"case": "x", "v": 1.0}])})


def test_latest_names_the_last_run_that_finished_not_one_stopped_midway(tmp_path, monkeypatch, capsys):
    """`results/CMD/latest` was moved when the run folder was made: `lmsbench bench` (or compare,
    figures, sim2real, demo) stopped by Ctrl-C or an error after that left latest naming a folder
    without bench.csv, the finished run before it no longer linked. It now moves once the run's
    outputs are all written."""
    from experiments import provenance
    from experiments.cli import main

    _bench_areas(monkeypatch)
    monkeypatch.chdir(tmp_path)
    assert main(["bench"]) == 0
    latest = tmp_path / "results" / "bench" / "latest"
    finished = latest.resolve()
    assert (finished / "bench.csv").is_file()
    real = provenance.write_record

    def stopped_at_the_table(path, content):
        if Path(path).name == "bench.csv":
            raise KeyboardInterrupt  # Ctrl-C while the table is written
        return real(path, content)

    monkeypatch.setattr(provenance, "write_record", stopped_at_the_table)
    for _ in range(2):  # two stopped runs: each leaves its folder, neither is linked
        assert main(["bench"]) == 130
    assert capsys.readouterr().err.splitlines() == ["lmsbench bench: interrupted"] * 2
    folders = sorted(p for p in latest.parent.iterdir() if p.name != "latest")
    assert len(folders) == 3 and not (folders[-1] / "bench.csv").exists()
    assert latest.resolve() == finished  # old: the last stopped run's folder, without bench.csv
    monkeypatch.setattr(provenance, "write_record", real)
    assert main(["bench"]) == 0
    assert latest.resolve() not in folders and (latest.resolve() / "bench.csv").is_file()


def test_a_demo_that_fails_midway_leaves_latest_at_the_last_finished_demo(tmp_path, monkeypatch, capsys):
    """`lmsbench demo` made results/demo/DATE_TIME and linked it as latest before its minutes of
    work: an error or Ctrl-C in the study left latest naming a folder with no report."""
    import experiments.demo
    from experiments.cli import main
    from lms200 import LmsbenchError

    def failing_demo(out, cfg, sweep_executor="local", log=print):
        (out / "tables").mkdir()
        raise LmsbenchError("the study failed")

    monkeypatch.setattr(experiments.demo, "run_demo", failing_demo)
    monkeypatch.chdir(tmp_path)
    assert main(["demo", "--no-sweep", "--duration", "2"]) == 2
    assert capsys.readouterr().err.splitlines() == ["lmsbench demo: error: the study failed"]
    base = tmp_path / "results" / "demo"
    assert not (base / "latest").exists() and not (base / "latest").is_symlink()  # old: linked to the failed run
    assert len(list(base.iterdir())) == 1


def test_versions_name_python_and_the_numeric_libraries():
    v = versions()
    assert v["python"].startswith("3.11") and "numpy" in v and "lmsbench" in v


def test_versions_name_the_checkouts_commit(monkeypatch):
    """Every result's record of versions gave the package's version alone (0.1.0 for every commit);
    `lmsbench --version` could tell the commit, the records beside the results could not. Run from a
    git checkout they now hold it; elsewhere (an installed wheel) they leave it out."""
    import subprocess

    from experiments import provenance

    if provenance.checkout_commit() is not None:
        head = subprocess.run(["git", "-C", str(provenance.CHECKOUT), "rev-parse", "--short=12", "HEAD"],
                              capture_output=True, text=True, check=True).stdout.strip()
        assert versions()["lmsbench_git"].startswith(head)
    monkeypatch.setattr(provenance, "checkout_commit", lambda: None)
    assert "lmsbench_git" not in versions()
    monkeypatch.setattr(provenance, "checkout_commit", lambda: "0123456789ab, modified")
    assert versions()["lmsbench_git"] == "0123456789ab, modified"


def test_result_files_get_the_users_umask(tmp_path):
    old = os.umask(0o022)
    try:
        write_atomic(pd.DataFrame({"a": [1]}), tmp_path / "t.parquet")
        write_atomic(pd.DataFrame({"a": [1]}), tmp_path / "t.csv")
    finally:
        os.umask(old)
    for name in ("t.parquet", "t.csv"):
        assert (tmp_path / name).stat().st_mode & 0o777 == 0o644, name


def _labels(ax, which: str) -> list:
    fig = ax.figure
    fig.canvas.draw()
    axis = ax.xaxis if which == "x" else ax.yaxis
    ticks = [t for t in axis.get_major_ticks() + axis.get_minor_ticks()
             if t.label1.get_visible() and t.label1.get_text()]
    lo, hi = sorted(ax.get_xlim() if which == "x" else ax.get_ylim())
    return [t for t in ticks if lo <= t.get_loc() <= hi]


def test_log_axes_have_plain_decimal_labels_that_do_not_overlap():
    for lo, hi in ((0.055, 0.95), (0.08, 3.0), (0.05, 300.0)):
        fig, ax = new_figure()
        ax.plot([lo, hi], [1, 2], "o")
        log_axis(ax, "x")
        ticks = _labels(ax, "x")
        texts = [t.label1.get_text() for t in ticks]
        assert texts and all("e" not in s and "$" not in s for s in texts), texts
        for s in texts:
            float(s)  # plain decimals
        renderer = fig.canvas.get_renderer()
        boxes = sorted((t.label1.get_window_extent(renderer) for t in ticks), key=lambda b: b.x0)
        for left, right in zip(boxes, boxes[1:]):
            assert left.x1 <= right.x0 + 0.5, (lo, hi, texts)


def test_a_sweep_with_one_seed_has_no_error_bars_and_says_so(tmp_path):
    table = pd.DataFrame({"extractor.k": [3, 5, 10], "f1": [0.9, 0.95, 0.8], "seed": [0, 0, 0], "status": "ok"})
    paths = fig_sweep(table, "extractor.k", "f1", tmp_path / "s")
    stats = pd.read_csv([p for p in paths if p.suffix == ".csv"][0])
    assert stats["count"].max() == 1
    assert label_of("extractor.k") == "window half-width k (beams)" and label_of("rho_rms_mm").endswith("(mm)")
    two = pd.concat([table, table.assign(seed=1, f1=table["f1"] - 0.02)])
    fig_sweep(two, "extractor.k", "f1", tmp_path / "t")
    assert np.allclose(pd.read_csv(tmp_path / "t.csv")["std"], np.std([0.0, 0.02], ddof=1))


def test_the_html_report_embeds_its_images_and_fits_the_page(tmp_path):
    (tmp_path / "figures").mkdir()
    fig, ax = new_figure()
    ax.plot([0, 1], [0, 1])
    fig.savefig(tmp_path / "figures" / "x.png")
    html = markdown_to_html("# T\n\n![cap](figures/x.png)\n\n| a | b |\n|---|---|\n| 1 | 2 |\n", "T", images=tmp_path)
    assert "src='data:image/png;base64,iVBOR" in html and "figures/x.png" not in html
    assert "max-width:100%" in html and "<div class='wide'><table>" in html
    linked = markdown_to_html("![cap](figures/x.png)", "T")  # without a folder: links, as before
    assert "<img src='figures/x.png' alt='cap'>" in linked


def test_compare_runs_a_users_extractor_by_module_and_function(tmp_path, monkeypatch, capsys, user_methods_dropped):
    from experiments.cli import main


    (tmp_path / "frontdoor_ext.py").write_text(
        "from features import extract\n"
        "def lines(scan):\n"
        "    return extract(scan, method='split_merge')  # a user's method: here the baseline, renamed\n"
        "def wrong(scan):\n"
        "    return 42\n")
    monkeypatch.chdir(tmp_path)
    assert main(["compare", "office:0", "--duration", "2", "--rate", "2", "--methods", "split_merge", "frontdoor_ext:lines",
                 "--out", str(tmp_path / "out"), "--no-progress", "--format", "csv"]) == 0
    summary = pd.read_csv(tmp_path / "out" / "summary.csv").set_index("method")
    assert summary.loc["frontdoor_ext:lines", "f1"] == summary.loc["split_merge", "f1"]  # same features, same scoring
    assert summary.loc["frontdoor_ext:lines", "tp"] == summary.loc["split_merge", "tp"] > 0
    # `--method module:function`, the spelling issue #16 names, was refused ('unrecognized arguments') once
    # abbreviations were switched off: it is the same option
    assert main(["compare", "office:0", "--duration", "2", "--rate", "2", "--method", "frontdoor_ext:lines",
                 "--out", str(tmp_path / "one"), "--no-progress", "--format", "csv"]) == 0
    one = pd.read_csv(tmp_path / "one" / "summary.csv").set_index("method")
    assert list(one.index) == ["frontdoor_ext:lines"] and one.loc["frontdoor_ext:lines", "f1"] == summary.loc["split_merge", "f1"]
    capsys.readouterr()
    for argv, message in ((["frontdoor_ext:nosuch"], "has no 'nosuch'"), (["nomodule:f"], "cannot import module"),
                          (["frontdoor_ext:wrong"], "returned int, not a features.FeatureSet")):
        assert main(["compare", "office:0", "--duration", "1", "--methods", *argv, "--out", str(tmp_path / "o2"),
                     "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err
