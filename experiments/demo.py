"""The demo, end to end: simulate an office run, compare every extractor against ground truth,
run the SLAM, a small sweep on Dask, draw the figures and write ``report.md`` / ``report.html``.
"""

from __future__ import annotations

import os
import time
import warnings
from pathlib import Path
from typing import Callable

import pandas as pd

from experiments.figures.make import article, draw_figures, draw_sweep
from experiments.figures.study import STUDY_TABLE_NAMES, StudyConfig, run_study, save_tables
from experiments.figures.tables import panels_log_name
from experiments.options import DEMO_OUTPUTS, DEMO_OWNER, DEMO_SWEEP, FIGURE_PART_FILES, demo_sweep_files, recorded_names
from experiments.report import Section, figure, markdown_table, write_report
from lms200.errors import LmsbenchWarning
from lms200.finite import printable

def run_demo(out: Path, cfg: StudyConfig, sweep_executor: str | None = "local",
             log: Callable[[str], None] = print) -> Path:
    """Run everything and write ``out/report.md`` (returned) and ``out/report.html``; a line at
    least every 4 s while it works."""
    from experiments.progress import Heartbeat

    with Heartbeat(log, "demo") as beat:
        return _run_demo(out, cfg, sweep_executor, beat)


def _run_demo(out: Path, cfg: StudyConfig, sweep_executor: str | None, beat) -> Path:
    from experiments.sweep import SweepSpec, run_sweep

    log = beat.say
    t0 = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    log(f"== lmsbench demo -> {out}")
    tables, notes = run_study(cfg, log=log)
    # the earlier demo's files this one may not write again (its sweep's and sim2real's, with --no-sweep or no
    # log; its Fig. 9 / 10 tables; a figures run's figures.yaml): they stayed beside its report as if they were its
    DEMO_OWNER.remove_earlier(out, DEMO_OUTPUTS, keep=("tables/study.yaml",), also=(  # study.yaml: written first, next
        *(f"figures/{name}" for name in FIGURE_PART_FILES), *(f"tables/{name}.parquet" for name in STUDY_TABLE_NAMES),
        *demo_sweep_files(out),
        # a `figures --sweep S --out DEMO/figures` run's plots, as its figures.yaml (removed here) lists them
        *(f"figures/{name}" for name in recorded_names(out / "figures" / "figures.yaml", "sweep_plots"))))
    save_tables(tables, cfg, notes, out / "tables")
    sweep_table = None
    if sweep_executor:
        spec = SweepSpec.from_dict(DEMO_SWEEP)
        log(f"== sweep {spec.name}: {len(spec.cells())} cells on {sweep_executor}")
        folder = out / "sweeps" / spec.name  # the earlier demo's sweep removed above: it recomputes everything
        beat.label = f"sweep {spec.name}"
        result = run_sweep(spec, folder, sweep_executor, progress=False)
        sweep_table = result.table
        log(f"   {result.computed} computed, {result.skipped} already done, {result.failed} failed")
    beat.label = "sim2real"
    s2r = _sim2real_section(cfg, out, log)
    beat.label = "figures"
    log("== figures")
    figs = draw_figures(tables, out / "figures", signals_k=cfg.signals_k, world=cfg.world)
    if sweep_table is not None:
        figs.update(draw_sweep(out / "sweeps" / DEMO_SWEEP["name"], out / "figures"))
    log(f"   {sum(len(v) for v in figs.values())} files in {out / 'figures'}")
    elapsed = time.perf_counter() - t0
    sections = report_sections(tables, notes, cfg, figs, sweep_table, elapsed, sweep_executor or "")
    if s2r is not None:
        sections.insert(len(sections) - (1 if notes else 0), s2r)
    md, html = write_report(out, "lmsbench demo: fast feature extraction in sensor coordinates", sections)
    log(f"== wrote {md} and {html} ({elapsed:.0f} s)")
    return md


#: The real log of the demo's sim-to-real section (skipped with a note where absent).
MIT_LOG = Path(__file__).resolve().parents[2] / "shared" / "data" / "carmen" / "mit-csail.clf.gz"


