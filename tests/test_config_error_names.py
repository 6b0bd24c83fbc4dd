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
