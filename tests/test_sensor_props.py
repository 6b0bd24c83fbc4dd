"""Property-based tests: any ranges array a Scan accepts gives a well-formed FeatureSet, never an
exception (all-inf, all-nan, one valid beam, zeros, huge values, any resolution and field of view)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from features import FeatureSet, extract
from lms200 import Scan

SPECIAL = [0.0, np.inf, np.nan, 1e-300, 1e300, 1e-3, 80.0, 8.183]


@st.composite
def scans(draw: st.DrawFn) -> Scan:
    n = draw(st.integers(1, 450))
    kind = draw(st.sampled_from(["special", "smooth", "mixed", "constant"]))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    if kind == "special":
        r = rng.choice(SPECIAL, n)
    elif kind == "constant":
        r = np.full(n, draw(st.sampled_from(SPECIAL + [2.5])))
    else:
        # piecewise walls with noise, then sprinkled special values
        r = np.repeat(rng.uniform(0.1, 20.0, 1 + n // 30), 30)[:n] + rng.normal(0, 0.01, n)
        r = np.abs(r)
        if kind == "mixed":
            hits = rng.random(n) < 0.1
            r[hits] = rng.choice(SPECIAL, hits.sum())
    inc = draw(st.sampled_from([np.deg2rad(0.25), np.deg2rad(0.5), np.deg2rad(1.0), 2 * np.pi / 360, 1e-4, 0.3]))
    amin = draw(st.floats(-np.pi, np.pi))
    r = r[: int(2 * np.pi / inc) + 1]  # a Scan spans at most a full turn
    range_max = draw(st.sampled_from([8.183, 81.83, 1e308]))
    return Scan(r, amin, inc, 0.0, range_max)


@settings(max_examples=300, deadline=None)
@given(scans(), st.integers(1, 12))
def test_never_raises_and_output_is_well_formed(scan: Scan, k: int) -> None:
    fs = extract(scan, method="sensor", k=k)
    assert isinstance(fs, FeatureSet)
    n = len(scan)
    for line in fs.lines:
        assert np.isfinite([line.rho, line.alpha, *line.start, *line.end]).all()
        assert line.rho >= 0 and -np.pi < line.alpha <= np.pi
        assert 0 <= line.first <= line.last < n
        assert line.cov.shape == (2, 2) and np.isfinite(line.cov).all()
        assert line.n_points <= line.last - line.first + 1
    for c in fs.corners:
        assert np.isfinite([c.x, c.y]).all() and 0 < c.angle < np.pi
        assert 0 <= c.lines[0] < c.lines[1] < len(fs.lines)
        assert 0 <= c.index < n


def test_merged_lines_near_the_origin_keep_rho_non_negative() -> None:
    """The information-weighted merge of two pieces of a line near the sensor could give rho < 0
    (the fused (rho, alpha) crossed the origin): 237 of 3,000 scans of uniform random ranges
    (0-10 m, 100-3,000 beams) had such a line, e.g. rho = -0.5742 m below. Now the same line is
    reported as (-rho, alpha + pi), with the covariance's off-diagonal negated. (Seeds 21 and 203
    were here too until the merge stopped at depth jumps: their pieces no longer merge; 435 and
    712 are the next seeds whose one line is such a fusion.)"""
    want_rho = {115: [0.09959437841423124], 230: [0.5741846243811728], 435: [0.40403227598860536],
                712: [0.6679779658475677]}
    for seed, rho_abs in want_rho.items():
        rng = np.random.default_rng(seed)
        n = int(rng.integers(100, 400))
        inc = float(np.exp(rng.uniform(np.log(3e-5), np.log(2 * np.pi / n))))
        scan = Scan(rng.uniform(0.0, 10.0, n), float(rng.uniform(-np.pi, np.pi)), inc, 0.02, 81.83)
        lines = extract(scan).lines
        np.testing.assert_allclose(lines.rho, rho_abs, rtol=1e-9)  # was -rho
        assert np.all((lines.alpha > -np.pi) & (lines.alpha <= np.pi))
        a = lines.alpha
        for ends in (lines.start, lines.end):  # the endpoints lie on the reported line
            np.testing.assert_allclose(ends[:, 0] * np.cos(a) + ends[:, 1] * np.sin(a), lines.rho, atol=1e-12)
        cov = lines.cov
        assert np.all(cov[:, 0, 0] > 0) and np.all(cov[:, 0, 0] * cov[:, 1, 1] > cov[:, 0, 1] ** 2)