def _sim2real_section(cfg: StudyConfig, out: Path, log: Callable[[str], None]) -> Section:
    """A calibrated simulation of the MIT-like preset next to the MIT CSAIL log (demo size:
    the study's duration and seed; at most duration x rate scans of the log, but at least 20),
    or a note."""
    from experiments.sim2real import PROBE_RATE_HZ, PROBE_SEEDS, format_report, sim2real, write_outputs

    path = Path(cfg.sim2real_log) if getattr(cfg, "sim2real_log", None) else MIT_LOG
    if not path.exists():
        return Section("Calibrated simulation next to a real log", [
            f"Skipped: {path} is not present on this machine (`lmsbench sim2real LOG` runs it on any log)."])
    log(f"== sim2real: {path.name} against the calibrated mit preset")
    max_scans = max(20, int(cfg.duration * cfg.rate_hz))
    # the rough fill's probe runs: the tour's duration on one world other than the report's, at
    # sim2real's PROBE_RATE_HZ (1 scan/s), as `lmsbench sim2real` runs them on twelve worlds
    # the settings the run is given are the ones its config.yaml records: it recorded the duration,
    # stride and max_scans alone, so the record read as sim2real's defaults (0.25 scans/s, 120 s probe
    # runs, the wall relief fitted) where the demo ran 3 scans/s, probes as long as the tour, no relief
    settings = dict(duration=cfg.duration, rate_hz=3.0, stride=10, max_scans=max_scans,
                    fit_duration=min(30.0, cfg.duration), wall_relief=False, probe_duration=cfg.duration,
                    probe_rate_hz=PROBE_RATE_HZ)
    full_run = f"lmsbench sim2real {os.path.relpath(path)}"  # the report said `lmsbench sim2real mit-csail.clf.gz`,
    # a bare name that does not run from the checkout, where the warnings' advice already gave the path
    with warnings.catch_warnings():  # its early warnings (too few real scans) labelled as its later ones below
        shown = warnings.showwarning  # (the command line's "lmsbench demo: warning: ..." named no step; a review)

        def said(message, category, filename, lineno, file=None, line=None):  # noqa: ANN001, ANN202
            if issubclass(category, LmsbenchWarning):
                log(f"warning: sim2real: {message}")
            else:
                shown(message, category, filename, lineno, file, line)

        warnings.showwarning = said
        result = sim2real(path, world="mit", seeds=(cfg.seed,), **settings,
                          probe_seeds=[next(s for s in PROBE_SEEDS if s != cfg.seed)],
                          # the log as a path from here: its bare name did not run from the checkout (a review)
                          advice=f"a longer demo --duration, or `{full_run}` for the full comparison")
    for warning in result.warnings:  # in the report and, as sim2real says them, on the terminal
        if warning not in result.warned_early:  # said before the work (too few real scans)
            log(f"warning: sim2real: {warning}")
    from experiments.provenance import versions

    write_outputs(result, out / "sim2real", str(path), dict(log=str(path), **settings, versions=versions()))
    body = format_report(result, path.name).split("\n", 2)[2]  # the tables, without the title
    return Section("Calibrated simulation next to a real log", [
        f"`lmsbench calibrate` fitted the sensor model to {path.name}; the `mit` preset (generator parameters "
        f"fixed from MIT CSAIL's range histogram, segment lengths and long-wall share) was then simulated with "
        f"that sensor and the log's robot speeds, and every extractor ran on both (real-data measures of "
        f"`features.realdata`). Demo size: {result.n_real} real and {result.n_sim} simulated scans (world "
        f"{cfg.seed}), the rough fill fitted on probe runs of {cfg.duration:g} s at {PROBE_RATE_HZ:g} scan/s on "
        f"world {', '.join(map(str, result.probe_seeds))}, no wall relief fitted; `{full_run}` "
        "runs the full comparison.", body,
        figure("sim2real/sim2real.png", "Real against calibrated simulation: readings by range, ray residuals "
                                        "around split-and-merge lines, lines per scan, segment lengths, "
                                        "explained fraction by method.")])


