"""Draw every figure from the study's tables (and sweep tables): the named figures of the paper.

Figure names (files ``NAME.png``, ``NAME.pdf`` and the data ``NAME*.csv`` in the output folder):

- ``fig3_scan``: the scan of Figs. 4-6 (Cartesian and in sensor coordinates);
- ``fig4_ad``, ``fig5_theta``, ``fig6_psi``: AD_i10, theta_i, psi_i of a 361-beam scan of the study's world (the office by default);
- ``fig7_timing``: processing time per scan over the run, every method;
- ``fig9_office``, ``fig9_intel``: scans with extracted lines (*) and corners (diamonds), ``fig9_office`` of the study's world whatever its name;
- ``fig10_slam``: SLAM trajectory and map against ground truth;
- ``accuracy_speed``: line F1 against time per scan, every extractor;
- ``sweep_NAME_METRIC``: one per sweep folder and metric.
"""

from __future__ import annotations

from lms200.records import MAX_COORD_M
from lms200.yamlio import load as load_yaml

from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from . import draw
from .tables import ad_reference, panels_log_name

#: Metrics plotted for a sweep when its table has them.
SWEEP_METRICS = ("f1", "corner_f1", "rho_rms_mm", "time_ms_median", "ate_rms", "final_error_m")

PAPER_FIGURES = ("fig3_scan", "fig4_ad", "fig5_theta", "fig6_psi", "fig7_timing", "fig9_office", "fig9_intel",
                 "fig10_slam", "accuracy_speed")


def article(word: str) -> str:
    """'an' before a vowel sound, else 'a' (captions name the world: an office, a corridor)."""
    return "an" if word[:1].lower() in "aeiou" else "a"


#: the tables each figure is drawn from (signals, timing, summary, the trajectory, each panel's
#: points): an empty one draws no figure; the ones beside them (lines, corners, map) may be empty
DRIVING_TABLES = ("signals", "timing", "summary", "trajectory", "office_points", "intel_points")


#: what the figures read of each table: the columns they group or label by, and the ones they plot or
#: compute with, which must hold numbers (``check_tables``); summary's only when it has an ``f1``
#: (accuracy_speed is drawn only then), and its ``rho_rms_mm`` where it has one
_POSITIONS = {"points": ("x", "y"), "lines": ("x1", "y1", "x2", "y2"), "corners": ("x", "y")}
TABLE_COLUMNS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "signals": ((), ("beam", "bearing_deg", "range_m", "ad", "theta_deg", "psi_deg")),
    "timing": (("method",), ("scan", "time_ms")),
    **{f"{panel}_{kind}": (("panel",), numbers) for panel in ("office", "intel") for kind, numbers in _POSITIONS.items()},
    "trajectory": (("source",), ("x", "y")),
    "map": (("source",), ("x1", "y1", "x2", "y2")),
    "summary": (("method",), ("f1", "time_ms_median", "time_ms_p25", "time_ms_p75")),
}
#: columns a figure draws only where its table has them, which must then hold numbers too (all nan draws
#: nothing of them): signals' ad_band of text was "internal error: TypeError: operation 'rsub' not supported"
OPTIONAL_NUMBERS: dict[str, tuple[str, ...]] = {"signals": ("ad_band",), "summary": ("rho_rms_mm",)}
#: the key columns that name an extractor or a source, text in every row (a panel is a scan's number)
TEXT_KEYS = ("method", "source")


def accuracy_speed_problem(tables: dict[str, pd.DataFrame]) -> str | None:
    """Why ``accuracy_speed`` cannot be drawn from ``tables`` (the note ``figures`` prints), or None when
    it can or when its table ``summary`` is there without rows (noted as an empty table). From a
    ``--tables`` folder without summary.parquet, or whose summary had no ``f1``, it was dropped without
    a word; one whose f1 or time_ms_median were all nan drew empty axes, exit 0."""
    summary = tables.get("summary")
    if summary is None:
        return "accuracy_speed is not drawn: there is no table summary (summary.parquet), which it is drawn from"
    if not len(summary):
        return None
    if "f1" not in summary:
        return ("accuracy_speed is not drawn: table summary has no column f1 (line F1 against ground truth), "
                "which it plots")
    if "time_ms_median" in summary and not (_finite(summary["f1"]) & _finite(summary["time_ms_median"])).any():
        return (f"accuracy_speed is not drawn: none of table summary's {len(summary)} rows holds a number (not nan) "
                "in both f1 and time_ms_median, which it plots")
    return None


