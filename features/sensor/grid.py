"""Constants of a scan's angle grid for the sensor method: the AD / slope window sums (eq. 4, 7)
and the Log-Hough log-cos template (eq. 5), built once per (k, beam step, subdivision) value."""

from __future__ import annotations

import threading
from functools import lru_cache

import numpy as np

from ..errors import ScanGeometryError
from ..noise_estimate import twice_cos
from .engine import B_ANGLE, B_COS, B_SIN, Grid

LOGCOS_FLOOR = float(np.log(1e-6))  # template value where |a - b| >= pi/2 (the beam cannot see the line)
MAX_TEMPLATE = 1 << 20  # most template entries (8 MB): beam steps finer than ~4 pi / 2^20 rad are refused
#: bytes of templates (and their phase rows) kept between calls: an lru_cache of 64 grids kept up
#: to 64 x 16 MB = 1 GiB for scans of many fine beam steps, and the third fine step in a process
#: ran out of a 50 MB address-space budget; at 20 MB, one of 10,000 fuzzed calls still did in a
#: long-lived process. A 361-beam 0.5 deg grid is 23 KB; steps finer than ~2.4e-5 rad (grids over
#: 8 MB) are rebuilt on each call (7-22 ms).
GRID_CACHE_BYTES = 8 << 20
GRID_CACHE_SIZE = 64  # most grids kept
_GRIDS: dict[tuple[int, float, int], Grid] = {}
_GRIDS_LOCK = threading.Lock()  # extract_many's threads share the cache


def grid_constants(k: int, increment: float, subdiv: int) -> Grid:
    """The Grid of window half-width ``k`` beams, beam step ``increment`` (rad) and Log-Hough
    angle step ``increment / subdiv``, built once and kept while the kept grids hold at most
    GRID_CACHE_BYTES (the oldest are dropped first; a larger one is built on every call).

    Raises:
        ScanGeometryError (a ValueError): when the angle step is so fine that the template would exceed MAX_TEMPLATE.
    """
    key = (k, increment, subdiv)
    grid = _GRIDS.get(key)
    if grid is None:
        grid = build_grid(k, increment, subdiv)
        size = grid_bytes(grid)
        if size <= GRID_CACHE_BYTES:
            with _GRIDS_LOCK:
                held = sum(grid_bytes(g) for g in _GRIDS.values())
                while _GRIDS and (held + size > GRID_CACHE_BYTES or len(_GRIDS) >= GRID_CACHE_SIZE):
                    held -= grid_bytes(_GRIDS.pop(next(iter(_GRIDS))))
                _GRIDS[key] = grid
    return grid


def grid_bytes(grid: Grid) -> int:
    """Bytes of a Grid's arrays (its template and phase rows)."""
    return int(grid.template.nbytes + grid.phases.nbytes)


@lru_cache(maxsize=64)
def window_sums(k: int, increment: float) -> tuple[float, float]:
    """(1 + 2 sum_{j=1..k} cos(jD), 2 sum_{m=1..k} sin(mD)) for half-width ``k`` and step D (rad):
    AD on a straight line (eq. 4) and the slope denominator (NOTES.md, eq. 7)."""
    j = np.arange(1, k + 1)
    return float(1.0 + 2.0 * np.cos(j * increment).sum()), float(2.0 * np.sin(j * increment).sum())


def build_grid(k: int, increment: float, subdiv: int) -> Grid:
    """The Grid of ``grid_constants``, built (not kept).

    The template holds log cos(m step) for |m| step up to just past pi/2 and is floored at
    LOGCOS_FLOOR; a lookup beyond its ends is clipped onto the floor, which is the value there.

    Raises:
        ScanGeometryError (a ValueError): when the angle step is so fine that the template would exceed MAX_TEMPLATE.
    """
    ad_line, two_sin_sum = window_sums(k, increment)
    step = increment / subdiv
    quarter_turn = 0.5 * np.pi / step if step > 0 else np.inf  # template steps up to pi/2
    if not 2 * (quarter_turn + 2) + 1 <= MAX_TEMPLATE:
        raise ScanGeometryError(
            f"angle_increment: {increment:.3g} rad / hough_subdiv {subdiv} is too fine a Log-Hough step for the "
            f"sensor method (its template would need {2 * (quarter_turn + 2) + 1:.3g} entries, at most "
            f"{MAX_TEMPLATE}); use a coarser scan or a smaller hough_subdiv"
        )
    half = int(np.ceil(quarter_turn)) + 1
    t = np.arange(-half, half + 1, dtype=np.float64)  # in place below: one template-sized array at a time
    t *= step
    beyond = np.abs(t) >= np.pi / 2
    np.cos(t, out=t)
    with np.errstate(divide="ignore", invalid="ignore"):
        np.log(t, out=t)
    t[beyond] = LOGCOS_FLOOR
    np.maximum(t, LOGCOS_FLOOR, out=t)
    t.setflags(write=False)
    return Grid(ad_line, two_sin_sum, float(step), half, t, twice_cos(increment), phase_rows(t, subdiv))


def phase_rows(template: np.ndarray, subdiv: int) -> np.ndarray:
    """The template split by index modulo ``subdiv`` and reversed: row r holds template[r + subdiv q]
    at column L - 1 - q (L = ceil(size / subdiv); the floor where r + subdiv q is past the end). The
    entries a run's consecutive beams look up at one angle, template[base - subdiv t], are then
    contiguous in t (``engine.band_search``)."""
    n = template.size
    cols = -(-n // subdiv)
    rows = np.full((subdiv, cols), LOGCOS_FLOOR)
    for r in range(subdiv):
        part = template[r::subdiv]
        rows[r, cols - part.size:] = part[::-1]
    rows.setflags(write=False)
    return rows


@lru_cache(maxsize=16)
def bearings_of(angle_min: float, increment: float, n: int) -> np.ndarray:
    """The (3, n) bearing table of n beams from ``angle_min`` in steps of ``increment`` (rad): rows
    ``engine.B_ANGLE`` (the bearings, as ``lms200.Scan.angles`` computes them), ``B_COS`` and
    ``B_SIN`` (their cosines and sines); read-only."""
    table = np.empty((3, n))
    table[B_ANGLE] = angle_min + np.arange(n) * increment
    table[B_COS] = np.cos(table[B_ANGLE])
    table[B_SIN] = np.sin(table[B_ANGLE])
    table.setflags(write=False)
    return table