def method_table(summary: pd.DataFrame) -> pd.DataFrame:
    """The extractor comparison as shown in the report (units in the column names)."""
    cols = {"method": "method", "backend": "backend", "time_ms_median": "ms/scan (median)", "time_ms_p95": "ms/scan (95 %)",
            "scans_per_s": "scans/s", "speed_vs_sensor": "speed vs sensor", "lines_per_scan": "lines/scan",
            "precision": "line precision", "recall": "line recall", "f1": "line F1",
            "rho_rms_mm": "rho RMS (mm)", "alpha_rms_deg": "alpha RMS (deg)",
            "corner_precision": "corner precision", "corner_recall": "corner recall",
            "corner_err_mm": "corner error (mm)", "explained": "explained fraction"}
    return summary[[c for c in cols if c in summary]].rename(columns=cols)


def timing_note(summary: pd.DataFrame) -> str:
    """What the times in the extractor table measure, with each method's backend (the summary's
    ``backend`` column: "numba" = compiled kernels, "numpy" = vectorised numpy), and which speed
    comparisons are like for like."""
    if "backend" in summary:
        by_backend = summary.drop_duplicates("method").groupby("backend", sort=True)["method"].apply(list)
    else:
        by_backend = pd.Series({"numpy": list(summary["method"].unique())})
    names = {"numba": "numba-compiled kernels", "numpy": "vectorised numpy (no compiled kernels)"}
    runs = "; ".join(f"{', '.join(f'`{m}`' for m in methods)} on {names.get(b, b)}" for b, methods in by_backend.items())
    text = (f"Times are wall-clock per scan on this machine (one core), the extraction call alone, the methods "
            f"interleaved scan by scan (`experiments.compare`). Backends (the `backend` column): {runs}.")
    compiled = by_backend.get("numba", [])
    if len(compiled) > 1:
        text += (f" Speed ratios among {', '.join(f'`{m}`' for m in compiled)} compare compiled with compiled code; "
                 f"against the numpy methods they are not like for like.")
    elif len(by_backend) > 1:
        text += " Speed ratios between different backends are not like for like."
    return text


def at_a_glance(tables: dict[str, pd.DataFrame]) -> list[str]:
    """Bullet points with the headline numbers, read off the tables."""
    items = []
    if "summary" in tables and "f1" in tables["summary"]:
        sm = tables["summary"].set_index("method")
        fastest, best = sm["time_ms_median"].idxmin(), sm["f1"].idxmax()
        items.append(f"- Fastest extractor: **{fastest}**, {sm.loc[fastest, 'time_ms_median']:.2f} ms per scan "
                     f"(median); highest line F1: **{best}**, {sm.loc[best, 'f1']:.3f}.")
        if "sensor" in sm.index:
            s = sm.loc["sensor"]
            items.append(f"- The paper's extractor (`sensor`): {s['time_ms_median']:.2f} ms per scan, line F1 "
                         f"{s['f1']:.3f} (precision {s['precision']:.3f}, recall {s['recall']:.3f}), rho RMS "
                         f"{s['rho_rms_mm']:.1f} mm, corner precision {s['corner_precision']:.3f}.")
        lowest = sm["rho_rms_mm"].idxmin()
        items.append(f"- Most precise lines: **{lowest}**, rho RMS {sm.loc[lowest, 'rho_rms_mm']:.1f} mm.")
    if "slam_metrics" in tables:
        for m in tables["slam_metrics"].to_dict("records"):
            items.append(f"- SLAM without odometry ({m.get('preset', 'default')}): ATE {m['ate_rms_m']:.3f} m RMS over "
                         f"{int(m['scans'])} scans, {int(m['map_lines'])} map lines, {m['time_per_scan_ms']:.1f} ms "
                         f"per scan{' (diverged)' if m['diverged'] else ''}.")
    return ["\n".join(items)] if items else []


