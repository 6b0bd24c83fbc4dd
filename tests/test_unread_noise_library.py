"""The library calls behind compare and SLAM say a range-noise field the run's scans do not read,
once per run, as ``features.extract`` says it per call (``compare(..., params={"sensor":
{"sigma_r": ...}})`` on cm-mode scans, and ``run_slam`` with ``extractor_params: {sigma_r: ...}``,
were silent: they pass a config, not its fields, to the extractors)."""

from __future__ import annotations

import warnings

import pytest

from features.registry import UnreadNoiseWarning
from lms200.errors import LmsbenchWarning


@pytest.fixture(scope="module")
def cm_records():
    from sim import SensorConfig, simulate_records

    recs = simulate_records("office", seed=3, duration=2.0, rate_hz=5, sensor=SensorConfig(units="cm", noise_sigma=0.008))
    assert len(recs) == 10 and recs[0].scan.range_max == pytest.approx(81.83)
    return recs


def _said(call) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")  # every warning counted, not once per place
        call()
    return [str(w.message) for w in caught if issubclass(w.category, LmsbenchWarning)]


def test_compare_says_a_field_no_scan_reads_once_per_run(cm_records):
    from experiments.compare import Source, compare

    src = Source.from_records(cm_records, None, name="cm")
    said = _said(lambda: compare([src], ["sensor"], params={"sensor": {"sigma_r": 0.02}}))
    assert said == ["sensor: sigma_r=0.02 is not used: sigma_r applies to mm-mode scans (range_max <= 10 m); "
                    "the scans of cm are cm mode (range_max 81.83 m): set sigma_r_cm"]  # once, not per scan (10)
    assert _said(lambda: compare([Source.from_records(cm_records, None, name="cm")], ["sensor"],
                                 params={"sensor": {"sigma_r_cm": 0.02}})) == []


@pytest.mark.parametrize("preset", ["paper", "default"])
def test_run_slam_says_a_field_no_scan_reads_once_per_run(cm_records, preset):
    from slam import SlamConfig, run_slam

    config = SlamConfig.from_dict({"preset": preset, "extractor_params": {"sigma_r": 0.02}})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        run_slam(cm_records, config)
    said = [w for w in caught if issubclass(w.category, LmsbenchWarning)]
    assert [str(w.message) for w in said] == [
        "sensor: sigma_r=0.02 is not used: sigma_r applies to mm-mode scans (range_max <= 10 m); "
        "the scans are cm mode (range_max 81.83 m): set sigma_r_cm"]
    assert said[0].category is UnreadNoiseWarning and said[0].filename == __file__  # the caller's line
    read = SlamConfig.from_dict({"preset": preset, "extractor_params": {"sigma_r_cm": 0.02}})
    assert _said(lambda: run_slam(cm_records, read)) == []
