"""One matplotlib style for every figure of the project (Agg backend, no display).

Use::

    from experiments.style import apply_style, new_figure, equal_axes, save_figure, METHOD_COLORS
    apply_style()
    fig, ax = new_figure()
    ...
    save_figure(fig, out_dir / "fig4_ad", data=table)   # writes .png, .pdf and the data beside them

Maps (anything in metres on both axes) go through :func:`equal_axes` so that one metre is the
same length on x and y.
"""

from __future__ import annotations

from pathlib import Path
from typing import Iterable

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

#: rcParams applied by :func:`apply_style`: small, print-sized, readable in a report.
STYLE: dict[str, object] = {
    "figure.figsize": (6.4, 4.0),
    "figure.dpi": 100,
    "savefig.dpi": 150,
    "savefig.bbox": "tight",
    "font.size": 9,
    "axes.titlesize": 10,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "grid.linewidth": 0.5,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "lines.linewidth": 1.2,
    "lines.markersize": 3,
    "image.cmap": "viridis",
    "pdf.fonttype": 42,  # TrueType in PDFs, editable text
}

#: One colour per extractor / source, the same in every figure (tab10 order).
METHOD_COLORS: dict[str, str] = {
    "sensor": "#1f77b4",
    "split_merge": "#ff7f0e",
    "iepf": "#2ca02c",
    "hough": "#d62728",
    "ransac": "#9467bd",
    "slam": "#8c564b",
    "truth": "#000000",
    "odometry": "#7f7f7f",
}

#: Colours for map elements.
SCAN_COLOR = "#9e9e9e"
LINE_COLOR = "#d62728"
CORNER_COLOR = "#1f77b4"
TRUTH_COLOR = "#000000"


def apply_style() -> None:
    """Set the project's rcParams (idempotent)."""
    plt.rcParams.update(STYLE)


def method_color(method: str) -> str:
    """The colour of a method; unknown names get a stable colour from the tab10 cycle."""
    if method in METHOD_COLORS:
        return METHOD_COLORS[method]
    palette = plt.get_cmap("tab10").colors
    return matplotlib.colors.to_hex(palette[sum(map(ord, method)) % len(palette)])


def new_figure(nrows: int = 1, ncols: int = 1, width: float | None = None, height: float | None = None,
               **kwargs):
    """A styled figure and its axes (``plt.subplots`` with the project's size defaults)."""
    apply_style()
    w, h = STYLE["figure.figsize"]  # type: ignore[misc]
    size = (width or w * max(1, ncols) ** 0.8, height or h * max(1, nrows) ** 0.8)
    kwargs.setdefault("layout", "constrained")  # titles and labels of panels never overlap
    return plt.subplots(nrows, ncols, figsize=size, **kwargs)


def equal_axes(ax, xlabel: str = "x (m)", ylabel: str = "y (m)") -> None:
    """Make a map axis metric: equal scale on x and y, labelled in metres."""
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)


def save_figure(fig, stem: Path | str, data: pd.DataFrame | dict[str, pd.DataFrame] | None = None,
                formats: Iterable[str] = ("png", "pdf")) -> list[Path]:
    """Save ``fig`` as ``stem.png`` and ``stem.pdf`` and the data behind it beside them.

    ``data`` is one table (written as ``stem.csv``) or several by name (``stem_NAME.csv``). Closes
    the figure. Returns every path written.
    """
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    written = []
    for fmt in formats:
        path = stem.with_suffix(f".{fmt}")
        fig.savefig(path)
        written.append(path)
    plt.close(fig)
    tables = {"": data} if isinstance(data, pd.DataFrame) else dict(data or {})
    for name, table in tables.items():
        path = stem.parent / (f"{stem.name}_{name}.csv" if name else f"{stem.name}.csv")
        table.to_csv(path, index=False)
        written.append(path)
    return written