def demo_command(cfg: StudyConfig, executor: str = "local") -> str:
    """The ``lmsbench demo`` command line that runs this study again (the options that differ from
    the defaults; ``executor`` "" for ``--no-sweep``). The report said `lmsbench demo` whatever
    the world, seed or log it ran. A word that is not UTF-8 (a log's name with an undecodable byte)
    is written in the shell's ANSI-C quotes, ``$'b\\xff.clf'``, which name that file again."""
    import shlex

    def shell_word(word: str) -> str:
        if printable(word) == word:
            return shlex.quote(word)
        raw = os.fsencode(word)  # the name's bytes, as the file system holds them
        return "$'" + "".join(chr(b) if 32 <= b < 127 and b not in b"'\\" else f"\\x{b:02x}" for b in raw) + "'"

    from experiments.figures.study import INTEL_LOG
    from experiments.logargs import log_option_flags
    from experiments.options import number_text

    default = StudyConfig()
    words = ["lmsbench", "demo"]
    for flag, name in (("--world", "world"), ("--seed", "seed"), ("--duration", "duration"), ("--rate-hz", "rate_hz")):
        value = getattr(cfg, name)
        if value != getattr(default, name):
            words += [flag, number_text(value) if isinstance(value, float) else str(value)]
    if cfg.intel_log is not None and Path(cfg.intel_log) != INTEL_LOG:
        words += ["--log", str(cfg.intel_log)]
    words += log_option_flags(cfg.log_options)
    words += ["--no-sweep"] if not executor else (["--inprocess"] if executor == "inprocess" else [])
    return " ".join(shell_word(word) for word in words)