def _finite(column: pd.Series) -> pd.Series:
    """Which values of ``column`` are finite numbers (text, nan and inf are not)."""
    numbers = pd.to_numeric(column, errors="coerce").astype(float)
    return numbers.notna() & (numbers.abs() != float("inf"))


def check_tables(tables: dict[str, pd.DataFrame], where: str) -> None:
    """LmsbenchError naming ``where`` (the tables' folder), the table and the column, for a table
    that lacks a column the figures read or holds text (or dates, ...) where they plot numbers.
    Checked before any output: a table of the same name written by other code, or edited, failed
    part-way through the drawing ("internal error: TypeError: Cannot perform reduction 'median'
    with string dtype", exit 1, figures.yaml and the figures before it written) or, for points,
    trajectories and maps held as text, drew them on categorical axes, exit 0 (found by the
    wrong-input hunt)."""
    from lms200 import LmsbenchError

    for driving, beside in (("office_points", ("office_lines", "office_corners")),
                            ("intel_points", ("intel_lines", "intel_corners")), ("trajectory", ("map",))):
        absent = [b for b in beside if driving in tables and len(tables[driving]) and b not in tables]
        if absent:  # Fig. 9 failed after the figures before it ("KeyError: 'office_corners'"); Fig. 10 was left out
            raise LmsbenchError(f"{where}: table {driving} has no {absent[0]} beside it ({absent[0]}.parquet), which its "
                                "figure draws with it: a tables folder of `lmsbench figures` or `lmsbench demo` holds both")
    for name, (keys, numbers) in TABLE_COLUMNS.items():
        table = _drawn_from(tables, name)
        if table is None:
            continue
        missing = [c for c in keys + numbers if c not in table]
        numbers = numbers + tuple(c for c in OPTIONAL_NUMBERS.get(name, ()) if c in table)
        if missing:
            raise LmsbenchError(f"{where}: table {name} has no column{'s' if len(missing) > 1 else ''} {', '.join(missing)}, "
                                "which the figures read: "
                                "not a table of `lmsbench figures` or `lmsbench demo` (edited, or another program's?)")
        text = [c for c in numbers if not (pd.api.types.is_numeric_dtype(table[c]) and not pd.api.types.is_bool_dtype(table[c]))]
        if text:
            raise LmsbenchError(f"{where}: table {name}'s column {text[0]} holds {table[text[0]].dtype} values, where "
                                "the figures plot numbers: not a table of `lmsbench figures` or `lmsbench demo` "
                                "(edited, or another program's?)")
        empty_key = [c for c in keys if table[c].isna().any()]
        if empty_key:  # a null panel was "internal error: IndexError", a null method drawn without a label
            raise LmsbenchError(f"{where}: table {name}'s column {empty_key[0]} has empty (null or nan) values in "
                                f"{int(table[empty_key[0]].isna().sum())} of its {len(table)} rows, where every row "
                                "names its " + {"method": "extractor", "panel": "scan", "source": "source"}[empty_key[0]]
                                + ": a damaged table, or not one of `lmsbench figures` or `lmsbench demo`")
        named = [c for c in keys if c in TEXT_KEYS and not table[c].map(lambda v: isinstance(v, str)).all()]
        if named:  # timing's method of numbers was "internal error: TypeError: 'int' object is not iterable"
            odd = next(v for v in table[named[0]] if not isinstance(v, str))
            raise LmsbenchError(f"{where}: table {name}'s column {named[0]} holds {type(odd).__name__} values ({odd!r}), "
                                "where every row names its " + {"method": "extractor", "source": "source"}[named[0]]
                                + " as text: a damaged table, or not one of `lmsbench figures` or `lmsbench demo`")
        plotted = (("f1", "time_ms_median") if name == "summary"  # summary's others may be nan
                   else tuple(c for c in numbers if c not in OPTIONAL_NUMBERS.get(name, ())))
        blank = [c for c in plotted if not _finite(table[c]).any()]
        if blank:  # every figure of it drawn empty, exit 0 (a damaged-input fuzz round: all nan, all inf)
            raise LmsbenchError(f"{where}: table {name}'s column {blank[0]} holds no finite number ({len(table)} rows, "
                                "all nan or infinite), so its figure would be empty: a damaged table, or not one of "
                                "`lmsbench figures` or `lmsbench demo`")
    _check_ranges(tables, where)
    _check_shapes(tables, where)


