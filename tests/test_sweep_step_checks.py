"""A sweep's cells checked against their simulated sensor before any cell runs (``experiments.sweep.kinds``):
a baseline's breakpoint_lambda not below the sensor's beam step (extract and slam cells), and what
``run_slam`` refuses at its first scan (``slam.run.check_first_scan``: a min_line_points or stride beyond the
sensor's beams). Each such cell failed after its simulation, the sweep exit 1; the rest ran."""

from __future__ import annotations

import pytest

from experiments.sweep import SweepSpec, SweepSpecError
from experiments.sweep.runner import check_spec

ONE_DEG = 0.017453292519943295
STEP = ("the beam step 1 deg is not below split_merge's breakpoint_lambda 1 deg (0.0174533 rad): the adaptive "
        "breakpoint distance r sin(step) / sin(breakpoint_lambda - step) (Borges & Aldon) has no meaning there (at the "
        "step every beam connects, beyond it none: no line); set breakpoint_lambda above the step, e.g. 0.174533 rad (10 deg)")


def test_an_extract_sweep_cell_whose_lambda_is_not_below_the_sensors_step_is_refused() -> None:
    """Old: the cell at lambda = 1 deg on a 1-deg sensor failed after simulating ("1 of 2 cells failed")."""
    spec = SweepSpec.from_dict({"name": "lam", "kind": "extract",
                                "fixed": {"method": "split_merge", "duration": 1.0, "rate_hz": 2.0,
                                          "sensor.resolution": ONE_DEG, "sensor.n_beams": 181},
                                "grid": {"extractor.breakpoint_lambda": [0.3, ONE_DEG]}, "seeds": [0]})
    with pytest.raises(SweepSpecError) as info:
        check_spec(spec)
    assert str(info.value) == (f"extractor split_merge {{'breakpoint_lambda': {ONE_DEG!r}}}: the simulated scans "
                               f"({{'n_beams': 181, 'resolution': {ONE_DEG!r}}}): " + STEP)
    ok = SweepSpec.from_dict({"name": "lam", "kind": "extract", "fixed": {"method": "split_merge"},
                              "grid": {"extractor.breakpoint_lambda": [0.3, ONE_DEG]}, "seeds": [0]})
    check_spec(ok)  # the default sensor's 0.5 deg step is below both


@pytest.mark.parametrize("fixed, message", [
    ({"slam.observations.min_line_points": 400},
     "observations.min_line_points: 400 is more than the first scan's 361 beams: no line of these scans has that many "
     "points, so the map would hold no line; at most 361 for these scans"),
    ({"slam.alignment.stride": 31},
     "alignment.stride: 31 keeps 12 of the first scan's 361 beams, fewer than the 13 points the scan matcher needs; at "
     "most 30 for these scans"),
    ({"slam.extractor": "split_merge", "extractor.breakpoint_lambda": ONE_DEG, "sensor.resolution": ONE_DEG,
      "sensor.n_beams": 181},
     f"the simulated scans ({{'n_beams': 181, 'resolution': {ONE_DEG!r}}}): " + STEP),
])
def test_a_slam_sweep_cell_run_slam_would_refuse_at_its_first_scan_is_refused(fixed: dict, message: str) -> None:
    spec = SweepSpec.from_dict({"name": "s", "kind": "slam", "fixed": {"duration": 2.0, **fixed}, "seeds": [0]})
    with pytest.raises(SweepSpecError) as info:
        check_spec(spec)
    assert str(info.value).endswith(": " + message), str(info.value)
    assert str(info.value).startswith("slam {")


def test_an_extract_sweep_over_a_corner_steps_field_is_checked() -> None:
    """A grid over extractor.METHOD.corners.FIELD (settable since the corners' breakpoint_lambda is checked
    against the step) made the checks' key hold a dict: "internal error: TypeError: unhashable type: 'dict'"
    (the last read). It is checked like any field, and refused on the sensor's step in the corners' words."""
    grid = {"extractor.split_merge.corners.breakpoint_lambda": [0.3, ONE_DEG]}
    ok = SweepSpec.from_dict({"name": "c", "kind": "extract", "fixed": {"method": "split_merge"}, "grid": grid,
                              "seeds": [0]})
    check_spec(ok)  # the default sensor's 0.5 deg step is below both
    coarse = SweepSpec.from_dict({"name": "c", "kind": "extract",
                                  "fixed": {"method": "split_merge", "sensor.resolution": ONE_DEG, "sensor.n_beams": 181},
                                  "grid": grid, "seeds": [0]})
    with pytest.raises(SweepSpecError, match=r"^extractor split_merge \{'corners': \{'breakpoint_lambda': 0.01745.*"
                                             r"not below split_merge's corners.breakpoint_lambda 1 deg"):
        check_spec(coarse)