def report_sections(tables: dict[str, pd.DataFrame], notes: list[str], cfg: StudyConfig, figs: dict,
                    sweep_table: pd.DataFrame | None, elapsed: float, executor: str = "local") -> list[Section]:
    timing = tables["timing"]
    n_scans = int(timing["scan"].nunique())
    intro = Section("What was run", [
        f"A simulated LMS200 (361 beams at 0.5°, the `{cfg.world}` world, seed {cfg.seed}) drove a "
        f"{cfg.duration:g} s tour; {n_scans} scans were kept ({cfg.rate_hz:g} scans/s of the sensor's 37.5). "
        f"Every extractor ran on every scan and was scored against the exact visible ground truth of the "
        f"simulator; the odometry-free SLAM (the paper preset's EKF and the default scan-matching pipeline) ran on the same scans. Whole demo: {elapsed:.0f} s.",
        f"Reproduce: `{demo_command(cfg, executor)}` (settings in `tables/study.yaml`; every table behind the "
        "figures is in `tables/*.parquet` and beside each figure as CSV).",
    ])
    sections = [intro]
    glance = at_a_glance(tables)
    if glance:
        sections.append(Section("At a glance", glance))
    if "summary" in tables:
        ext = Section("Extractors: accuracy and speed", [
            markdown_table(method_table(tables["summary"])),
            timing_note(tables["summary"]) + " Precision / recall / F1 pool the line matches of all scans against "
            "the faces visible from the true pose; `explained fraction` is the share of valid beams within 3 sigma "
            "of an extracted segment.",
        ])
        for name, caption in (("accuracy_speed", "Accuracy (line F1, rho RMS error) against time per scan, every extractor."),
                              ("fig7_timing", "Fig. 7: processing time for successive scans, every method.")):
            if name in figs:
                ext.text.append(figure(f"figures/{name}.png", caption))
        sections.append(ext)
    sig = Section("The paper's signals (Figs. 3-6)", [])
    for name, caption in (("fig3_scan", f"Fig. 3: the {cfg.world} scan of Figs. 4-6, in the sensor frame and in "
                                        f"sensor coordinates (range over beam index)."),
                          ("fig4_ad", f"Fig. 4: AD_i{cfg.signals_k} of {article(cfg.world)} {cfg.world} scan; the dashed line is "
                                      f"its value on any straight line, 1 + 2 Σ cos(jΔ)."),
                          ("fig5_theta", "Fig. 5: θ_i, the line normal angle estimated at each beam."),
                          ("fig6_psi", f"Fig. 6: ψ_i = θ_i − θ_(i+{cfg.signals_k}), large at corners.")):
        if name in figs:
            sig.text.append(figure(f"figures/{name}.png", caption))
    sections.append(sig)
    f9 = Section("Extracted features (Fig. 9)", [])
    for name, caption in (("fig9_office", "Fig. 9: lines (red, a star at the midpoint) and corners (diamonds), "
                                          f"simulated {cfg.world}, sensor frame."),
                          ("fig9_intel", _real_log_caption(tables))):
        if name in figs:
            f9.text.append(figure(f"figures/{name}.png", caption))
    sections.append(f9)
    if "slam_metrics" in tables:
        m = tables["slam_metrics"].rename(columns={
            "ate_rms_m": "ATE RMS (m)", "ate_max_m": "ATE max (m)", "heading_rms_deg": "heading RMS (deg)",
            "final_error_m": "final error (m)", "map_lines": "map lines", "cpu_time_s": "CPU time (s)",
            "time_per_scan_ms": "ms/scan"})
        sl = Section("SLAM without odometry (Fig. 10)", [markdown_table(m)])
        if "fig10_slam" in figs:
            sl.text.append(figure("figures/fig10_slam.png", "Fig. 10: SLAM trajectory and line map against the true "
                                                            "trajectory and walls (world frame, equal axes): the "
                                                            "paper preset (left) beside the default pipeline (right)."))
        sections.append(sl)
    if sweep_table is not None and not sweep_table.empty:
        ok = sweep_table[sweep_table["status"] == "ok"]
        where = "on a local Dask cluster" if executor == "local" else "in process"
        sw = Section(f"A sweep ({where}): window size k against range noise", [])
        if "f1" in ok:
            pivot = ok.pivot_table(index="extractor.k", columns="sensor.noise_sigma", values="f1", aggfunc="mean")
            pivot.columns = [f"F1 at σ = {c:g} m" for c in pivot.columns]
            sw.text.append(markdown_table(pivot.reset_index().rename(columns={"extractor.k": "k"})))
        sw.text.append(sweep_note(len(sweep_table), int((sweep_table["status"] != "ok").sum())))
        for name in sorted(n for n in figs if n.startswith("sweep_")):
            metric = name[len(f"sweep_{DEMO_SWEEP['name']}_"):]
            sw.text.append(figure(f"figures/{name}.png", f"Sweep: {metric} against the range noise (m), one line "
                                                         f"per window size k."))
        sections.append(sw)
    if notes:
        sections.append(Section("Notes", [f"- {n}" for n in notes]))
    return sections


def sweep_note(cells: int, failed: int) -> str:
    """The sweep section's last line: its table, in the run's folder, and where the larger sweeps are:
    the checkout's ``sweeps/*.yaml``, not the run's ``sweeps/`` (which holds the demo's sweep alone; the
    copy in results/demo pointed ``sweeps/*.yaml`` into the run folder, where no such file is)."""
    return (f"{cells} cells, {failed} failed; table in `sweeps/{DEMO_SWEEP['name']}/results.parquet`. "
            "Larger sweeps: the sweep files of the checkout's `sweeps` folder (`lmsbench sweep "
            "sweeps/k_vs_noise.yaml` from the checkout; docs/experiments.md).")


def _real_log_caption(tables: dict[str, pd.DataFrame]) -> str:
    """Fig. 9's caption for the real log's panels: the Intel log's (the default), else the log's
    name (`demo --log` takes any log: it was captioned Intel, 180 beams at 1 deg, whatever it was)."""
    name = panels_log_name(tables["intel_points"]) if "intel_points" in tables else "Intel"
    if name == "Intel":
        return ("Fig. 9: the same on scans of the Intel Research Lab log (real data, 180 beams at 1°, cm-mode "
                "ranges: the extractor's defaults, its range noise estimated from each scan).")
    return (f"Fig. 9: the same on scans of the real log {name} (the extractor's defaults, its range noise "
            "estimated from each scan).")