#: times per scan (ms) the figures draw on log axes (Fig. 7, accuracy_speed): from 1 ns, the step of the
#: clock compare times with (``perf_counter_ns``), to a day; zero or less has no place on a log axis
MIN_TIME_MS = 1e-6
MAX_TIME_MS = 86_400_000.0
#: the bound of a position's x and y (m) the figures draw (Figs. 9, 10), every log's and trajectory's of lmsbench
MAX_POSITION_M = MAX_COORD_M
_TIME = (MIN_TIME_MS, MAX_TIME_MS, "time per scan (1 ns to a day, 1e-06 to 8.64e+07 ms)")
_POSITION = (-MAX_POSITION_M, MAX_POSITION_M, f"position (x and y within +-{MAX_POSITION_M:g} m, as every log and "
                                             "trajectory lmsbench reads or writes)")
#: each table's columns whose finite values must lie in bounds (nan is a row without that number): low, high,
#: and what a value is, said when one lies outside
PLOTTED_RANGES: dict[str, dict[str, tuple[float, float, str]]] = {
    "timing": {"time_ms": _TIME},
    "summary": {**{c: _TIME for c in ("time_ms_median", "time_ms_p25", "time_ms_p75")},
                "f1": (0.0, 1.0, "line F1 score (0 to 1)")},
    **{name: {c: _POSITION for c in numbers} for name, (_, numbers) in TABLE_COLUMNS.items()
       if name in ("trajectory", "map") or name.endswith(("_points", "_lines", "_corners"))},
}


def _drawn_from(tables: dict[str, pd.DataFrame], name: str) -> pd.DataFrame | None:
    """The table ``name`` where a figure is drawn from it, else None: absent, empty, or a summary
    without f1 (no accuracy-speed figure then), whose columns the checks then leave alone."""
    table = tables.get(name)
    if table is None or not len(table) or (name == "summary" and "f1" not in table):
        return None
    return table


def _check_ranges(tables: dict[str, pd.DataFrame], where: str) -> None:
    """LmsbenchError naming the table, column and row of a value the figures cannot draw as what it is:
    a time per scan (Fig. 7's and accuracy_speed's log axes) of zero or less, infinite, below 1 ns or beyond
    a day, an F1 outside [0, 1] (its axis is 0 to 1.02), a position beyond +-MAX_POSITION_M, and a summary
    row whose 25 % time exceeds its median or its median its 75 % (the error bars' lengths). Before, -9e99 or
    0 ms was drawn under matplotlib's warnings (or none: a line off the log axis), a point or trajectory at
    9e99 m as a figure of one dot, exit 0, and a 25 % time above the median was "internal error: ValueError:
    'xerr' must not contain negative values" after figures.yaml (the wrong-input hunt, round 7)."""
    from lms200 import LmsbenchError

    for name, columns in PLOTTED_RANGES.items():
        table = _drawn_from(tables, name)
        if table is None:
            continue
        for column, (low, high, what) in columns.items():
            values = table[column].to_numpy(dtype=float, na_value=np.nan)
            bad = ~np.isnan(values) & ~((values >= low) & (values <= high))
            if bad.any():
                row = int(np.argmax(bad))
                raise LmsbenchError(f"{where}: table {name}'s column {column} holds {values[row]:g} (row {row}), which is no "
                                    f"{what}: a damaged table, or not one of `lmsbench figures` or `lmsbench demo`")
        if name == "summary":
            p25, median, p75 = (table[c].to_numpy(dtype=float, na_value=np.nan)
                                for c in ("time_ms_p25", "time_ms_median", "time_ms_p75"))
            unordered = (p25 > median) | (median > p75)  # False where any is nan
            if unordered.any():
                row = int(np.argmax(unordered))
                raise LmsbenchError(f"{where}: table summary's row {row} holds the times time_ms_p25 {p25[row]:g}, "
                                    f"time_ms_median {median[row]:g}, time_ms_p75 {p75[row]:g} ms, not in that order "
                                    "(quantiles of one method's times): a damaged table, or not one of `lmsbench "
                                    "figures` or `lmsbench demo`")


