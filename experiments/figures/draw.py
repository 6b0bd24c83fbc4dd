"""Draw each figure from its tidy table(s) alone, so any figure can be redrawn without rerunning.

Every ``fig_*`` function takes DataFrames (schemas in :mod:`experiments.figures.tables`) and a
path stem, and writes ``stem.png``, ``stem.pdf`` and the tables beside them (CSV).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import matplotlib.pyplot as plt
from matplotlib.collections import LineCollection

from experiments.style import (CORNER_COLOR, LINE_COLOR, SCAN_COLOR, SHOWN_IN_DEGREES, TRUTH_COLOR, equal_axes, label_of, log_axis,
                               method_color,
                               new_figure, save_figure, shown)


def add_segments(ax, table: pd.DataFrame, lw: float, color: str, label: str | None = None) -> None:
    """Draw the segments of ``table`` (x1, y1, x2, y2) as ``ax.plot`` draws each ("-", projecting
    caps, z-order 2, the axes' limits taken in), but as one LineCollection instead of a Line2D a
    segment: drawing, layout and legend placement paid per artist (Fig. 10 of a 40 s run took
    2.8-4.0 s, 1.1-1.2 s now; its legends' "best", testing every wall, was 40 % of it in a profile). ``label``: one legend entry, a line of that width and colour (an
    empty Line2D, as before: a collection's own handle has butt caps). Nothing where ``table`` is empty."""
    if not len(table):
        return
    segments = table[["x1", "y1", "x2", "y2"]].to_numpy(dtype=float).reshape(-1, 2, 2)
    ax.add_collection(LineCollection(segments, linewidths=lw, colors=color, zorder=2,
                                     capstyle=plt.rcParams["lines.solid_capstyle"]), autolim=True)
    if label is not None:
        ax.plot([], [], "-", lw=lw, color=color, label=label)


def fig_scan(signals: pd.DataFrame, stem: Path, title: str) -> list[Path]:
    """Fig. 3: the scan itself, Cartesian in the sensor frame (equal axes) and range over beam index."""
    fig, (ax, ax2) = new_figure(1, 2, width=10.0, height=4.0)
    b = np.radians(signals["bearing_deg"].to_numpy())
    r = signals["range_m"].to_numpy(dtype=float)
    shown = np.isfinite(r)
    ax.plot(r[shown] * np.cos(b[shown]), r[shown] * np.sin(b[shown]), ".", ms=2.5, color=SCAN_COLOR)
    ax.plot([0], [0], "k^", ms=6)
    equal_axes(ax, "x (m, ahead)", "y (m, left)")
    ax.set_title("Cartesian, sensor frame")
    ax2.plot(signals["beam"][shown], r[shown], ".", ms=2.5, color=SCAN_COLOR)
    ax2.set_xlabel("beam index i")
    ax2.set_ylabel("range d_i (m)")
    ax2.set_title("sensor coordinates")
    fig.suptitle(title)
    return save_figure(fig, stem, data=signals[["beam", "bearing_deg", "range_m"]])


def fig_signal(signals: pd.DataFrame, column: str, ylabel: str, title: str, stem: Path,
               reference: float | None = None) -> list[Path]:
    """Figs. 4-6: one per-beam signal of a scan (``ad``, ``theta_deg``, ``psi_deg``) over the beam index,
    with ``reference`` (the straight-line value) as a dashed line and a ``reference`` column of the data."""
    if reference is not None:
        signals = signals.assign(reference=float(reference))
    fig, ax = new_figure(height=3.2)
    ax.plot(signals["beam"], signals[column], ".-", lw=0.7, ms=2.5, color=method_color("sensor"))
    if reference is not None:
        ax.axhline(reference, color=TRUTH_COLOR, lw=0.8, ls="--", label=f"straight line: {reference:.4f}")
        if "ad_band" in signals and column == "ad" and signals["ad_band"].notna().any():
            ax.fill_between(signals["beam"], reference - signals["ad_band"], reference + signals["ad_band"],
                            color=TRUTH_COLOR, alpha=0.3, lw=0, label="line test band (ad_tau x noise std)")
        ax.legend(loc="best")
    ax.set_xlabel("beam index i")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    return save_figure(fig, stem, data=signals)


def fig_timing(timing: pd.DataFrame, stem: Path) -> list[Path]:
    """Fig. 7: processing time per scan (ms) over the scans of a run, one line per method."""
    fig, ax = new_figure(height=3.6)
    for method, group in timing.groupby("method", sort=False):
        med = group["time_ms"].median()
        ax.plot(group["scan"], group["time_ms"], lw=0.9, color=method_color(method),
                label=f"{method} (median {med:.2f} ms)")
    log_axis(ax, "y")
    ax.set_xlabel("scan (index in the run)")
    ax.set_ylabel("processing time per scan (ms)")
    ax.set_title("Processing time for successive scans")
    ax.legend(loc="upper right", ncol=2)
    return save_figure(fig, stem, data=timing)


def fig_scans(points: pd.DataFrame, lines: pd.DataFrame, corners: pd.DataFrame, stem: Path,
              title: str) -> list[Path]:
    """Fig. 9: scans (sensor frame) with extracted lines and corners, one panel per scan.

    ``points``: panel, label, x, y; ``lines``: panel, x1, y1, x2, y2; ``corners``: panel, x, y.
    """
    panels = list(dict.fromkeys(points["panel"]))
    ncols = 2 if len(panels) == 4 else min(3, len(panels))
    nrows = int(np.ceil(len(panels) / ncols))
    fig, axes = new_figure(nrows, ncols, width=3.6 * ncols, height=3.4 * nrows, squeeze=False)
    for ax, panel in zip(axes.ravel(), panels):
        pts = points[points["panel"] == panel]
        ax.plot(pts["x"], pts["y"], ".", ms=1.5, color=SCAN_COLOR)
        ax.plot([0], [0], "k^", ms=5)
        ln = lines[lines["panel"] == panel]
        add_segments(ax, ln, 1.6, LINE_COLOR)
        ax.plot((ln["x1"] + ln["x2"]) / 2, (ln["y1"] + ln["y2"]) / 2, "*", ms=5, color=LINE_COLOR)
        cr = corners[corners["panel"] == panel]
        ax.plot(cr["x"], cr["y"], "D", ms=5, mfc="none", mew=1.2, color=CORNER_COLOR)
        ax.set_title(f"{pts['label'].iloc[0]}: {len(ln)} line{'s' if len(ln) != 1 else ''}, "
                     f"{len(cr)} corner{'s' if len(cr) != 1 else ''}", fontsize=8)
        equal_axes(ax, "x (m, ahead)", "y (m, left)")
    first = axes.ravel()[0]
    method = str(lines["method"].iloc[0]) if "method" in lines and len(lines) else "the extractor"
    first.plot([], [], ".", color=SCAN_COLOR, label="scan points")
    first.plot([], [], "-*", color=LINE_COLOR, label=f"lines ({method})")
    first.plot([], [], "D", mfc="none", color=CORNER_COLOR, label=f"corners ({method})")
    first.legend(loc="lower left", fontsize=7)
    for ax in axes.ravel()[len(panels):]:
        ax.set_visible(False)
    fig.suptitle(title)
    return save_figure(fig, stem, data={"points": points, "lines": lines, "corners": corners})


def fig_slam(trajectory: pd.DataFrame, map_lines: pd.DataFrame, stem: Path, title: str) -> list[Path]:
    """Fig. 10: SLAM trajectory and line map against ground truth (world frame, equal axes), one
    panel per estimate: the paper preset (if present) beside the default pipeline ("slam").

    ``trajectory``: source (slam / paper preset / truth / ...), t, x, y, theta; ``map_lines``:
    source (slam / paper preset / truth), x1, y1, x2, y2.
    """
    estimates = [s for s in ("paper preset", "slam") if s in set(trajectory["source"])]
    fig, axes = new_figure(1, len(estimates), width=5.6 * len(estimates), height=5.6, squeeze=False)
    truth_map = map_lines[map_lines["source"] == "truth"]
    truth = trajectory[trajectory["source"] == "truth"]
    for ax, source in zip(axes.ravel(), estimates):
        add_segments(ax, truth_map, 3.0, "#d0d0d0", label="true walls")
        add_segments(ax, map_lines[map_lines["source"] == source], 1.2, LINE_COLOR, label="SLAM map lines")
        est = trajectory[trajectory["source"] == source]
        ax.plot(truth["x"], truth["y"], "--", lw=1.4, color=method_color("truth"), label="true trajectory")
        ax.plot(est["x"], est["y"], "-", lw=1.4, color=method_color(source), label=f"{source} trajectory")
        ax.plot(truth["x"].head(1), truth["y"].head(1), "ko", ms=5, label="start")
        equal_axes(ax)
        ax.set_title("paper preset (EKF, constant velocity)" if source == "paper preset"
                     else "default (scan matching + pose graph)", fontsize=9)
    # One legend below the panels: a map fills its panel, so no place inside is free of data in
    # every world ("best" inside each panel had to test every wall and still covered some).
    entries: dict[str, object] = {}
    for ax in axes.ravel():
        for handle, label in zip(*ax.get_legend_handles_labels()):
            entries.setdefault(label, handle)
    entries["start"] = entries.pop("start")  # after both trajectories
    fig.legend(entries.values(), entries.keys(), loc="outside lower center", ncol=min(len(entries), 6), fontsize=7)
    fig.suptitle(title)
    return save_figure(fig, stem, data={"trajectory": trajectory, "map": map_lines})


def fig_accuracy_speed(summary: pd.DataFrame, stem: Path) -> list[Path]:
    """Accuracy against time per scan, one point per extractor: line F1 (left) and rho RMS error
    (right, mm) against the median time per scan (ms), bars from the 25 to the 75 % time."""
    panels = [("f1", "line F1 against ground truth")]
    if "rho_rms_mm" in summary:
        panels.append(("rho_rms_mm", "rho RMS error of matched lines (mm)"))
    fig, axes = new_figure(1, len(panels), width=4.6 * len(panels), height=3.8, squeeze=False)
    for ax, (column, label) in zip(axes.ravel(), panels):
        for i, row in enumerate(summary.itertuples()):
            x, y = row.time_ms_median, getattr(row, column)
            ax.errorbar(x, y, xerr=[[x - row.time_ms_p25], [row.time_ms_p75 - x]], fmt="o", ms=6, capsize=3,
                        color=method_color(row.method))
            # alternate above / below so neighbours do not overwrite each other, in the point's colour:
            # two methods of nearly one speed (hough, ransac) had each name beside the other's point
            ax.annotate(row.method, (x, y), textcoords="offset points", xytext=(5, 5 if i % 2 == 0 else -12),
                        fontsize=8, color=method_color(row.method))
        log_axis(ax, "x")
        ax.set_xlabel("time per scan (ms; median, bars 25-75 %)")
        ax.set_ylabel(label)
        if column == "f1":
            ax.set_ylim(0.0, 1.02)  # the whole scale: differences of 0.01 are not drawn as chasms
    fig.suptitle("Accuracy versus speed, every extractor")
    return save_figure(fig, stem, data=summary)


def short_value(value: object) -> str:
    """A parameter value as a short label: a path by its file name, any text cut to 28 characters."""
    text = str(value)
    if "/" in text:
        text = text.rstrip("/").rsplit("/", 1)[-1]
    return text if len(text) <= 28 else text[:27] + "~"


def is_number(values: pd.Series) -> bool:
    """Whether a parameter's values are numbers to draw on a numeric axis: numeric and not booleans
    (a bool is an int to pandas and numpy: ``alignment.deskew: [true, false]`` was drawn at x = 0
    and 1, joined by a line, or taken as the x axis before a numeric parameter). Booleans, like
    text, are categories: lines, panels or labelled x positions."""
    return pd.api.types.is_numeric_dtype(values) and not pd.api.types.is_bool_dtype(values)


def fig_sweep(table: pd.DataFrame, x: str, y: str, stem: Path, hue: str | None = None,
              facet: str | None = None, title: str = "") -> list[Path]:
    """A sweep plot: metric ``y`` (mean over seeds, +/- one std) against parameter ``x``, a line per
    value of ``hue``, a panel per value of ``facet``. Failed cells are left out."""
    ok = table[table["status"] == "ok"] if "status" in table else table
    keys = [c for c in (facet, hue, x) if c]
    stats = ok.groupby(keys, dropna=False)[y].agg(["mean", "std", "count"]).reset_index()
    # text or boolean x values (no varied parameter is a number): categories in the grid's order, not joined
    categories = None if is_number(ok[x]) else list(dict.fromkeys(ok[x]))
    seeds = int(stats["count"].max()) if len(stats) else 0
    panels = list(stats.groupby(facet, sort=True)) if facet else [(None, stats)]
    fig, axes = new_figure(1, len(panels), width=min(4.2 * len(panels), 13), height=3.6, squeeze=False,
                           sharey=True)
    hue_values = (sorted(stats[hue].unique()) if is_number(stats[hue])
                  else list(dict.fromkeys(ok[hue]))) if hue else [None]  # text, booleans: the grid's order
    cmap = plt.get_cmap("viridis", max(2, len(hue_values)))
    for ax, (facet_value, panel) in zip(axes.ravel(), panels):
        groups = sorted(panel.groupby(hue), key=lambda g: hue_values.index(g[0])) if hue else [(None, panel)]
        for value, group in groups:
            if hue in ("method", "extractor"):
                color = method_color(str(value))
            elif hue:
                color = cmap(hue_values.index(value) / max(1, len(hue_values) - 1))
            else:
                color = None
            if categories is not None:
                group = group.assign(_at=group[x].map(categories.index)).sort_values("_at")
            yerr = group["std"].fillna(0.0) if seeds > 1 else None  # no spread from a single seed
            ax.errorbar(shown(x, group[x]) if categories is None else group["_at"], group["mean"], yerr=yerr,
                        fmt="o-" if categories is None else "o", ms=4, capsize=2, lw=1.0,
                        label=f"{shown(hue, value):g}" if hue in SHOWN_IN_DEGREES else short_value(value) if hue
                        else label_of(y), color=color)
        if categories is not None:
            ax.set_xticks(range(len(categories)), [short_value(v) for v in categories], rotation=20, ha="right",
                          fontsize=7)
        ax.set_xlabel(label_of(x))
        if facet:
            facet_shown = f"{shown(facet, facet_value):g} deg" if facet in SHOWN_IN_DEGREES else f"{facet_value}"
            ax.set_title(f"{facet} = {facet_shown}", fontsize=9)
    spread = f"mean +/- std over {seeds} seeds" if seeds > 1 else "one seed"
    axes.ravel()[0].set_ylabel(f"{label_of(y)}\n({spread})")
    if hue:
        axes.ravel()[-1].legend(title=label_of(hue), loc="best", fontsize=7, title_fontsize=7)
    fig.suptitle(title or f"{label_of(y)} against {label_of(x)}")
    return save_figure(fig, stem, data=stats)


def fig_sweep_scatter(table: pd.DataFrame, params: list[str], y: str, stem: Path, title: str = "") -> list[Path]:
    """A random-search plot: metric ``y`` of every cell against each sampled parameter (a panel each)."""
    ok = table[table["status"] == "ok"] if "status" in table else table
    fig, axes = new_figure(1, len(params), width=min(3.6 * len(params), 14), height=3.4, squeeze=False, sharey=True)
    for ax, name in zip(axes.ravel(), params):
        values = shown(name, ok[name]) if is_number(ok[name]) else ok[name].astype(str)  # categories: a choice
        ax.plot(values, ok[y], "o", ms=4, color=method_color("sensor"), alpha=0.8, label="one cell")
        ax.set_xlabel(label_of(name))
    axes.ravel()[0].set_ylabel(label_of(y))
    axes.ravel()[0].legend(loc="best")
    fig.suptitle(title or f"{label_of(y)} against the sampled parameters")
    return save_figure(fig, stem, data=ok[[*params, y]])
