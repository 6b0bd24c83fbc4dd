"""``experiments.sim2real.sim2real``'s arguments checked before any work (``_checked_arguments`` and the
rates at the log's first scan): ``stride=0`` was an internal ZeroDivisionError, and 1.5, -1,
``max_scans=0``, ``duration=-1`` or nan, ``rate_hz`` 0 or 1e300, ``methods=[]`` or an unknown name read the
log and simulated before failing or comparing nothing; ``seeds=[]`` said "nothing to compare" after the
calibration. Each is now an LmsbenchError naming the argument, with the CLI's bounds."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import sim
from experiments.sim2real import sim2real
from lms200 import LmsbenchError, Record, Scan, write_log


def _room(stamp: float) -> Scan:
    b = np.deg2rad(np.arange(181) - 90.0) + 1e-9
    r = np.minimum(np.minimum(np.abs(3 / np.cos(b)), np.abs(3 / np.sin(b))), 7.9)
    return Scan(r, -np.pi / 2, math.radians(1.0), 0.0, 8.0, stamp=stamp)


@pytest.mark.parametrize("change, message", [
    ({"stride": 0}, "stride: must be an integer >= 1, got 0"),
    ({"stride": 1.5}, "stride: must be an integer >= 1, got 1.5"),
    ({"max_scans": 0}, "max_scans: must be an integer >= 1 (or None: every scan), got 0"),
    ({"seeds": []}, "seeds: no simulated world: give one seed or more"),
    ({"seeds": [1, 1]}, "seeds: seed(s) 1 given more than once"),
    ({"duration": -1.0}, "duration: must be a finite number in [0.1, 3600] s, got -1.0"),
    ({"duration": math.nan}, "duration: must be a finite number in [0.1, 3600] s, got nan"),
    ({"rate_hz": 1e300}, "rate_hz: 1e+300 scans/s is more than the sensor gives (75 scans/s at 1 deg)"),
    ({"fit_duration": -5.0}, "fit_duration: must be a finite number in [1, 600] s, got -5.0"),
    ({"fit_duration": math.nan}, "fit_duration: must be a finite number in [1, 600] s, got nan"),
    ({"methods": []}, "methods: no extraction method: give one or more (default: every built-in method)"),
    ({"methods": ["sensor", "nope"]},
     "unknown extraction method 'nope'; available: sensor, split_merge, iepf, hough, ransac"),
])
def test_a_bad_argument_is_refused_before_any_simulation(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                         change: dict, message: str) -> None:
    def no_simulation(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        raise AssertionError("simulated before the arguments were checked")

    monkeypatch.setattr(sim, "simulate_records", no_simulation)
    log = tmp_path / "room.clf"
    write_log(log, [Record(_room(0.2 * k)) for k in range(3)])
    kwargs = dict(world="office", seeds=[1], duration=1.0, stride=1,
                  sensor=sim.SensorConfig(interlaced=False, n_beams=181, resolution=math.radians(1.0)))
    with pytest.raises(LmsbenchError) as info:
        sim2real(log, **{**kwargs, **change})
    assert str(info.value) == message


def test_a_stride_past_the_log_is_its_error_alone(tmp_path: Path) -> None:
    """``sim2real LOG --stride 1000`` on a log of 40 scans said the early warning (only 1 real scans), then
    the calibration's error: a user error is one line, the error alone. The warning now follows the
    calibration, which refuses too few scans."""
    import warnings

    log = tmp_path / "room.clf"
    write_log(log, [Record(_room(0.2 * k)) for k in range(40)])
    with warnings.catch_warnings(record=True) as said, pytest.raises(LmsbenchError, match="calibrating needs at least 2"):
        warnings.simplefilter("always")
        sim2real(log, world="office", seeds=[1], duration=1.0, stride=1000)
    assert [str(w.message) for w in said] == []