def _check_shapes(tables: dict[str, pd.DataFrame], where: str) -> None:
    """What the figures draw that no study saves and that they cannot draw: a signals table of more
    rows than a scan has beams (a million rows drew for over two minutes), more Fig. 9 panels than
    MAX_PANELS (1,441 panels: C++ std::bad_alloc, exit 134), a trajectory without the truth or an
    estimate ("internal error: ValueError: Number of columns must be a positive integer, not 0")
    and a map without the true walls (drawn without them, exit 0)."""
    from lms200 import LmsbenchError

    from features.baselines.checks import MAX_BEAMS

    def refuse(text: str) -> None:
        raise LmsbenchError(f"{where}: {text}: a damaged table, or not one of `lmsbench figures` or `lmsbench demo`")

    signals = tables.get("signals")
    if signals is not None and len(signals) > MAX_BEAMS:
        refuse(f"table signals holds {len(signals)} rows, more than a scan's beams (at most {MAX_BEAMS}; it is one scan)")
    for name in ("office_points", "intel_points"):
        points = tables.get(name)
        if points is not None and len(points) and points["panel"].nunique() > MAX_PANELS:
            refuse(f"table {name} holds {points['panel'].nunique()} panels (scans), more than Fig. 9 draws (at most "
                   f"{MAX_PANELS}; a study draws 4)")
    trajectory = tables.get("trajectory")
    if trajectory is not None and len(trajectory):
        sources = set(trajectory["source"])
        if "truth" not in sources or not sources & {"slam", "paper preset"}:
            refuse("table trajectory has no rows of source " + ("truth" if "truth" not in sources else
                                                                "slam or paper preset") + ", which Fig. 10 draws")
    walls = tables.get("map")
    if trajectory is not None and len(trajectory) and walls is not None and len(walls) and "truth" not in set(walls["source"]):
        refuse("table map has no rows of source truth (the true walls Fig. 10 draws)")


#: most panels (scans) of Fig. 9 (a study draws 4, StudyConfig.panels)
MAX_PANELS = 16


def draw_figures(tables: dict[str, pd.DataFrame], out: Path, signals_k: int = 10,
                 angle_increment: float | None = None, world: str = "office",
                 log: Callable[[str], None] | None = None) -> dict[str, list[Path]]:
    """Every paper figure whose tables are present and whose driving table (``DRIVING_TABLES``)
    holds rows (an empty one drew empty axes); returns name -> files written. ``world`` names the simulated world in the
    titles (the files keep the paper's names, e.g. ``fig9_office``). ``log`` (a driver's progress)
    is told of each figure as it starts: ``drawing fig3_scan (1 of 9) ...``."""
    out.mkdir(parents=True, exist_ok=True)
    # a figure's driving table without rows draws nothing (the tables beside it, lines, corners, the
    # map, may be empty: a scan without corners still has its figure)
    tables = {name: table for name, table in tables.items() if len(table) or name not in DRIVING_TABLES}
    plan: list[tuple[str, Callable[[], list[Path]]]] = []  # each figure to draw, in order, and how
    if "signals" in tables:
        sig = tables["signals"]
        inc = angle_increment or float(pd.Series(sig["bearing_deg"]).diff().median() * 3.141592653589793 / 180)
        plan += [
            ("fig3_scan", lambda: draw.fig_scan(sig, out / "fig3_scan", f"Fig. 3: a {len(sig)}-beam scan of the {world}")),
            ("fig4_ad", lambda: draw.fig_signal(sig, "ad", f"AD_i{signals_k}",
                                                f"Fig. 4: AD_i{signals_k} of {article(world)} {world} scan",
                                                out / "fig4_ad", reference=ad_reference(signals_k, inc))),
            ("fig5_theta", lambda: draw.fig_signal(sig, "theta_deg", "theta_i (deg)",
                                                   "Fig. 5: theta_i (line normal angle) of the scan", out / "fig5_theta")),
            ("fig6_psi", lambda: draw.fig_signal(sig, "psi_deg", "psi_i (deg)",
                                                 f"Fig. 6: psi_i = theta_i - theta_(i+{signals_k})", out / "fig6_psi")),
        ]
    if "timing" in tables:
        plan.append(("fig7_timing", lambda: draw.fig_timing(tables["timing"], out / "fig7_timing")))
    real = panels_log_name(tables["intel_points"]) if "intel_points" in tables else "Intel"
    for source, title in (("office", "Fig. 9: features extracted by {method}, simulated " + world),
                          ("intel", "Fig. 9: features extracted by {method}, "
                                    + ("Intel Research Lab" if real == "Intel" else real) + " (real log)")):
        if f"{source}_points" in tables and len(tables[f"{source}_points"]):  # no panel: no figure
            lines = tables[f"{source}_lines"]
            method = str(lines["method"].iloc[0]) if "method" in lines and len(lines) else "the extractor"
            plan.append((f"fig9_{source}", lambda source=source, title=title.format(method=method): draw.fig_scans(
                tables[f"{source}_points"], tables[f"{source}_lines"], tables[f"{source}_corners"],
                out / f"fig9_{source}", title)))
    if "trajectory" in tables and "map" in tables:
        plan.append(("fig10_slam", lambda: draw.fig_slam(tables["trajectory"], tables["map"], out / "fig10_slam",
                                                         "Fig. 10: SLAM without odometry against ground truth")))
    if "summary" in tables and accuracy_speed_problem(tables) is None:
        plan.append(("accuracy_speed", lambda: draw.fig_accuracy_speed(tables["summary"], out / "accuracy_speed")))
    written: dict[str, list[Path]] = {}
    for number, (name, figure) in enumerate(plan, 1):
        if log is not None:  # figures drew ~27 s without a word (12 s from --tables) before its listing
            log(f"drawing {name} ({number} of {len(plan)}) ...")
        written[name] = figure()
    return written


