"""A baseline's breakpoint_lambda not above the scan's beam step (features.registry.step_problem).

The adaptive breakpoint distance r sin(step) / sin(lambda - step) (Borges & Aldon 2004) has no
meaning there: split_merge, iepf, hough and ransac found no line on a 2-deg scan at
breakpoint_lambda 1 deg (the distance negative: no two neighbours connect), silently, and at a
step equal to lambda the distance was infinite. Now ``extract`` / ``extract_many`` / ``compare``
refuse the config with a ConfigError naming breakpoint_lambda, the step and what to set."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from experiments.cli import main
from features import extract, extract_many
from features.errors import ConfigError
from lms200 import Record, Scan, write_log
from lms200.errors import LmsbenchError

BASELINES = ["split_merge", "iepf", "hough", "ransac"]


def _room(step_deg: float, stamp: float = 0.0) -> Scan:
    """A scan of a 6 m square room from its middle, over 180 deg at ``step_deg``."""
    n = int(round(180 / step_deg)) + 1
    b = np.deg2rad(np.arange(n) * step_deg - 90.0) + 1e-9
    r = np.minimum(np.minimum(np.abs(3 / np.cos(b)), np.abs(3 / np.sin(b))), 7.9)
    return Scan(r, -np.pi / 2, np.deg2rad(step_deg), 0.0, 8.0, stamp=stamp)


def _message(method: str, step_deg: float, lam_deg: float, fit_deg: float, where: str = "scan") -> str:
    return (f"{where}: the beam step {step_deg:g} deg is not below {method}'s breakpoint_lambda {lam_deg:g} deg "
            f"({math.radians(lam_deg):.6g} rad): the adaptive breakpoint distance r sin(step) / "
            "sin(breakpoint_lambda - step) (Borges & Aldon) has no meaning there (at the step every beam connects, beyond it none: no line); "
            f"set breakpoint_lambda above the step, e.g. {math.radians(fit_deg):.6g} rad ({fit_deg:g} deg)")


@pytest.mark.parametrize("method", BASELINES)
@pytest.mark.parametrize(("step_deg", "lam_deg", "fit_deg"), [(2.0, 1.0, 20.0), (1.0, 1.0, 10.0), (12.0, 10.0, 90.0)])
def test_extract_refuses_a_breakpoint_lambda_not_above_the_step(method: str, step_deg: float, lam_deg: float,
                                                                  fit_deg: float) -> None:
    """Old: 0 lines (2 deg at 1 deg, 12 deg at the default 10 deg), or every beam connected (1 deg at 1 deg)."""
    scan = _room(step_deg)
    with pytest.raises(ConfigError) as info:
        extract(scan, method, breakpoint_lambda=math.radians(lam_deg))
    assert str(info.value) == _message(method, step_deg, lam_deg, fit_deg)
    assert isinstance(info.value, ValueError) and isinstance(info.value, LmsbenchError)
    with pytest.raises(ConfigError) as many:
        extract_many([_room(step_deg, 0.0), _room(step_deg, 1.0)], method, breakpoint_lambda=math.radians(lam_deg))
    assert str(many.value) == str(info.value)


@pytest.mark.parametrize("method", BASELINES)
def test_a_breakpoint_lambda_above_the_step_finds_the_rooms_walls(method: str) -> None:
    """The suggested value works: the three walls of the room, on a 2-deg scan (default 10 deg) and a
    1-deg one at 1.5 deg."""
    assert len(extract(_room(2.0), method).lines) == 3
    assert len(extract(_room(1.0), method, breakpoint_lambda=math.radians(1.5)).lines) == 3
    assert [len(fs.lines) for fs in extract_many([_room(2.0, 0.0), _room(2.0, 1.0)], method)] == [3, 3]


def test_compare_says_it_in_one_line_before_any_work(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`lmsbench compare LOG --set extractor.split_merge.breakpoint_lambda=<1 deg>` on a 1-deg log ran,
    exit 0, every split_merge line count 0 (2 deg: 0; at 1 deg exactly: no breakpoint at all)."""
    log = tmp_path / "room.clf"
    write_log(log, [Record(_room(2.0, float(k))) for k in range(3)])
    out = tmp_path / "out"
    rc = main(["compare", str(log), "--methods", "split_merge", "--set",
               f"extractor.split_merge.breakpoint_lambda={math.radians(1.0)!r}", "--out", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.strip().splitlines() == [f"lmsbench compare: error: {_message('split_merge', 2.0, 1.0, 20.0, f'{log}: scan 0')}"]
    assert not out.exists() or not any(out.iterdir())


def test_compare_refuses_it_before_any_method_runs(tmp_path: Path) -> None:
    """compare (the API, which calls the methods' run directly, not extract) says it at the first scan."""
    from experiments.compare import compare

    log = tmp_path / "room.clf"
    write_log(log, [Record(_room(2.0, float(k))) for k in range(3)])
    with pytest.raises(ConfigError) as info:
        compare([str(log)], ["split_merge", "hough"], params={"hough": {"breakpoint_lambda": math.radians(1.5)}})
    assert str(info.value) == _message("hough", 2.0, 1.5, 20.0, "room.clf: scan 0")
