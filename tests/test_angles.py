"""The project's one angle wrap (issue 16): ``lms200.angles``. Checked against an independent
reference (exact rational arithmetic on the doubles) and for the same bits in its three forms."""

from __future__ import annotations

import math
import re
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from features.jit import wrap_one
from lms200.angles import TWO_PI, wrap

ROOT = Path(__file__).resolve().parents[1]


def exact_wrap(a: float) -> Fraction:
    """a - 2 pi k in (-pi, pi] with pi the double math.pi, computed exactly (no rounding)."""
    x, p = Fraction(a), Fraction(math.pi)
    k = math.floor((p - x) / (2 * p))  # pi - x = 2 pi k + r, 0 <= r < 2 pi
    return x + 2 * p * k


def angles() -> np.ndarray:
    rng = np.random.default_rng(16)
    multiples = np.arange(-40, 41) * math.pi
    return np.concatenate([rng.uniform(-100.0, 100.0, 3000), rng.normal(0.0, 1e-15, 200), multiples,
                           np.nextafter(multiples, np.inf), np.nextafter(multiples, -np.inf),
                           [0.0, -0.0, 5e-324, -5e-324, 1e6, -1e6]])


def test_wrap_is_within_one_rounding_of_the_exact_wrap_and_in_the_half_open_interval():
    a = angles()
    w = wrap(a)
    assert np.all(w > -math.pi) and np.all(w <= math.pi)
    for x, y in zip(a, w):
        err = abs(Fraction(float(y)) - exact_wrap(float(x)))
        # one rounding of pi - x, of the remainder and of pi - r: a few ulps of the larger operand;
        # an exact wrap landing on -pi is moved to +pi (2 pi away, the same angle)
        bound = Fraction(4 * math.ulp(max(abs(float(x)), math.pi)))
        assert err <= bound or abs(err - 2 * Fraction(math.pi)) <= bound, (x, y)


def test_wrap_moves_angles_already_inside_by_at_most_the_rounding_of_pi_minus_a():
    inside = np.array([0.0, 0.1, -0.1, 1.0, -3.0, 3.0, math.pi, 1e-300])
    np.testing.assert_allclose(wrap(inside), inside, rtol=0.0, atol=math.ulp(math.pi))
    assert wrap(-math.pi) == math.pi and wrap(3 * math.pi) == math.pi
    assert wrap(np.nextafter(-math.pi, 0.0)) == math.pi  # pi - a rounds to 2 pi: the same angle, as +pi


def test_float_array_and_compiled_forms_give_the_same_bits():
    a = angles()
    w = wrap(a)
    assert np.array_equal(np.array([wrap(float(x)) for x in a]), w)
    assert np.array_equal(np.array([wrap_one(float(x)) for x in a]), w)
    assert type(wrap(1)) is float and type(wrap(np.float64(7.0))) is float
    assert isinstance(wrap([1.0, 7.0]), np.ndarray) and wrap(np.array(7.0)) == 7.0 - TWO_PI


# wrap-like formulas that would be a second wrap: a remainder by 2 pi, atan2 of sin and cos, a
# mod of pi shifted by pi, a function of its own named wrap (the forms the project's four wraps
# and six inline ones had)
SECOND_WRAP = re.compile(r"remainder\([^)]*(2 \* (math|np)\.pi|tau|TWO_PI)"
                         r"|atan2\((np|math)\.sin\((.+?)\), (np|math)\.cos\(\5\)\)"
                         r"|\+ (np|math)\.pi\) % |mod\([^)]*\+ (np|math)\.pi, 2"
                         r"|^\s*def _?wrap\w*\(")


@pytest.mark.parametrize("package", ["lms200", "sim", "features", "slam", "experiments"])
def test_no_package_wraps_angles_by_a_formula_of_its_own(package):
    found = [f"{path.relative_to(ROOT)}:{n}" for path in sorted((ROOT / package).rglob("*.py"))
             for n, line in enumerate(path.read_text().splitlines(), 1)
             if SECOND_WRAP.search(line) and path.name != "angles.py"]
    assert not found, f"angles wrapped outside lms200.angles (use wrap / wrap_one): {found}"
