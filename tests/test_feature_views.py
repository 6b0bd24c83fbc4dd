"""A FeatureSet cannot be changed through what its lines and corners hand out: ``fs.lines[0].cov``
was a writable view of its arrays (``fs.lines[0].cov[0, 0] = 5`` changed the FeatureSet,
silently), and so were the columns ``fs.lines.rho``, ``fs.corners.x``, ...)."""

from __future__ import annotations

import numpy as np
import pytest

from features import extract
from sim import simulate_records


@pytest.fixture(scope="module")
def fs():
    scan = simulate_records("office", seed=0, duration=0.5, rate_hz=2)[0].scan
    out = extract(scan, "split_merge")
    assert len(out.lines) >= 2 and len(out.corners) >= 1
    return out


def test_a_lines_cov_cannot_be_written_through(fs):
    before = fs.lines.values.copy()
    cov = fs.lines[0].cov
    with pytest.raises(ValueError, match="read-only"):
        cov[0, 0] = 5.0
    np.testing.assert_array_equal(fs.lines.values, before)
    mine = cov.copy()  # a copy is the caller's to change
    mine[0, 0] = 5.0
    assert fs.lines.values[0, 6] == before[0, 6] != 5.0
    assert np.shares_memory(cov, fs.lines.values)  # still a view: no copy per line


@pytest.mark.parametrize("name", ["rho", "alpha", "start", "end", "first", "last", "n_points", "cov"])
def test_the_lines_columns_cannot_be_written_through(fs, name):
    before = (fs.lines.values.copy(), fs.lines.beams.copy())
    column = getattr(fs.lines, name)
    with pytest.raises(ValueError, match="read-only"):
        column[0] = 7
    np.testing.assert_array_equal(fs.lines.values, before[0])
    np.testing.assert_array_equal(fs.lines.beams, before[1])


@pytest.mark.parametrize("name", ["x", "y", "angle", "beam", "line_pair"])
def test_the_corners_columns_cannot_be_written_through(fs, name):
    before = (fs.corners.values.copy(), fs.corners.beams.copy())
    with pytest.raises(ValueError, match="read-only"):
        getattr(fs.corners, name)[0] = 7
    np.testing.assert_array_equal(fs.corners.values, before[0])
    np.testing.assert_array_equal(fs.corners.beams, before[1])


def test_a_corner_and_a_lines_other_fields_are_values(fs):
    """The rest of a Line and every field of a Corner are Python numbers and tuples, not views."""
    line, corner = fs.lines[0], fs.corners[0]
    assert all(type(v) is float for v in (line.rho, line.alpha, *line.start, *line.end))
    assert all(type(v) is int for v in (line.first, line.last, line.n_points))
    assert all(type(v) is float for v in (corner.x, corner.y, corner.angle)) and type(corner.index) is int
    assert type(corner.lines) is tuple and all(type(v) is int for v in corner.lines)
    assert fs.lines.values.flags.writeable  # the storage itself stays writable (the extractors fill it)
