"""Compiled helpers of the batch kernels (``extract_batch`` of each engine): the concatenated rows
of ``features.types.Lines`` and ``Corners`` of many scans, grown as scans are added, and each
scan's offsets into them.

numba's disk cache does not notice an edit here in the engines that call these functions (it
watches the file that defines a cached function only): after changing this module, delete the
engines' caches (``__pycache__/*.nbi``, ``*.nbc`` under ``features/``).
"""

from __future__ import annotations

import numpy as np

from .jit import inline_kernel, kernel


@inline_kernel
def grow(a, rows):  # noqa: ANN001, ANN201
    """``a`` (N, c) with room for at least ``rows`` rows (doubling), the first N rows kept."""
    if rows <= a.shape[0]:
        return a
    out = np.empty((max(rows, 2 * a.shape[0]), a.shape[1]), a.dtype)
    out[: a.shape[0]] = a
    return out


@kernel
def new_rows(n_scans):  # noqa: ANN001, ANN201
    """Empty rows for ``n_scans`` scans: (line values, line beams, corner values, corner beams,
    line offsets (S + 1,), corner offsets (S + 1,))."""
    return (np.empty((8 * n_scans + 8, 10)), np.empty((8 * n_scans + 8, 3), np.int64), np.empty((2 * n_scans + 2, 3)),
            np.empty((2 * n_scans + 2, 3), np.int64), np.zeros(n_scans + 1, np.int64), np.zeros(n_scans + 1, np.int64))


@inline_kernel
def append_rows(rows, s, scan_rows):  # noqa: ANN001, ANN201
    """``rows`` with scan ``s``'s (line values, line beams, corner values, corner beams) added."""
    lv, lb, cv, cb, line_off, corner_off = rows
    slv, slb, scv, scb = scan_rows
    nl, nc = line_off[s], corner_off[s]
    ml, mc = nl + slv.shape[0], nc + scv.shape[0]
    lv, lb, cv, cb = grow(lv, ml), grow(lb, ml), grow(cv, mc), grow(cb, mc)
    lv[nl:ml] = slv
    lb[nl:ml] = slb
    cv[nc:mc] = scv
    cb[nc:mc] = scb
    line_off[s + 1] = ml
    corner_off[s + 1] = mc
    return lv, lb, cv, cb, line_off, corner_off


@kernel
def finish_rows(rows):  # noqa: ANN001, ANN201
    """The rows cut to what the scans filled, and the offsets."""
    lv, lb, cv, cb, line_off, corner_off = rows
    nl, nc = line_off[-1], corner_off[-1]
    return lv[:nl], lb[:nl], cv[:nc], cb[:nc], line_off, corner_off
