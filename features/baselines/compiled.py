"""The numba backend of ``split_merge`` and ``iepf``: the compiled kernels of ``kernels`` behind the
same ``(scan, config) -> FeatureSet`` call as the numpy reference. Imported (and numba with it)
only when the backend is first used."""

from __future__ import annotations

import numpy as np

from lms200 import Scan

from ..types import Corner, FeatureSet, new_line
from . import kernels as kn


def extract_numba(scan: Scan, cfg, method: str, chord: bool) -> FeatureSet:  # noqa: ANN001
    """Lines and corners of ``scan`` (sensor frame) by split-and-merge (``chord=False``) or
    iterative end-point fit (``chord=True``) with the config ``cfg`` of that method."""
    ranges = np.ascontiguousarray(scan.ranges, dtype=np.float64)
    bearings = np.ascontiguousarray(scan.angles, dtype=np.float64)
    rho, alpha, n, first, last, p0, p1, cov = kn.segment_lines(
        ranges, bearings, np.ascontiguousarray(scan.valid), float(scan.angle_increment), float(cfg.sigma),
        float(np.deg2rad(cfg.breakpoint_lambda_deg)), float(cfg.split_threshold), float(cfg.merge_rms),
        float(cfg.min_points), float(cfg.min_length), float(cfg.max_skip), float(cfg.runs_z), bool(chord),
    )
    rho_l, alpha_l = rho.tolist(), alpha.tolist()
    n_l = n.astype(np.int64).tolist()
    first_l, last_l = first.tolist(), last.tolist()
    start = list(map(tuple, p0.tolist()))
    end = list(map(tuple, p1.tolist()))
    lines = [
        new_line(rho_l[m], alpha_l[m], start[m], end[m], first_l[m], last_l[m], cov[m], n_l[m])
        for m in range(len(rho_l))
    ]
    found: list[Corner] = []
    if len(lines) > 1:
        cc = cfg.corners
        cf, ci = kn.corners(
            rho, alpha, first, last, p0, p1, float(scan.angle_increment), float(np.deg2rad(cc.min_turn_deg)),
            float(cc.max_gap_beams), float(cc.max_distance), float(np.deg2rad(cc.lambda_deg)), float(cc.sigma),
        )
        found = [Corner(x, y, a, index, (k, k + 1)) for (x, y, a), (index, k) in zip(cf.tolist(), ci.tolist())]
    return FeatureSet(lines, found, method)
