"""The real pipeline on short simulated runs: the figure command writes every named figure, the
built-in sweep cells agree with ``experiments.compare`` run independently, and the demo writes
its report."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import sim
from experiments.cli import main
from experiments.figures.make import PAPER_FIGURES
from experiments.figures.study import INTEL_LOG

if not hasattr(sim, "simulate_records"):  # pragma: no cover - only while sim is being built
    pytest.skip("sim.simulate_records is not available yet", allow_module_level=True)


def test_extract_cell_agrees_with_compare_on_the_same_simulated_run():
    from experiments.compare import compare, sim_source, summarise
    from experiments.sweep.kinds import extract_cell

    params = {"method": "split_merge", "world": "office", "seed": 3, "duration": 2.0, "rate_hz": 2.0,
              "extractor.split_threshold": 0.05}
    cell = extract_cell(params)
    source = sim_source("office", seed=3, duration=2.0, rate_hz=2.0)
    reference = summarise(compare([source], ["split_merge"], params={"split_merge": {"split_threshold": 0.05}})).iloc[0]
    for name in ("tp", "fp", "fn", "f1", "rho_rms_mm", "corner_precision", "corner_recall", "lines_per_scan", "scans"):
        assert cell[name] == pytest.approx(float(reference[name]), nan_ok=True), name
    assert cell["scans"] == 4 and cell["time_ms_median"] > 0


def test_slam_cell_reports_trajectory_error_against_truth():
    from experiments.sweep.kinds import slam_cell

    params = {"world": "office", "seed": 0, "duration": 4.0, "rate_hz": 10.0, "slam.extractor_params.k": 5}
    cell = slam_cell(params)
    assert cell["scans"] == pytest.approx(len(sim.simulate_records("office", 0, 4.0, rate_hz=10.0)))
    assert 0 <= cell["ate_rms"] <= cell["ate_max"] and np.isfinite(cell["final_error_m"])
    # slam.extractor_params.NAME reaches the SLAM's extractor: an unknown name is refused there
    with pytest.raises(ValueError, match="no_such_field"):
        slam_cell({**params, "slam.extractor_params.no_such_field": 1})


@pytest.mark.slow
def test_the_figure_command_writes_every_named_figure_and_redraws_from_its_tables(tmp_path, capsys):
    out = tmp_path / "figs"
    assert main(["figures", "--out", str(out), "--duration", "4", "--rate-hz", "5",
                 "--methods", "sensor", "iepf"]) == 0
    expected = [n for n in PAPER_FIGURES if n != "fig9_intel" or INTEL_LOG.exists()]
    for name in expected:
        for suffix in (".png", ".pdf"):
            assert (out / f"{name}{suffix}").stat().st_size > 1000, name
        assert list(out.glob(f"{name}*.csv")), name
    if not INTEL_LOG.exists():
        assert "Intel log" in capsys.readouterr().out
    timing = pd.read_csv(out / "fig7_timing.csv")
    assert set(timing["method"]) == {"sensor", "iepf"} and len(timing) == 2 * timing["scan"].nunique()
    signals = pd.read_csv(out / "fig4_ad.csv")
    assert len(signals) == 361
    # on straight walls AD_i10 sits at 1 + 2 sum cos(j * 0.5 deg) (eq. 4): the median beam is on one
    assert np.nanmedian(signals["ad"]) == pytest.approx(1 + 2 * np.cos(np.deg2rad(0.5) * np.arange(1, 11)).sum(), abs=0.05)
    # a log option with --tables was ignored (the figures redrawn as they were, exit 0): refused
    capsys.readouterr()
    assert main(["figures", "--tables", str(out / "tables"), "--laser-range-max", "50", "--out", str(tmp_path / "lr")]) == 2
    assert "--laser-range-max does not apply to --tables" in capsys.readouterr().err and not (tmp_path / "lr").exists()
    # redraw from the saved tables alone: the same data beside the figures; and a folder of its own
    # earlier outputs is replaced (here redrawn from its own tables: every CSV and figure made stale
    # first, so each one is written again); one with a file of the user's is refused, untouched.
    # (One redraw for both: a redraw into a new folder, which this did too, is the one from the
    # emptied tables below.)
    drawn = {csv.name: pd.read_csv(csv) for name in expected for csv in sorted(out.glob(f"{name}*.csv"))}
    for name in expected:
        for stale in [*out.glob(f"{name}*.csv"), out / f"{name}.png", out / f"{name}.pdf"]:
            stale.write_text("stale\n")
    assert main(["figures", "--tables", str(out / "tables"), "--out", str(out)]) == 0
    assert sorted(drawn) == sorted(csv.name for name in expected for csv in out.glob(f"{name}*.csv"))
    for csv_name, table in drawn.items():
        pd.testing.assert_frame_equal(pd.read_csv(out / csv_name), table)
    for name in expected:
        for suffix in (".png", ".pdf"):
            assert (out / f"{name}{suffix}").stat().st_size > 1000, name
    pd.testing.assert_frame_equal(pd.read_csv(out / "fig4_ad.csv"), signals)
    (out / "tables" / "mine.txt").write_text("mine")
    assert main(["figures", "--tables", str(out / "tables"), "--out", str(out)]) == 2
    assert "holds tables/mine.txt, which this command does not write" in capsys.readouterr().err
    # an empty table (no rows) draws no figure, with a note (the summary's drew empty axes); all
    # tables empty is refused before any output (it wrote "0 files", exit 0)
    import shutil

    emptied = tmp_path / "emptied"
    shutil.copytree(out / "tables", emptied)
    (emptied / "mine.txt").unlink()
    # (the signals, the trajectory and the Intel panels emptied too: six figures fewer to draw, 5 s of the test's 25)
    for name in ("summary", "office_corners", "signals", "trajectory", "intel_points"):  # a scan without corners still has its Fig. 9 (review)
        if (emptied / f"{name}.parquet").exists():  # intel_points only where the Intel log is
            pd.read_parquet(emptied / f"{name}.parquet").iloc[:0].to_parquet(emptied / f"{name}.parquet")
    capsys.readouterr()
    assert main(["figures", "--tables", str(emptied), "--out", str(tmp_path / "e1")]) == 0
    assert not (tmp_path / "e1" / "accuracy_speed.png").exists() and (tmp_path / "e1" / "fig7_timing.png").exists()
    assert (tmp_path / "e1" / "fig9_office.png").exists()
    assert not any((tmp_path / "e1" / f"{name}.png").exists() for name in ("fig3_scan", "fig4_ad", "fig10_slam", "fig9_intel"))
    printed = capsys.readouterr().out
    for name in ("summary", "signals", "trajectory"):
        assert f"note: table {name} is empty: the figures drawn from it are not drawn" in printed
    assert "note: table office_corners" not in printed
    for table in emptied.glob("*.parquet"):
        pd.read_parquet(table).iloc[:0].to_parquet(table)
    assert main(["figures", "--tables", str(emptied), "--out", str(tmp_path / "e2")]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench figures: error: --tables {emptied}: every table a figure is drawn from is empty (no rows); "
        "nothing to draw"]
    assert not (tmp_path / "e2").exists()


@pytest.mark.slow
def test_the_demo_writes_a_report_whose_figures_exist(tmp_path):
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--duration", "4", "--rate-hz", "5", "--inprocess"]) == 0
    report = (out / "report.md").read_text()
    for heading in ("## Extractors: accuracy and speed", "## SLAM without odometry (Fig. 10)",
                    "## A sweep (in process)", "## At a glance"):
        assert heading in report
    images = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", report)
    assert len(images) >= 9 and all((out / p).exists() for p in images)
    for method in ("sensor", "split_merge", "iepf", "hough", "ransac"):
        assert re.search(rf"^\| {method} \|", report, re.M), method
    html = (out / "report.html").read_text()
    assert html.count("<img ") == len(images) and "<table>" in html
    # self-contained: every figure embedded, nothing linked
    assert html.count("<img src='data:image/png;base64,") == len(images) and "src='figures/" not in html
    sweep = pd.read_parquet(out / "sweeps" / "demo_k_vs_noise" / "results.parquet")
    assert len(sweep) == 9 and (sweep["status"] == "ok").all()
    # the demo's own outputs are every file it leaves: a second demo into the folder may replace them
    from experiments.options import DEMO_OUTPUTS

    assert DEMO_OUTPUTS.foreign(out) == []


@pytest.mark.slow
def test_fig9_of_another_log_is_named_by_that_log(tmp_path, capsys, monkeypatch):
    """`demo --log aces-corrected.log.gz` (docs/experiments.md) drew ACES's scans under "Intel log:
    4 scans with features", panels "Intel scan I", the title "Intel Research Lab (real log)" and the
    demo's caption "Intel Research Lab log (real data, 180 beams at 1°, ...)". The log is named by
    its file; the Intel log keeps its names."""
    from lms200 import write_log

    from experiments.figures import draw

    write_log(tmp_path / "lab.clf", sim.simulate_records("office", seed=2, duration=1.0, rate_hz=4.0))
    titles = {}
    scans = draw.fig_scans
    # Fig. 9 of the log drawn for real; the other figures only noted (drawing them was 10 of the test's 14 s)
    monkeypatch.setattr(draw, "fig_scans", lambda p, ln, c, path, title: titles.setdefault(path.name, title)
                        and (scans(p, ln, c, path, title) if path.name == "fig9_intel" else []))
    for name in ("fig_scan", "fig_signal", "fig_timing", "fig_slam", "fig_accuracy_speed"):
        monkeypatch.setattr(draw, name, lambda *args, **kwargs: [])
    out = tmp_path / "figs"
    assert main(["figures", "--out", str(out), "--duration", "1", "--rate-hz", "4", "--methods", "split_merge",
                 "--no-slam", "--intel", str(tmp_path / "lab.clf")]) == 0
    assert "] lab.clf log: 4 scans with features" in capsys.readouterr().out
    labels = pd.read_csv(out / "fig9_intel_points.csv")["label"]
    assert labels.str.startswith("lab.clf scan ").all()
    assert titles["fig9_intel"] == "Fig. 9: features extracted by split_merge, lab.clf (real log)"
    from experiments.demo import _real_log_caption

    tables = {"intel_points": pd.DataFrame({"label": labels})}
    assert _real_log_caption(tables).startswith("Fig. 9: the same on scans of the real log lab.clf (")
    intel = {"intel_points": pd.DataFrame({"label": ["Intel scan 88"]})}
    assert "Intel Research Lab log (real data, 180 beams at 1°" in _real_log_caption(intel)


def test_the_demo_without_out_also_leaves_results_demo_report_md(tmp_path, monkeypatch, capsys):
    """Issue #8 names `results/demo/report.md`; since issue #16 each run goes to its own
    results/demo/DATE_TIME folder (linked as latest) and no results/demo/report.md was left (an
    audit of the resolved issues). The newest run's report is now copied there, its links pointing
    into the run's folder, with the self-contained report.html beside it."""
    import experiments.demo

    def fake_run_demo(out, cfg, sweep_executor="local", log=print):
        (out / "figures").mkdir(parents=True)
        (out / "figures" / "a.png").write_bytes(b"png")
        (out / "report.md").write_text("# lmsbench demo\n\n![a](figures/a.png) [web](https://x.org/a.png)\n"
                                       "settings in `tables/study.yaml`, `lmsbench demo`\n")
        (out / "report.html").write_text("<html>embedded</html>")
        return out / "report.md"

    monkeypatch.setattr(experiments.demo, "run_demo", fake_run_demo)
    monkeypatch.chdir(tmp_path)
    assert main(["demo", "--no-sweep", "--duration", "2"]) == 0
    base = tmp_path / "results" / "demo"
    run = (base / "latest").resolve()
    copied = (base / "report.md").read_text()
    assert copied == (f"# lmsbench demo\n\n![a]({run.name}/figures/a.png) [web](https://x.org/a.png)\n"
                      f"settings in `{run.name}/tables/study.yaml`, `lmsbench demo`\n")
    assert all((base / p).is_file() for p in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", copied))
    assert (base / "report.html").read_text() == "<html>embedded</html>"
    assert f"copied the report to {Path('results/demo/report.md')}" in capsys.readouterr().out


@pytest.mark.parametrize("slam", [True, False])
def test_the_study_compiles_the_slam_kernels_before_it_times_the_slam(monkeypatch, slam):
    """The first `make demo` timed the default SLAM pipeline with its kernels' compile (5.9 s of
    CPU for 375 scans, reported as 7x slower than the paper preset; warm, 0.3 s and 3x faster):
    the study's warm-up compiled the extractors only. It now warms the SLAM's kernels too
    whenever the study runs the SLAM."""
    import experiments.progress
    from experiments.figures.study import StudyConfig, run_study

    class Warmed(Exception):
        pass

    seen = {}

    def warm_up(log=print, slam=False):
        seen["slam"] = slam
        raise Warmed

    monkeypatch.setattr(experiments.progress, "warm_up_kernels", warm_up)
    with pytest.raises(Warmed):
        run_study(StudyConfig(duration=2.0, slam=slam), log=lambda msg: None)
    assert seen == {"slam": slam}


def test_the_demo_report_names_the_command_that_ran_it():
    """The report's "Reproduce:" line said `lmsbench demo` whatever the world, seed, duration or
    log of the run (a new user's review: `demo --world pillars --duration 3 --no-sweep`). It now
    gives the options that differ from the defaults, the log's reading options included."""
    import math
    import shlex

    from experiments.demo import demo_command
    from experiments.figures.study import StudyConfig

    assert demo_command(StudyConfig()) == "lmsbench demo"
    assert demo_command(StudyConfig(world="pillars", duration=3.0), executor="") == \
        "lmsbench demo --world pillars --duration 3 --no-sweep"
    cfg = StudyConfig(seed=7, rate_hz=2.5, intel_log="logs/my run.clf",
                      log_options={"topic": None, "skip_bad_lines": True,
                                   "geometry": {"resolution": math.radians(0.5), "range_max": 30.0}})
    line = demo_command(cfg, executor="inprocess")
    assert line == ("lmsbench demo --seed 7 --rate-hz 2.5 --log 'logs/my run.clf' --skip-bad-lines "
                    "--laser-resolution-deg 0.5 --laser-range-max 30 --inprocess")
    # every number exactly (it gave --duration 12.3457 for 12.3456789: a review)
    exact = StudyConfig(duration=12.3456789, rate_hz=0.1234567,
                        log_options={"geometry": {"resolution": math.radians(0.3)}})
    assert demo_command(exact) == ("lmsbench demo --duration 12.3456789 --rate-hz 0.1234567 "
                                   f"--laser-resolution-deg {math.degrees(math.radians(0.3))!r}")
    from experiments.cli import build_parser

    args = build_parser().parse_args(shlex.split(line)[1:])  # the line parses back to the same options
    assert (args.world, args.seed, args.rate_hz, str(args.log), args.skip_bad_lines, args.laser_resolution_deg,
            args.laser_range_max, args.inprocess) == ("office", 7, 2.5, "logs/my run.clf", True, 0.5, 30.0, True)


def test_the_demos_sim2real_warnings_give_advice_the_demo_takes(tmp_path, monkeypatch):
    """The demo's report said 'only 20 real scans ... (more with a higher --max-scans or a lower
    --stride; more --seeds, ...)': options of `lmsbench sim2real` that `lmsbench demo` refuses, and
    the terminal heard none of it (a new user's review). The demo now passes its own advice and
    says each warning on the terminal too."""
    import experiments.sim2real
    from experiments.sim2real import small_sample_warnings

    assert small_sample_warnings(5, 720, 12, advice="a longer demo --duration")[0].endswith(
        "(more with a longer demo --duration)")

    class Stop(Exception):
        pass

    seen = {}

    def fake(log, **kwargs):
        seen.update(kwargs)
        raise Stop

    monkeypatch.setattr(experiments.sim2real, "sim2real", fake)
    with pytest.raises(Stop):
        _demo_sim2real_until(tmp_path, 2.0)
    # the log as a path from where the demo runs (its bare name did not run from the checkout)
    assert seen["advice"] == (f"a longer demo --duration, or `lmsbench sim2real {os.path.relpath(tmp_path / 'mit.clf')}` "
                              "for the full comparison")


def test_the_demos_sim2real_config_records_the_settings_it_ran_with(tmp_path, monkeypatch):
    """The demo's sim2real/config.yaml held log, duration, stride and max_scans alone (and no
    versions): read as `lmsbench sim2real`'s record, the run was at its defaults, 0.25 scans/s with
    120 s probe runs and the wall relief fitted, where the demo ran 3 scans/s, probes as long as the
    tour and no relief. Every setting the demo passes to sim2real is now in the record."""
    import experiments.sim2real

    class Stop(Exception):
        pass

    ran, recorded = {}, {}

    def fake(log, **kwargs):
        ran.update(kwargs)
        return type("Result", (), {"warnings": []})()

    def fake_write(result, out, log, config):
        recorded.update(config)
        raise Stop

    monkeypatch.setattr(experiments.sim2real, "sim2real", fake)
    monkeypatch.setattr(experiments.sim2real, "write_outputs", fake_write)
    with pytest.raises(Stop):
        _demo_sim2real_until(tmp_path, 7.0)
    assert (recorded["rate_hz"], recorded["probe_duration"], recorded["wall_relief"]) == (3.0, 7.0, False)  # old: KeyError
    settings = {k: v for k, v in ran.items() if k not in ("world", "seeds", "probe_seeds", "advice")}
    assert {k: recorded[k] for k in settings} == settings and "versions" in recorded


def _demo_sim2real_until(folder: Path, duration: float) -> None:
    """The demo's sim2real section on an empty mit.clf in ``folder`` (the test's fakes stop it)."""
    from experiments.demo import _sim2real_section
    from experiments.figures.study import StudyConfig

    cfg = StudyConfig(duration=duration)
    cfg.sim2real_log = str(folder / "mit.clf")
    (folder / "mit.clf").write_text("")
    _sim2real_section(cfg, folder, lambda msg: None)


def _tiny_log(tmp_path: Path) -> Path:
    from lms200 import write_log

    path = tmp_path / "tiny.clf"
    write_log(path, sim.simulate_records("office", seed=0, duration=0.5, rate_hz=5))
    return path


@pytest.mark.parametrize("kw, message", [
    (dict(stride=1.5), r"^stride: must be an integer >= 1 \(every stride-th scan\), got 1\.5$"),  # every 3rd scan (k % 1.5)
    (dict(stride=True), r"^stride: must be an integer >= 1 .*, got True$"),  # every scan
    (dict(stride="2"), r"^stride: must be an integer >= 1 .*, got '2'$"),  # '<' TypeError
    (dict(stride=0), r"^stride: must be an integer >= 1"),
    (dict(max_scans=0), r"^max_scans: must be an integer >= 1 \(or None: every scan\), got 0$"),  # no scan, silently
    (dict(max_scans=-1), r"^max_scans: must be an integer >= 1"),  # the same
    # int64's bound named (round 7: `compare --max-scans 1e29`'s digits were "must be an integer >= 1, got 1000...")
    (dict(max_scans=10**29), r"^max_scans: must be an integer in 1\.\.2\^63 - 1 \(or None: every scan\), got 10{29}$"),
    (dict(stride=1e300), r"^stride: must be an integer in 1\.\.2\^63 - 1 .*, got 1e\+300$"),
])
def test_log_source_refuses_counts_that_are_not_whole_numbers_from_1(tmp_path: Path, kw: dict, message: str) -> None:
    from experiments.compare import log_source
    from lms200.errors import InputError

    with pytest.raises(InputError, match=message):
        log_source(_tiny_log(tmp_path), **kw)


def test_log_source_still_takes_its_counts(tmp_path: Path) -> None:
    from experiments.compare import log_source

    path = _tiny_log(tmp_path)
    stamps = [r.scan.stamp for r in log_source(path).records]
    assert len(stamps) == 3
    assert [r.scan.stamp for r in log_source(path, stride=np.int64(2)).records] == stamps[::2]
    assert [r.scan.stamp for r in log_source(path, stride=2.0).records] == stamps[::2]  # a whole float, as before
    assert len(list(log_source(path, max_scans=2.0).records)) == 2
    assert len(list(log_source(path, max_scans=2).records)) == 2


@pytest.mark.parametrize("args, kw, message", [
    (lambda s: ([s], "sensor"), {}, r"^methods: must be a list of method names, got the text 'sensor' \(give \['sensor'\]\)$"),
    (lambda s: ([s], []), {}, r"^methods: no method given \(None runs every available one\)$"),  # ran all five
    (lambda s: ([s], ["sensor", "sensor"]), {}, r"^methods: 'sensor' is given twice$"),  # every scan counted twice
    (lambda s: ([s], ["sensor"]), dict(params=5), r"^params: must be a mapping of method name to its fields"),  # AttributeError
    (lambda s: ([s], ["sensor"]), dict(params={"sensor": 3}), r"^params: must be a mapping"),  # a TypeError
    (lambda s: ([], ["sensor"]), {}, r"^sources: no source given$"),  # an empty table, silently
    (lambda s: ([s], ["sensor"]), dict(max_scans=0), r"^max_scans: must be an integer >= 1"),  # the same
])
def test_compare_names_a_bad_argument_before_any_work(args, kw: dict, message: str) -> None:
    from experiments.compare import compare, sim_source
    from lms200.errors import InputError

    with pytest.raises(InputError, match=message):
        compare(*args(sim_source("office", duration=0.1, rate_hz=None)), **kw)


def test_compare_refuses_parameters_of_a_method_it_does_not_run_before_reading_a_source(tmp_path: Path) -> None:
    from experiments.compare import compare
    from lms200.errors import InputError

    # they were dropped without a word: the run went on the defaults of every method it ran
    with pytest.raises(InputError, match=r"^params: 'iepf' is not among the methods run \(sensor\); give parameters "
                                         r"only for a method in methods$"):
        compare([str(tmp_path / "absent.clf")], ["sensor"], params={"iepf": {"split_threshold": 0.05}})


def test_compare_still_takes_a_generator_of_sources() -> None:
    from experiments.compare import compare, sim_source

    table = compare((s for s in [sim_source("office", duration=0.1, rate_hz=None)]), ["split_merge"])
    assert set(table["method"]) == {"split_merge"} and len(table) == 4  # 0.1 s: four scans


def _study_tables(folder: Path, summary: pd.DataFrame | None) -> Path:
    """A tables folder of `lmsbench figures` holding only the timing table of two methods and ``summary``."""
    from experiments.figures.study import StudyConfig, save_tables

    folder.mkdir()
    timing = pd.DataFrame({"method": ["sensor"] * 3 + ["iepf"] * 3, "scan": [0, 1, 2] * 2,
                           "time_ms": [0.1, 0.2, 0.1, 0.05, 0.04, 0.05]})
    save_tables({"timing": timing, **({"summary": summary} if summary is not None else {})},
                StudyConfig(methods=("sensor", "iepf"), slam=False), [], folder)
    return folder


SUMMARY = pd.DataFrame({"method": ["sensor", "iepf"], "f1": [0.98, 0.99], "time_ms_median": [0.1, 0.05],
                        "time_ms_p25": [0.1, 0.04], "time_ms_p75": [0.2, 0.05]})


@pytest.mark.parametrize("case, note", [
    ("missing", "there is no table summary (summary.parquet), which it is drawn from"),
    ("no f1", "table summary has no column f1 (line F1 against ground truth), which it plots"),
    ("apart", "none of table summary's 2 rows holds a number (not nan) in both f1 and time_ms_median, which it plots"),
])
def test_figures_says_why_accuracy_speed_is_not_drawn(tmp_path, capsys, case, note) -> None:
    """A review: `figures --tables DIR` with no summary.parquet, or one without an f1 column, dropped
    accuracy_speed without a word; with its f1 (or time_ms_median) all nan it drew empty axes, exit 0.
    It is not drawn, and a note line says which figure and why, as for an empty table (exit 0: the
    other figures are drawn); a plotted column of no number at all is a damaged table, refused as every
    other table's (the next test)."""
    summary = {"missing": None, "no f1": SUMMARY.drop(columns=["f1"]),
               "apart": SUMMARY.assign(f1=[np.nan, 0.99], time_ms_median=[0.1, np.nan])}[case]
    tables = _study_tables(tmp_path / "tables", summary)
    assert main(["figures", "--tables", str(tables), "--out", str(tmp_path / "out")]) == 0
    printed = capsys.readouterr().out
    assert not (tmp_path / "out" / "accuracy_speed.png").exists() and (tmp_path / "out" / "fig7_timing.png").exists()
    assert f"note: accuracy_speed is not drawn: {note}\n" in printed, printed
    if case != "apart":
        return
    # one row with both numbers draws it, without a note
    ok = _study_tables(tmp_path / "ok", SUMMARY.assign(f1=[np.nan, 0.99]))
    assert main(["figures", "--tables", str(ok), "--out", str(tmp_path / "ok_out")]) == 0
    assert "accuracy_speed is not drawn" not in capsys.readouterr().out
    assert (tmp_path / "ok_out" / "accuracy_speed.png").exists()


@pytest.mark.parametrize("summary, column", [(SUMMARY.assign(f1=np.nan, time_ms_median=np.nan), "f1"),
                                             (SUMMARY.assign(time_ms_median=np.inf), "time_ms_median")])
def test_a_summary_of_no_number_in_a_plotted_column_is_refused(tmp_path, capsys, summary, column) -> None:
    """The summary's f1 or time_ms_median of no finite number (all nan: empty axes, exit 0; then a note)
    is a damaged table, refused before any output as every other table's plotted column is."""
    tables = _study_tables(tmp_path / "tables", summary)
    assert main(["figures", "--tables", str(tables), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"table summary's column {column} holds no finite number (2 rows, all nan or infinite)" in err, err
    assert not (tmp_path / "out").exists()


def test_figures_says_which_tables_the_study_saved_are_missing(tmp_path, capsys) -> None:
    """A review: `figures --tables DIR` with a table of the study deleted (signals.parquet, the Intel panels',
    the trajectory) left its figures out without a word, exit 0. Each such table is named in a note, with the
    figures not drawn; a table the study did not make (the trajectory of a study without SLAM, the Intel panels
    where its notes say the log was skipped) is not."""
    tables = _study_tables(tmp_path / "tables", SUMMARY)  # timing and summary only, slam=False, no notes
    assert main(["figures", "--tables", str(tables), "--out", str(tmp_path / "out")]) == 0
    notes = [line for line in capsys.readouterr().out.splitlines() if line.startswith("note: table")]
    assert notes == [
        "note: table signals is missing (signals.parquet, which the study saved): fig3_scan to fig6_psi are not drawn",
        "note: table office_points is missing (office_points.parquet, which the study saved): fig9_office is not drawn",
        "note: table intel_points is missing (intel_points.parquet, which the study saved): fig9_intel is not drawn"]
    (tables / "notes.txt").write_text("Fig. 9 (Intel log) skipped: None is not present on this machine.\n")
    assert main(["figures", "--tables", str(tables), "--out", str(tmp_path / "out2")]) == 0
    assert "intel_points is missing" not in capsys.readouterr().out
