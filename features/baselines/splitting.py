"""Recursive splitting and collinear merging, level-synchronous and vectorised over all segments.

The split step is that of split-and-merge (Pavlidis & Horowitz 1974; as evaluated by Nguyen et al.
2007): a segment whose farthest point lies more than a threshold from its line is split. With
``chord=True`` the line is the chord between the segment's end points (iterative end-point fit,
Duda & Hart 1973 / Douglas & Peucker 1973); otherwise the test uses the least-squares line. The
split point is always the point farthest from the chord: the least-squares line of a bent segment
lies farthest from its end points, and splitting there peels one point per pass.
Each pass handles every pending segment at once: no Python loop over points or segments.
"""

from __future__ import annotations

import numpy as np

from .common import Points, PrefixFit


def _ragged(start: np.ndarray, end: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions of every point of every range, the range label of each, and each range's offset."""
    length = end - start + 1
    offsets = np.cumsum(length) - length
    total = int(length.sum())
    labels = np.repeat(np.arange(start.size), length)
    pos = np.arange(total) - np.repeat(offsets - start, length)
    return pos, labels, offsets


def split(
    pts: Points, fitter: PrefixFit, clusters: np.ndarray, threshold: float, min_points: int, chord: bool
) -> np.ndarray:
    """Split clusters (c, 2 inclusive position ranges) until every point lies within ``threshold``
    (m) of its segment's line. Split points are shared by the two halves. Returns (s, 2) ranges in
    scan order; ranges shorter than ``min_points`` are not split further."""
    x, y = pts.x, pts.y
    active = clusters[(clusters[:, 1] - clusters[:, 0] + 1) >= max(min_points, 3)]
    finished = [clusters[(clusters[:, 1] - clusters[:, 0] + 1) < max(min_points, 3)]]
    while active.size:
        s, e = active[:, 0], active[:, 1]
        pos, labels, offsets = _ragged(s, e)
        xp, yp = x[pos], y[pos]
        # the chord between the end points: where a bent segment's corner lies farthest
        dx, dy = x[e] - x[s], y[e] - y[s]
        norm = np.maximum(np.hypot(dx, dy), 1e-12)
        nx, ny = -dy / norm, dx / norm
        rho = nx * x[s] + ny * y[s]
        d_chord = np.abs(xp * nx[labels] + yp * ny[labels] - rho[labels])
        d_chord[(pos == s[labels]) | (pos == e[labels])] = -1.0  # split strictly inside
        if chord:
            d = d_chord
        else:
            # the split test of split-and-merge uses the least-squares line; its farthest point is
            # usually an end point of a bent segment, so the split itself goes where the chord is
            # farthest (splitting at an end would peel one point per pass)
            rho_f, alpha_f, *_ = fitter.fit(s, e)
            d = np.abs(xp * np.cos(alpha_f)[labels] + yp * np.sin(alpha_f)[labels] - rho_f[labels])
        dmax = np.maximum.reduceat(d, offsets)
        cmax = np.maximum.reduceat(d_chord, offsets)
        needs = dmax > threshold
        finished.append(active[~needs])
        if not needs.any():
            break
        hit = np.flatnonzero((d_chord == cmax[labels]) & needs[labels])
        first = np.concatenate(([True], labels[hit][1:] != labels[hit][:-1]))
        at = pos[hit[first]]
        seg = active[needs]
        halves = np.concatenate((np.column_stack((seg[:, 0], at)), np.column_stack((at, seg[:, 1]))))
        long_enough = (halves[:, 1] - halves[:, 0] + 1) >= max(min_points, 3)
        finished.append(halves[~long_enough])
        active = halves[long_enough]
    out = np.concatenate(finished)
    return out[np.lexsort((out[:, 1], out[:, 0]))]


def merge_collinear(fitter: PrefixFit, segs: np.ndarray, max_rms: float) -> np.ndarray:
    """Merge neighbouring segments that share a split point while the least-squares line over both
    keeps an RMS residual <= ``max_rms`` (m). Each pass merges the pairs whose merged residual is a
    local minimum among overlapping pairs, so merges never conflict; passes repeat until none."""
    while segs.shape[0] > 1:
        joined = segs[1:, 0] == segs[:-1, 1]
        rms = fitter.residual_rms(segs[:-1, 0], segs[1:, 1])
        rms = np.where(joined, rms, np.inf)
        ok = rms <= max_rms
        if not ok.any():
            break
        left = np.concatenate(([np.inf], rms[:-1]))
        right = np.concatenate((rms[1:], [np.inf]))
        pick = ok & (rms < left) & (rms <= right)
        i = np.flatnonzero(pick)
        segs = segs.copy()
        segs[i, 1] = segs[i + 1, 1]
        segs = np.delete(segs, i + 1, axis=0)
    return segs


def unshare(segs: np.ndarray) -> np.ndarray:
    """Drop split points shared by two neighbours from both segments' final fits (a corner point
    belongs to neither line's interior)."""
    segs = segs.copy()
    if segs.shape[0] > 1:
        shared = segs[1:, 0] == segs[:-1, 1]
        segs[:-1, 1] -= shared
        segs[1:, 0] += shared
    return segs
