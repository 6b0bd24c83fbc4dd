"""The one spelling of extractor overrides: extractor.FIELD and extractor.METHOD.FIELD."""

from __future__ import annotations

import pytest

from experiments.overrides import OverrideError, extractor_overrides
from lms200 import LmsbenchError


def test_a_field_goes_to_every_extractor_that_has_it_and_a_method_field_to_one():
    got = extractor_overrides({"extractor.min_points": 10, "extractor.hough.rho_step": 0.01, "method": "x"},
                              ["sensor", "hough", "split_merge"])
    assert got["hough"] == {"min_points": 10, "rho_step": 0.01}
    assert got["sensor"]["min_points"] == 10 and got["split_merge"]["min_points"] == 10
    assert extractor_overrides({"extractor.k": 5}, ["sensor", "hough"]) == {"sensor": {"k": 5}}


def test_the_method_specific_value_wins_whatever_the_order():
    for flat in ({"extractor.min_points": 10, "extractor.sensor.min_points": 6},
                 {"extractor.sensor.min_points": 6, "extractor.min_points": 10}):
        got = extractor_overrides(flat, ["sensor", "iepf"])
        assert got == {"sensor": {"min_points": 6}, "iepf": {"min_points": 10}}


@pytest.mark.parametrize("flat, methods, match", [
    ({"extractor.kk": 5}, ["sensor"], "has a field 'kk'.*fields: .*ad_tau"),
    ({"extractor.hough.k": 5}, ["hough"], "hough has no field 'k'"),
    ({"extractor.hough.rho_step": 5}, ["sensor"], "not an extractor of this run; known: sensor"),
    ({"extractor.nosuch.k": 5}, ["sensor"], "not an extractor of this run; known: .*split_merge"),
])
def test_unknown_names_are_one_line_errors_listing_the_known_ones(flat, methods, match):
    with pytest.raises(OverrideError, match=match) as info:
        extractor_overrides(flat, methods)
    assert isinstance(info.value, LmsbenchError) and "\n" not in str(info.value)


def test_a_sweep_cell_ignores_another_methods_fields_but_checks_them():
    assert extractor_overrides({"extractor.hough.rho_step": 0.01}, ["sensor"], other_methods=True) == {}
    with pytest.raises(OverrideError, match="rho_stp"):
        extractor_overrides({"extractor.hough.rho_stp": 0.01}, ["sensor"], other_methods=True)


@pytest.mark.parametrize("name", ["sigma_r", "sigma_r_cm"])
def test_a_noise_field_takes_metres_or_auto_and_nothing_else(name):
    """sigma_r / sigma_r_cm are `float | str`: a number of metres or "auto" (the docs' promise), while the
    config, not the type check, refuses other words and bad numbers."""
    from experiments.compare import _check_types
    from features.registry import make_config

    for value in ("auto", 0.01):
        _check_types("sensor", {name: value})
        assert getattr(make_config("sensor", **{name: value}), name) == value
    for value in ("autox", -1.0):
        _check_types("sensor", {name: value})
        with pytest.raises(LmsbenchError, match=name):
            make_config("sensor", **{name: value})
    with pytest.raises(LmsbenchError, match="k must be a whole number"):
        _check_types("sensor", {"k": 2.5})


@pytest.mark.parametrize("method", ["split_merge", "iepf", "hough", "ransac"])
def test_an_unknown_corner_field_names_the_method_and_a_known_one_is_set(method):
    """A review: `--set extractor.METHOD.corners.FIELD=V` of a field the corner step does not have said
    "corners: has no field 'bogus' (its fields: ...)" (the config's check), naming no method, where an
    unknown field of the method itself names the key and the method. And a sweep cell of another method
    refused a known corner field of this one ("iepf has no field 'corners.sigma'"): it is ignored there,
    checked as its own method's is."""
    fields = "min_turn, max_gap_beams, max_distance, breakpoint_lambda, sigma"
    for other in (False, True):
        with pytest.raises(OverrideError) as info:
            extractor_overrides({f"extractor.{method}.corners.bogus": 1}, [method] if not other else ["sensor"],
                                other_methods=other)
        assert str(info.value) == (f"extractor.{method}.corners.bogus: {method}'s corner step (corners) has no field "
                                   f"'bogus'; its fields: {fields}")
    assert extractor_overrides({f"extractor.{method}.corners.sigma": 0.01}, [method]) == {method: {"corners": {"sigma": 0.01}}}
    assert extractor_overrides({f"extractor.{method}.corners.sigma": 0.01}, ["sensor"], other_methods=True) == {}  # old: refused


def test_set_names_a_slam_setting_and_where_it_goes_not_a_made_up_extractor_field() -> None:
    """`--set prealign.scan_velocity=false` was told "(write extractor.prealign.scan_velocity)", a field no
    extractor has; it names the SLAM section and --config now. The section list follows SlamConfig's."""
    import argparse
    import dataclasses

    from experiments.overrides import SLAM_SECTIONS, set_option
    from slam import SlamConfig

    nested = tuple(f.name for f in dataclasses.fields(SlamConfig) if dataclasses.is_dataclass(f.type) or
                   dataclasses.is_dataclass(getattr(SlamConfig(), f.name)))
    assert SLAM_SECTIONS == nested
    with pytest.raises(argparse.ArgumentTypeError, match=r"\(prealign\.scan_velocity is a SLAM setting, not an extractor's: "
                                                         r"give it to lmsbench slam in --config FILE\.yaml as "
                                                         r"'prealign: \{scan_velocity: false\}'\)$"):
        set_option("prealign.scan_velocity=false")
    with pytest.raises(argparse.ArgumentTypeError, match=r"\(write extractor\.sensor\.k\)$"):  # a method's name: as before
        set_option("sensor.k=3")
