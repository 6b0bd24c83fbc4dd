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
