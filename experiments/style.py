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

import math
from pathlib import Path
from typing import Any, Iterable

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from lms200.errors import in_chain  # noqa: E402

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


def log_axis(ax, which: str = "x") -> None:
    """A readable log axis: plain decimal tick labels (0.05, 0.1, 2, 50), never scientific
    notation; minor ticks labelled (at 2 and 5 x a power of ten) only when the axis spans less than
    two decades, so labels never run into each other."""
    from matplotlib.ticker import FuncFormatter, LogLocator

    axis = ax.xaxis if which == "x" else ax.yaxis
    (ax.set_xscale if which == "x" else ax.set_yscale)("log")

    def plain(value: float, _pos: int | None = None) -> str:
        return f"{value:.6g}" if value > 0 else ""

    def minor(value: float, _pos: int | None = None) -> str:
        lo, hi = sorted(ax.get_xlim() if which == "x" else ax.get_ylim())
        if lo <= 0 or math.log10(hi / lo) >= 2:
            return ""
        mantissa = round(value / 10 ** math.floor(math.log10(value) + 1e-9), 6)
        return plain(value) if mantissa in (2.0, 5.0) else ""

    axis.set_major_locator(LogLocator(base=10))
    axis.set_minor_locator(LogLocator(base=10, subs=tuple(range(2, 10))))
    axis.set_major_formatter(FuncFormatter(plain))
    axis.set_minor_formatter(FuncFormatter(minor))


#: Axis labels (with units) of the parameters and metrics of sweeps and comparisons.
LABELS: dict[str, str] = {
    "sensor.noise_sigma": "range noise, 1 sigma (m)",
    "sensor.resolution": "angular resolution (deg)",  # radians in the config, drawn in degrees (see shown)
    "sensor.resolution_deg": "angular resolution (deg)",  # the old spelling, in sweep tables written before
    "sensor.beam_width": "laser spot width (deg)",  # radians in the config, drawn in degrees
    "sensor.beam_width_deg": "laser spot width (deg)",
    "sensor.n_beams": "beams per scan",
    "sensor.dropout_prob": "dropout probability",
    "extractor.k": "window half-width k (beams)",
    "extractor.ad_tau": "AD threshold ad_tau (noise std)",
    "extractor.psi_split": "psi split threshold (rad)",
    "extractor.band_tau": "Log-Hough band half-width band_tau (std)",
    "extractor.sigma_r": "extractor's range noise sigma_r (m)",
    "method": "extractor",
    "seed": "seed",
    "duration": "simulated run (s)",
    "rate_hz": "scans kept per second (scans/s)",
    "f1": "line F1 against ground truth",
    "precision": "line precision",
    "recall": "line recall",
    "corner_f1": "corner F1 against ground truth",
    "rho_rms_mm": "rho RMS error of matched lines (mm)",
    "alpha_rms_deg": "alpha RMS error of matched lines (deg)",
    "time_ms_median": "time per scan, median (ms)",
    "us_median": "time per scan, median (us)",
    "ate_rms": "ATE RMS after 2-D alignment (m)",
    "ate_max": "largest ATE after 2-D alignment (m)",
    "final_error_m": "final position error (m)",
    "heading_rms": "heading RMS error (rad)",
    "lines_per_scan": "lines per scan",
}


#: Parameters held in radians (configs have one angle unit) but drawn in degrees, as their labels say.
SHOWN_IN_DEGREES = frozenset({"sensor.resolution", "sensor.beam_width"})


def shown(name: str, values: Any) -> Any:
    """``values`` of parameter ``name`` as drawn: degrees for the angles of SHOWN_IN_DEGREES (their
    labels say deg), else as they are. Takes a number or an array / Series."""
    if name not in SHOWN_IN_DEGREES:
        return values
    return np.degrees(values) if not isinstance(values, (int, float)) else math.degrees(values)


def label_of(name: str) -> str:
    """The axis label of a parameter or metric: a known one with its unit, else the name with the
    unit its suffix says (``_m``, ``_mm``, ``_deg``, ``_s``, ``_hz``), else the name itself."""
    if name in LABELS:
        return LABELS[name]
    for suffix, unit in (("_mm", "mm"), ("_m", "m"), ("_deg", "deg"), ("_rad", "rad"), ("_ms", "ms"),
                         ("_s", "s"), ("_hz", "scans/s"), ("_sigma", "m")):
        if name.endswith(suffix):
            return f"{name} ({unit})"
    return name


def equal_axes(ax, xlabel: str = "x (m)", ylabel: str = "y (m)") -> None:
    """Make a map axis metric: equal scale on x and y, labelled in metres."""
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)


def savefig(fig, path: Path | str, **kwargs) -> None:
    """``fig.savefig(path, **kwargs)``, a failed write raised as its own OSError: matplotlib's PDF
    backend, cleaning up after a write that found a full disk, raised an error of its own (an
    AttributeError "'Stream' object has no attribute 'pos'", or a zlib error) that masked the OSError
    (ENOSPC) in its ``__context__``, and the command died with "internal error: ..." instead of the one
    line a full disk is (``compare``, ``figures`` writing a PDF onto a full disk)."""
    try:
        fig.savefig(path, **kwargs)
    except OSError:
        raise
    except Exception as exc:
        failed = in_chain(exc, OSError)
        if failed is None:
            raise
        raise failed from None


def save_figure(fig, stem: Path | str, data: pd.DataFrame | dict[str, pd.DataFrame] | None = None,
                formats: Iterable[str] = ("png", "pdf")) -> list[Path]:
    """Save ``fig`` as ``stem.png`` and ``stem.pdf`` and the data behind it beside them.

    ``data`` is one table (written as ``stem.csv``) or several by name (``stem_NAME.csv``). Closes
    the figure. Returns every path written.
    """
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    from experiments.provenance import write_record

    # each file whole (a hidden temporary file renamed into place): a full disk while saving left a cut
    # PNG or PDF (an image 'file is truncated') or CSV beside whole ones, under an error line
    written = []
    for fmt in formats:
        path = stem.parent / f"{stem.name}.{fmt}"  # with_suffix took a dot in the name for one: a sweep's metrics
        # acc.5 and acc.6 drew into one sweep_NAME_acc.png, and a sweep named k.v put every plot in sweep_k.png
        write_record(path, lambda tmp, fmt=fmt: savefig(fig, tmp, format=fmt))
        written.append(path)
    plt.close(fig)
    tables = {"": data} if isinstance(data, pd.DataFrame) else dict(data or {})
    for name, table in tables.items():
        path = stem.parent / (f"{stem.name}_{name}.csv" if name else f"{stem.name}.csv")
        write_record(path, lambda tmp, table=table: table.to_csv(tmp, index=False))
        written.append(path)
    return written
