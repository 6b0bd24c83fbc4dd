"""A config value error names the method and, for the corner step, the step: `--set extractor.min_points=-1`
goes to every method that has the field, and "min_points: must be ..." did not say whose bound was broken
(the sensor method's is 3 .. 16384 beams, the baselines' >= 2); a baseline's "sigma: ..." from its corner
step read as the method's own sigma."""

from __future__ import annotations

import pytest

from experiments.compare import resolved_configs
from features.errors import ConfigError
from features.registry import make_config
from lms200 import LmsbenchError


@pytest.mark.parametrize(("params", "message"), [
    ({"iepf": {"min_points": -1}}, "iepf: min_points: must be an integer >= 2, got -1"),
    ({"sensor": {"min_points": -1}, "iepf": {"min_points": -1}},
     "sensor: min_points: must be a number in [3, 16384] beams, got -1"),
    ({"split_merge": {"corners": {"sigma": -1}}},
     "split_merge: corners.sigma: must be a range noise std in [1e-06, 1000] m, got -1"),
])
def test_a_config_value_error_names_the_method_and_the_corner_step(params: dict, message: str) -> None:
    with pytest.raises(ConfigError) as err:
        resolved_configs(["sensor", "split_merge", "iepf"], params)
    assert str(err.value) == message
    assert isinstance(err.value, LmsbenchError) and isinstance(err.value, ValueError)


def test_a_corner_step_error_from_make_config_names_the_step() -> None:
    with pytest.raises(ConfigError, match=r"^corners\.max_distance: "):
        make_config("iepf", corners={"max_distance": -5.0})
    assert make_config("iepf", corners={"sigma": 0.02}).corners.sigma == 0.02  # a good value is taken


@pytest.mark.parametrize(("method", "field", "odd", "plain"), [
    ("hough", "alpha_step", "Fraction(1, 50)", 0.02),
    ("hough", "breakpoint_lambda", "Fraction(1, 5)", 0.2),
    ("ransac", "breakpoint_lambda", "Fraction(1, 5)", 0.2),
    ("ransac", "hypotheses", "np.uint8(40)", 40),
    ("split_merge", "max_skip", "np.int8(3)", 3),
])
def test_a_config_taken_with_an_odd_number_type_extracts_as_with_the_plain_number(method, field, odd, plain) -> None:
    """A value of a valid number type other than int / float passed the checks and then failed at the
    first scan: hough's and ransac's numpy arithmetic ran in the type given (np.uint8(40) hypotheses:
    OverflowError, 361 out of bounds for uint8; a Fraction angle: object arrays, a TypeError from
    np.cos / np.sin). The fields are now kept as plain ints and floats, and the features are those
    of the plain number."""
    from fractions import Fraction

    import numpy as np

    from features import extract
    from lms200 import Scan

    value = eval(odd, {"Fraction": Fraction, "np": np})
    cfg = make_config(method, **{field: value})
    assert type(getattr(cfg, field)) is type(plain) and getattr(cfg, field) == float(value)
    b = np.deg2rad(0.5) * (np.arange(361) - 180)
    scan = Scan(np.minimum(3.0 / np.maximum(np.abs(np.cos(b)), 1e-3), 2.5 / np.maximum(np.abs(np.sin(b)), 1e-3)),
                float(b[0]), float(np.deg2rad(0.5)), 0.0, 8.183)
    fs = extract(scan, method, config=cfg)
    assert len(fs.lines) >= 3 and fs == extract(scan, method, config=make_config(method, **{field: float(value) if isinstance(plain, float) else plain}))


HUGE = "Fraction(10**400)"  # beyond float64: float() raised OverflowError
TINY = "Fraction(1, 10**400)"  # nonzero, rounds to 0.0 in float64


@pytest.mark.parametrize(("method", "params", "message"), [
    ("split_merge", {"split_threshold": HUGE}, r"^split_threshold: must be a width in \[0.0001, 1\] m, got Fraction\(1000"),
    ("hough", {"max_lines": HUGE}, r"^max_lines: must be an integer >= 1, got Fraction\(1000"),
    ("ransac", {"max_failures": HUGE}, r"^max_failures: must be an integer >= 1 and <= \d+, got Fraction\(1000"),
    ("iepf", {"sigma_fit": HUGE}, r"^sigma_fit: must be a range noise std in \[1e-06, 1000\] m, got Fraction\(1000"),
    ("split_merge", {"merge_sigmas": TINY}, r"^merge_sigmas: must be 0 \(off\) or a number in \[1, 100\] std, got Fraction\(1, 1000"),
    ("split_merge", {"merge_sigmas": "np.longdouble('1e-400')"}, r"^merge_sigmas: .*, got np.longdouble\('1e-400'\)$"),
    ("split_merge", {"merge_sigmas": "Fraction(1, 3)"}, r"^merge_sigmas: .* std, got Fraction\(1, 3\)$"),
    ("split_merge", {"merge_rms": TINY}, r"^merge_rms: is nonzero but rounds to 0 in float64 .*, got Fraction\(1, 1000"),
    ("iepf", {"corners": {"max_distance": TINY}}, r"^corners\.max_distance: is nonzero but rounds to 0 in float64 "),
])
def test_a_field_checked_after_the_shared_ones_sees_and_quotes_the_value_given(method, params, message) -> None:
    """The number fields were made plain floats at the end of the shared checks, before a method's
    own later checks: a huge Fraction raised OverflowError (not ConfigError), a tiny one ran as 0.0
    (off), and a message quoted the rounded value (0.3333333333333333 for Fraction(1, 3))."""
    from fractions import Fraction

    import numpy as np

    names = {"Fraction": Fraction, "np": np}
    given = {k: ({f: eval(x, names) for f, x in v.items()} if isinstance(v, dict) else eval(v, names))
             for k, v in params.items()}
    with pytest.raises(ConfigError, match=message):
        make_config(method, **given)


def test_a_corner_field_given_as_a_fraction_is_kept_as_the_nearest_float() -> None:
    from fractions import Fraction

    corners = make_config("split_merge", corners={"sigma": Fraction(1, 100), "max_gap_beams": __import__("numpy").int16(4)}).corners
    assert type(corners.sigma) is float and corners.sigma == 0.01
    assert type(corners.max_gap_beams) is int and corners.max_gap_beams == 4