def draw_sweep(folder: Path, out: Path, log: Callable[[str], None] | None = None,
               table: pd.DataFrame | None = None, spec: dict | None = None) -> dict[str, list[Path]]:
    """Plots of one sweep folder: each metric against the first grid parameter, a line per value
    of the second, a panel per value of the third (or combination of the rest); mean +/- std over
    seeds and random draws. A linked grid key "a,b" counts as its first name. The plots are
    ``out/sweep_<name>_<metric>.*`` (``sweep_stems``), name being the sweep.yaml's ``name:``.
    ``log`` is told of each plot as it starts, as by :func:`draw_figures`. ``table``: the folder's
    results.parquet as read already (``options.read_sweep_results``), else read here; ``spec``: its
    sweep.yaml as parsed already, likewise."""
    table, name, varied, sampled, metrics = sweep_plan(folder, table, spec)

    def starting(stem: str, number: int) -> None:
        if log is not None:
            log(f"drawing {stem} ({number} of {len(metrics)}) ...")

    if not varied and sampled:  # a random search: each metric against each sampled parameter
        scatters = {}
        for number, m in enumerate(metrics, 1):
            starting(f"sweep_{name}_{m}", number)
            scatters[f"sweep_{name}_{m}"] = draw.fig_sweep_scatter(table, sampled, m, out / f"sweep_{name}_{m}",
                                                                   title=f"{name}: {m} against the sampled parameters")
        return scatters
    if not varied:
        return {}
    # the x axis is a number where one is varied: text and boolean parameters (logs, methods, worlds,
    # deskew on/off) become the lines and panels (a sweep whose first grid key was a list of log paths
    # drew them as x values; one of [true, false] was drawn at x = 0 and 1)
    varied = sorted(varied, key=lambda n: not draw.is_number(table[n]))
    x, rest = varied[0], varied[1:]
    hue = rest[0] if rest else None
    facet = None
    if len(rest) == 2:
        facet = rest[1]
    elif len(rest) > 2:  # one panel per combination of the remaining parameters
        facet = ", ".join(rest[1:])
        table = table.assign(**{facet: table[rest[1:]].astype(object).apply(
            lambda r: ", ".join(f"{k}={v}" for k, v in r.items()), axis=1)})
    written = {}
    for number, metric in enumerate(metrics, 1):
        stem = f"sweep_{name}_{metric}"
        starting(stem, number)
        written[stem] = draw.fig_sweep(table, x, metric, out / stem, hue=hue, facet=facet,
                                       title=f"{name}: {metric} against {x}")
    return written


def sweep_stems(folder: Path, table: pd.DataFrame | None = None, spec: dict | None = None) -> list[str]:
    """The names (without .png / .pdf / .csv) of the plots ``draw_sweep`` draws of ``folder``,
    drawing nothing: ``figures`` checks before any work that no two ``--sweep`` folders share one
    (two sweeps of one name, e.g. one sweep file run into two folders, wrote the second's plots over
    the first's, exit 0). ``table``, ``spec``: as :func:`draw_sweep`'s."""
    _, name, varied, sampled, metrics = sweep_plan(folder, table, spec)
    return [f"sweep_{name}_{m}" for m in metrics] if varied or sampled else []


