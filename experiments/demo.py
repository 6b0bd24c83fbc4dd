"""The demo's building blocks: an analytic room scan and the scan plot (Cartesian and polar)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from lms200 import Scan  # noqa: E402


def room_scan(
    width: float = 6.0,
    depth: float = 4.0,
    x: float = 1.5,
    y: float = 0.5,
    theta: float = 0.3,
    sigma: float = 0.005,
    seed: int = 0,
) -> Scan:
    """One 361-beam LMS200 scan from inside an axis-aligned rectangular room, cast exactly.

    The room spans [0, width] x [-depth/2, depth/2] (m, world frame); the sensor sits at (x, y)
    with heading theta (rad). Ranges get Gaussian noise of ``sigma`` m (seeded) and 1 mm
    quantisation; beyond 8.183 m is +inf (mm mode).
    """
    angles = -np.pi / 2 + np.arange(361) * np.deg2rad(0.5) + theta
    c, s = np.cos(angles), np.sin(angles)
    with np.errstate(divide="ignore", invalid="ignore"):
        tx = np.where(c > 0, (width - x) / c, np.where(c < 0, -x / c, np.inf))
        ty = np.where(s > 0, (depth / 2 - y) / s, np.where(s < 0, (-depth / 2 - y) / s, np.inf))
    r = np.minimum(tx, ty)
    r = r + np.random.default_rng(seed).normal(0.0, sigma, r.size)
    r = np.round(r, 3)
    r[r > 8.182] = np.inf
    return Scan.lms200(r)


def plot_scan(scan: Scan, path: Path, title: str = "") -> None:
    """Save the scan in Cartesian (sensor frame, equal axes) and in polar (range over bearing)."""
    fig = plt.figure(figsize=(11, 4.5))
    ax = fig.add_subplot(1, 2, 1)
    p = scan.points
    ax.plot(p[:, 0], p[:, 1], ".", ms=2)
    ax.plot([0], [0], "k^")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m, ahead)")
    ax.set_ylabel("y (m, left)")
    ax.set_title("Cartesian, sensor frame")
    ax.grid(True, alpha=0.3)
    ax2 = fig.add_subplot(1, 2, 2)
    shown = np.where(np.isfinite(scan.ranges), scan.ranges, np.nan)
    ax2.plot(np.degrees(scan.angles), shown, ".", ms=2)
    ax2.set_xlabel("bearing (deg)")
    ax2.set_ylabel("range (m)")
    ax2.set_title("sensor coordinates (range, bearing)")
    ax2.grid(True, alpha=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
