"""The Log-Hough transform (eq. 5, Giesler et al. 1998) searched in a narrow band of normal angles.

For a point (d, b) and a candidate normal angle a, the line through it has
log p = log d + log cos(a - b). With a and b on one angle grid of step delta, log cos(a - b) is a
lookup in a precomputed template at index (a - b) / delta: every vote is an index shift.
All candidate runs are searched at once: their beams are stacked with a run id, the band of angles
is a 2-D array (beams x angles), and the accumulator is one ``np.bincount``.
"""

from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import numpy as np

LOGCOS_FLOOR = np.log(1e-6)  # template value where |a - b| >= pi/2 (the beam cannot see the line)
N_BINS = 13  # log-range cells of the accumulator around each (run, angle)'s middle vote


@lru_cache(maxsize=16)
def logcos_template(step: float) -> tuple[np.ndarray, int]:
    """log cos(m * step) for m = -M..M covering (-pi, pi], and M (the index of angle 0)."""
    half = int(np.ceil(np.pi / step))
    x = np.arange(-half, half + 1) * step
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(np.abs(x) < np.pi / 2, np.log(np.cos(x)), LOGCOS_FLOOR)
    t = np.maximum(t, LOGCOS_FLOOR)
    t.setflags(write=False)
    return t, half


@lru_cache(maxsize=16)
def band_layout(n_angles: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Angle offsets -h..h of the band, the centre-preferring tie-break added to the votes, and
    the cell offsets (a * n_cells) of each band angle in a run's block of the accumulator."""
    h = (n_angles - 1) // 2
    offsets = np.arange(-h, h + 1)
    tie = -1e-3 * np.abs(offsets)[:, None]  # (n_angles, 1): prefer the band centre on ties
    cell_base = np.arange(n_angles) * (N_BINS + 2)
    return offsets, tie, cell_base


class HoughPeak(NamedTuple):
    alpha: np.ndarray  # (R,) normal angle of the peak (rad, sensor frame, not wrapped)
    rho: np.ndarray  # (R,) distance of the peak line (m)
    inlier: np.ndarray  # (N,) bool: the beam voted in the peak cell


def band_search(
    beam: np.ndarray,
    log_d: np.ndarray,
    run_id: np.ndarray,
    starts: np.ndarray,
    counts: np.ndarray,
    centre: np.ndarray,
    half_width: np.ndarray,
    bin_half: np.ndarray,
    angle_min: float,
    increment: float,
    subdiv: int,
    n_angles: int,
) -> HoughPeak:
    """Log-Hough peak of every run in its band of normal angles.

    Args:
        beam: (N,) beam index of each stacked beam; log_d: (N,) log range; run_id: (N,) run of it.
        starts, counts: (R,) first row and number of rows of each run in the stack.
        centre: (R,) slope estimate of each run (rad); half_width: (R,) band half-width (rad).
        bin_half: (R,) half-width of the peak's log-range window (dimensionless, in log p); the
            accumulator cells are this wide and a peak is read over two adjacent cells.
        angle_min, increment: the scan's bearing of beam 0 and beam step (rad).
        subdiv: template steps per beam step; n_angles: odd number of angles searched per band.
    """
    step = increment / subdiv
    template, zero = logcos_template(step)
    offsets, tie, cell_base = band_layout(n_angles)
    h = max(int(offsets[-1]), 1)
    n_runs = starts.size
    n_cells = N_BINS + 2  # cells 1..N_BINS, 0 and N_BINS + 1 collect the votes outside
    # band of each run on the template grid: centre index and stride (in template steps)
    centre_idx = np.rint((centre - angle_min) / step).astype(np.int64)
    stride = np.maximum(np.rint(half_width / (h * step)), 1.0).astype(np.int64)
    a_idx = centre_idx[:, None] + stride[:, None] * offsets  # (R, A)
    # eq. 5: log p = log d + log cos(a - b), a lookup at a - b on the template
    idx = (a_idx + zero).take(run_id, axis=0)
    idx -= (beam * subdiv)[:, None]
    log_p = template.take(idx, mode="clip")
    log_p += log_d[:, None]  # (N, A)
    # cells are laid out around the median vote of three beams at 1/4, 1/2 and 3/4 of each run
    # (a mean would be dragged off by the neighbour-line beams at a run's ends, one beam can be a spike)
    q1 = log_p.take(starts + counts // 4, axis=0)
    q2 = log_p.take(starts + counts // 2, axis=0)
    q3 = log_p.take(starts + (3 * counts) // 4, axis=0)
    ref = np.maximum(np.minimum(q1, q2), np.minimum(np.maximum(q1, q2), q3))  # (R, A)
    inv_width = 1.0 / bin_half
    # cell = floor((log p - ref) / width) + N_BINS / 2 + 1, clipped into the two outside cells
    offset = (N_BINS / 2.0 + 1.0) - ref * inv_width[:, None]  # (R, A)
    rel = log_p * inv_width.take(run_id)[:, None]
    rel += offset.take(run_id, axis=0)
    np.fmax(rel, 0.0, out=rel)  # fmax also sends a nan vote to the outside cell 0
    np.minimum(rel, N_BINS + 1.0, out=rel)
    key = rel.astype(np.int64)
    key += (run_id * (n_angles * n_cells))[:, None] + cell_base
    acc = np.bincount(key.ravel(), minlength=n_runs * n_angles * n_cells)
    acc = acc.reshape(n_runs, n_angles, n_cells)[:, :, 1 : N_BINS + 1]
    pair = acc[:, :, :-1] + acc[:, :, 1:] + tie  # votes in two adjacent cells
    best_a, best_c = np.divmod(pair.reshape(n_runs, -1).argmax(axis=1), N_BINS - 1)
    runs = np.arange(n_runs)
    # the pair (c, c+1) covers (log p - ref) / width in [c - N_BINS/2, c + 2 - N_BINS/2)
    peak_log_p = ref[runs, best_a] + (best_c + 1 - N_BINS / 2.0) * bin_half
    alpha = angle_min + a_idx[runs, best_a] * step
    chosen = log_p[np.arange(beam.size), best_a[run_id]]
    inlier = np.abs(chosen - peak_log_p[run_id]) <= bin_half[run_id]
    return HoughPeak(alpha, np.exp(peak_log_p), inlier)