def sweep_plan(folder: Path, table: pd.DataFrame | None = None,
               spec: dict | None = None) -> tuple[pd.DataFrame, str, list[str], list[str], list[str]]:
    """What ``draw_sweep`` plots of ``folder``: its table (``table``, its results.parquet read already,
    else read here), name, varied grid parameters, sampled parameters and metrics (``spec``: its
    sweep.yaml parsed already, else parsed here)."""
    from experiments.figures.study import check_table, read_table

    path = folder / "results.parquet"
    table = read_table(path) if table is None else check_table(table, path)
    if spec is None:  # the sweep's record, an earlier version's too
        spec = load_yaml((folder / "sweep.yaml").read_text(), words=True)
    name = spec.get("name", folder.name)
    if "name" in spec and not _file_name(name):  # it names the plots' files
        from lms200 import LmsbenchError

        # "../../x" wrote its plots outside --out (through a folder "sweep_.." it made), a list was drawn as
        # "sweep_['a', 'b']_f1", 300 characters failed after the paper's figures ("File name too long")
        raise LmsbenchError(f"--sweep {folder}: its sweep.yaml's name: {str(name)[:120]!r} is no name a file can take "
                            f"(text of at most {MAX_PLOT_NAME} characters, without / and not starting with .), and it "
                            "names the sweep's plots (sweep_NAME_METRIC): not a sweep.yaml `lmsbench sweep` wrote (edited?)")
    # one name per grid key: parameters linked to it ("a,b") follow it and need no line of their own
    varied = [key.split(",")[0].strip() for key in spec.get("grid", {})]
    varied = [n for n in varied if n in table and table[n].nunique() > 1]
    sampled = [n for n in spec.get("random", {}) if n in table]
    return table, name, varied, sampled, sweep_metrics(table, spec, folder)


#: longest sweep name a plot is named by (a sweep's own are at most 100: experiments.sweep.spec.MAX_NAME_CHARS)
MAX_PLOT_NAME = 150


def _file_name(name: object) -> bool:
    """Whether a sweep.yaml's name can name its plots' files in --out: text, no path, not hidden."""
    return (isinstance(name, str) and 0 < len(name) <= MAX_PLOT_NAME and "/" not in name and "\0" not in name
            and not name.startswith("."))


#: a sweep row's columns that are no metric: the runner's own (docs/experiments.md, "Sweep outputs")
SWEEP_BOOKKEEPING = ("seed", "status", "error", "elapsed_s", "cell")


def sweep_metrics(table: pd.DataFrame, spec: dict, folder: Path | None = None) -> list[str]:
    """The metrics of a sweep's plots: for a built-in kind, those of SWEEP_METRICS the table has
    values of; for a user's ``package.module:function`` kind (whose metrics are its own names:
    nothing was drawn for it, and one that also returned an "f1" had only that drawn), or a built-in
    kind without any, every numeric column with a value that is neither a parameter of the sweep
    file nor the runner's bookkeeping."""
    from lms200 import LmsbenchError

    text = [m for m in SWEEP_METRICS if m in table and table[m].notna().any() and not _numbers(table[m])]
    if text:  # "internal error: TypeError: dtype 'str' does not support operation 'mean'" (a damaged-input fuzz round)
        raise LmsbenchError(f"--sweep {folder if folder is not None else spec.get('name', '')}: its results.parquet's column {text[0]} holds "
                            f"{table[text[0]].dtype} values, where a sweep's metric is a number: a damaged or edited "
                            "table, or not one of `lmsbench sweep`")
    known = [m for m in SWEEP_METRICS if m in table and _finite(table[m]).any()]  # all inf was plotted as nothing
    if known and ":" not in str(spec.get("kind", "")):
        return known
    params = {n.strip() for key in (*spec.get("grid", {}), *spec.get("random", {}), *spec.get("fixed", {}))
              for n in str(key).split(",")}
    metrics = [c for c in table.columns if c not in params and c not in SWEEP_BOOKKEEPING
               and _numbers(table[c]) and _finite(table[c]).any()]
    from experiments.sweep.spec import metric_name_problem

    for metric in metrics:  # it names a plot's files: "a/b\n" drew one into a folder of its own, 5,000 characters
        problem = metric_name_problem(metric)  # were an internal MemoryError (the cells refuse them now)
        if problem:
            raise LmsbenchError(f"--sweep {folder if folder is not None else spec.get('name', '')}: its results.parquet "
                                f"holds {problem}; no plot can be named by it")
    return metrics


def _numbers(column: pd.Series) -> bool:
    """Whether a column holds numbers the plots can average (not text, lists or booleans)."""
    return pd.api.types.is_numeric_dtype(column) and not pd.api.types.is_bool_dtype(column)


