"""A small, slow, independent oracle of the sensor method for the tests: the per-beam signals
(eq. 4, 6-7 as corrected in NOTES.md, psi) written from their definitions over sliding windows,
and the Log-Hough vote (eq. 5) of one run computing log cos directly (no template)."""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

N_BINS = 13  # the accumulator's log-range cells (as documented for features.sensor.engine)


def signals(ranges: np.ndarray, bearings: np.ndarray, increment: float, k: int, range_lo: float,
            range_hi: float) -> dict:
    """AD, ad, theta (unwrapped) and psi of every beam; nan where a window is incomplete or invalid."""
    n = ranges.size
    with np.errstate(all="ignore"):
        u = np.where((ranges >= range_lo) & (ranges <= range_hi), 1.0 / ranges, np.nan)
        AD = np.full(n, np.nan)
        ad = np.full(n, np.nan)
        if n >= 2 * k + 1:
            win = sliding_window_view(u, 2 * k + 1)  # window of centre i = k + row
            centre = win[:, k]
            AD[k : n - k] = win.sum(axis=1) / centre  # eq. 4
            ad[k : n - k] = (win[:, k:].sum(axis=1) - win[:, :k].sum(axis=1)) / centre  # eq. 6
        sin_sum = sum(np.sin(m * increment) for m in range(1, k + 1))
        theta = bearings + np.arctan((ad - 1.0) / (2.0 * sin_sum))  # eq. 7, corrected
        psi = np.full(n, np.nan)
        if n > k:
            psi[: n - k] = np.angle(np.exp(1j * (theta[: n - k] - theta[k:])))
    return {"AD": AD, "ad": ad, "theta": theta, "psi": psi,
            "ad_line": 1.0 + 2.0 * sum(np.cos(j * increment) for j in range(1, k + 1))}


def log_hough_peak(beam: np.ndarray, log_d: np.ndarray, a_idx: np.ndarray, step: float, subdiv: int,
                   bin_half: float, floor: float) -> tuple[int, float, np.ndarray]:
    """The peak of one run's votes over the band angles ``a_idx`` (template grid indices): every
    beam votes log p = log d + log cos(a - b) (eq. 5) into cells of width ``bin_half`` laid out
    around the median vote of the beams at 1/4, 1/2, 3/4 of the run; the peak is the pair of
    adjacent cells with most votes (ties: the angle nearest the band centre, then the lowest
    angle and cell). Returns (index into a_idx, log p of the peak, inlier mask)."""
    x = (a_idx[None, :] - beam[:, None] * subdiv) * step
    with np.errstate(all="ignore"):
        logcos = np.where(np.abs(x) < np.pi / 2, np.log(np.cos(x)), floor)
    votes = np.maximum(logcos, floor) + log_d[:, None]  # (beams, angles)
    cnt = beam.size
    ref = np.median(votes[[cnt // 4, cnt // 2, (3 * cnt) // 4]], axis=0)
    cell = np.floor((votes - ref) / bin_half + N_BINS / 2.0 + 1.0)
    cell = np.clip(np.nan_to_num(cell, nan=0.0), 0, N_BINS + 1).astype(int)
    h = (a_idx.size - 1) // 2
    best, best_a, best_c = -np.inf, 0, 0
    for a in range(a_idx.size):
        hist = np.bincount(cell[:, a], minlength=N_BINS + 2)
        for c in range(N_BINS - 1):
            v = hist[c + 1] + hist[c + 2] - 1e-3 * abs(a - h)
            if v > best:
                best, best_a, best_c = v, a, c
    peak = ref[best_a] + (best_c + 1 - N_BINS / 2.0) * bin_half
    return best_a, peak, np.abs(votes[:, best_a] - peak) <= bin_half
