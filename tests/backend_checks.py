"""Backend equality for the extractor tests: a compiled backend gives its numpy reference's
FeatureSet (same lines, beams and corners; values within TOL)."""

from __future__ import annotations

import numpy as np
import pytest

from features import FeatureSet

TOL = 1e-9


def assert_same(ref: FeatureSet, got: FeatureSet, label: str, method: str = "sensor") -> None:
    """Same line count, beams, point counts and corners; geometry and covariance within TOL."""
    assert len(got.lines) == len(ref.lines), label
    for m, (a, b) in enumerate(zip(ref.lines, got.lines)):
        where = f"{label} line {m}"
        assert (b.first, b.last, b.n_points) == (a.first, a.last, a.n_points), where
        assert b.rho == pytest.approx(a.rho, abs=TOL), where
        assert b.alpha == pytest.approx(a.alpha, abs=TOL), where
        np.testing.assert_allclose(b.start, a.start, rtol=0, atol=TOL, err_msg=where)
        np.testing.assert_allclose(b.end, a.end, rtol=0, atol=TOL, err_msg=where)
        np.testing.assert_allclose(b.cov, a.cov, rtol=1e-9, atol=1e-15, err_msg=where)
        assert isinstance(b.first, int) and isinstance(b.rho, float), where
    assert len(got.corners) == len(ref.corners), label
    for a, b in zip(ref.corners, got.corners):
        assert (b.index, b.lines) == (a.index, a.lines), label
        np.testing.assert_allclose((b.x, b.y, b.angle), (a.x, a.y, a.angle), rtol=0, atol=TOL, err_msg=label)
    assert got.method == ref.method == method
