"""Real-data figure of ``lmsbench compare LOG``: per log, explained fraction against lines per scan,
one marker per method (up and to the left is better: more of the scan explained by fewer lines).
Drawn from the compare summary table alone."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd

from experiments.style import method_color, new_figure, save_figure

MARKERS = ("o", "s", "^", "D", "v", "P", "X")
COLUMNS = ["source", "method", "lines_per_scan", "explained_3cm", "explained_3sigma", "ray_rmse_mm",
           "repeatability", "sigma_r_mm"]


def fig_explained_vs_lines(summary: pd.DataFrame, source: str, stem: Path) -> list[Path]:
    """One log's methods: explained fraction (filled: 3 cm; open: 3 sigma of the estimated noise)
    against lines per scan. Writes ``stem.png``, ``stem.pdf`` and the plotted rows (CSV)."""
    rows = summary[summary["source"] == source]
    data = rows[[c for c in COLUMNS if c in rows]].reset_index(drop=True)
    fig, ax = new_figure(height=3.6)
    for k, row in enumerate(data.itertuples(index=False)):
        color, marker = method_color(row.method), MARKERS[k % len(MARKERS)]
        ax.plot(row.lines_per_scan, row.explained_3cm, marker, color=color, ms=7, label=f"{row.method} (3 cm)")
        ax.plot(row.lines_per_scan, row.explained_3sigma, marker, color=color, ms=7, mfc="none",
                label=f"{row.method} (3 sigma)")
    sigma = f", sigma_r = {data['sigma_r_mm'].iloc[0]:.1f} mm" if "sigma_r_mm" in data and len(data) else ""
    ax.set_xlabel("lines per scan")
    ax.set_ylabel("explained fraction of valid beams")
    ax.set_ylim(0.0, 1.0)
    ax.set_title(f"{source}: explained fraction vs lines per scan{sigma}")
    ax.legend(loc="best", ncol=2)
    return save_figure(fig, stem, data=data)


def figure_stem(out: Path, source: str) -> Path:
    """``out/realdata_<source>`` with the source name made safe for a file name (compare's
    ``check_sources`` refuses two logs whose names give one stem)."""
    return out / ("realdata_" + re.sub(r"[^A-Za-z0-9_-]+", "_", source))
