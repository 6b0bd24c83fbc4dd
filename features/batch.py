"""Helpers of ``features.extract_many``: the one geometry of a batch of scans, the stacked ranges,
and the per-scan FeatureSets cut from a batch kernel's concatenated rows."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from lms200 import Scan

from .errors import ScanGeometryError, not_a_scan
from .types import BatchFeatureSet, FeatureSet


def common_geometry(scans: Sequence[Scan]) -> Scan:
    """The first scan, after checking that every scan has its geometry: beam count, angle_min,
    angle_increment, range_min and range_max. Raises ValueError naming the first that differs,
    and ``ScanTypeError`` naming the first item that is not a Scan."""
    first = scans[0]
    if not isinstance(first, Scan):
        raise not_a_scan(first, "scans[0]")
    key = (first.ranges.size, first.angle_min, first.angle_increment, first.range_min, first.range_max)
    for i, s in enumerate(scans):  # ranges.size, not len(s): a Python call a scan fewer
        if not isinstance(s, Scan):
            raise not_a_scan(s, f"scans[{i}]")
        if (s.ranges.size, s.angle_min, s.angle_increment, s.range_min, s.range_max) != key:
            raise ScanGeometryError(
                f"scans[{i}]: geometry (beams, angle_min, angle_increment, range_min, range_max) = "
                f"{(len(s), s.angle_min, s.angle_increment, s.range_min, s.range_max)} differs from scans[0]'s {key}; "
                "extract_many needs scans of one geometry (group them first)"
            )
    return first


def stacked_ranges(scans: Sequence[Scan]) -> np.ndarray:
    """(S, n) C-contiguous ranges of the scans (m), which have n beams each; read-only, like a Scan's
    ranges, so that the batch kernels' per-scan rows have the types of a single call's ranges and
    reuse its compiled code instead of compiling the whole extractor a second time."""
    out = np.concatenate([s.ranges for s in scans]).reshape(len(scans), -1)
    out.flags.writeable = False
    return out


def split_rows(lv: np.ndarray, lb: np.ndarray, cv: np.ndarray, cb: np.ndarray, line_off: np.ndarray,
               corner_off: np.ndarray, method: str) -> list[FeatureSet]:
    """One FeatureSet per scan from a batch's concatenated line and corner rows and their offsets
    (``BatchFeatureSet``: each scan's rows are cut from the batch's when first read)."""
    rows = (lv, lb, cv, cb, line_off.tolist(), corner_off.tolist())
    cut = BatchFeatureSet.cut
    return [cut(rows, s, method) for s in range(len(line_off) - 1)]
