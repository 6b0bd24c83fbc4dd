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


def _message(method: str, step_deg: float, lam_deg: float, fit_deg: float, where: str = "scan",
             field: str = "breakpoint_lambda") -> str:
    """registry.step_problem's text, for the lines' field or the corner step's (``corners.breakpoint_lambda``)."""
    what = "no corner" if field.startswith("corners.") else "no line"
    return (f"{where}: the beam step {step_deg:g} deg is not below {method}'s {field} {lam_deg:g} deg "
            f"({math.radians(lam_deg):.6g} rad): the adaptive breakpoint distance r sin(step) / "
            f"sin(breakpoint_lambda - step) (Borges & Aldon) has no meaning there (at the step every beam connects, beyond it none: {what}); "
            f"set {field} above the step, e.g. {math.radians(fit_deg):.6g} rad ({fit_deg:g} deg)")


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


def _corner_message(method: str, step_deg: float, lam_deg: float, fit_deg: float, where: str = "scan") -> str:
    return _message(method, step_deg, lam_deg, fit_deg, where, field="corners.breakpoint_lambda")


@pytest.mark.parametrize("method", BASELINES)
def test_the_corner_steps_own_breakpoint_lambda_is_checked_the_same_way(method: str) -> None:
    """The shared corner step (``CornerConfig.breakpoint_lambda``) connects two lines' facing ends within the
    same adaptive distance: at 1.5 deg on a 2-deg scan every baseline found the room's 3 walls and 0 of its 2
    corners, silently. Now refused as the lines' lambda is, naming corners.breakpoint_lambda; 10 deg finds both."""
    from features.baselines.common import CornerConfig

    scan = _room(2.0)
    with pytest.raises(ConfigError) as info:
        extract(scan, method, corners=CornerConfig(breakpoint_lambda=math.radians(1.5)))
    assert str(info.value) == _corner_message(method, 2.0, 1.5, 20.0)
    with pytest.raises(ConfigError) as many:
        extract_many([_room(2.0, 0.0), _room(2.0, 1.0)], method, corners=CornerConfig(breakpoint_lambda=math.radians(1.5)))
    assert str(many.value) == str(info.value)
    fs = extract(scan, method, corners=CornerConfig(breakpoint_lambda=math.radians(10.0)))
    assert (len(fs.lines), len(fs.corners)) == (3, 2)


def test_figures_refuses_a_log_its_panels_method_cannot_segment_before_any_work(tmp_path: Path,
                                                                               capsys: pytest.CaptureFixture[str]) -> None:
    """`lmsbench figures --methods split_merge --log` a 12-deg log drew Fig. 9's real-log panels with no
    line (fig9_intel_lines.csv empty), exit 0, after the whole study; the panels' extract_timed called
    the method's run without extract's check. Now compare's message, before any work."""
    log = tmp_path / "coarse.clf"
    write_log(log, [Record(_room(12.0, float(k))) for k in range(3)])
    out = tmp_path / "figs"
    rc = main(["figures", "--methods", "split_merge", "--log", str(log), "--no-slam", "--duration", "2", "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.strip().splitlines() == [f"lmsbench figures: error: {_message('split_merge', 12.0, 10.0, 90.0, f'{log}: scan 0')}"]
    assert not out.exists()


def test_extract_timed_refuses_it_naming_the_scan() -> None:
    """experiments.evaluate.extract_timed (Fig. 9's panels) ran the method's run directly: no line, silently."""
    from experiments.evaluate import extract_timed

    with pytest.raises(ConfigError) as info:
        extract_timed([_room(2.0, 0.0), _room(12.0, 1.0)], "iepf")
    assert str(info.value) == _message("iepf", 12.0, 10.0, 90.0, "scan 1")


def test_sim2real_refuses_it_before_any_simulation(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """sim2real (given a sensor, so no calibration) read the log, then simulated its worlds and compared,
    and only compare refused the log's 12-deg step, minutes later at the defaults (the scene statistics'
    split_merge found no line on it, silently). Now refused at the log's first scan, compare's message."""
    import sim
    from experiments.sim2real import sim2real

    def no_simulation(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        raise AssertionError("simulated before the log's beam step was checked")

    monkeypatch.setattr(sim, "simulate_records", no_simulation)
    log = tmp_path / "coarse.clf"
    write_log(log, [Record(_room(12.0, float(k))) for k in range(3)])
    with pytest.raises(ConfigError) as info:
        sim2real(log, world="office", seeds=[1], duration=1.0, stride=1, sensor=sim.SensorConfig(interlaced=False))
    assert str(info.value) == _message("split_merge", 12.0, 10.0, 90.0, f"{log}: scan 0")


def test_the_corners_breakpoint_lambda_is_set_from_the_command_line(tmp_path, capsys):
    """After the corners' own breakpoint_lambda was checked against the beam step, nothing on the command
    line could set it (`--set extractor.split_merge.corners.breakpoint_lambda=...` "has no field",
    `corners={...}` "must be a CornerConfig"): a baseline on a 12-degree log was refused whatever was set
    (a review). Both spellings set it now; a field the corner step does not have is named."""
    from experiments.cli import main
    from lms200 import Record, Scan
    from lms200.carmen import write_carmen

    step = np.deg2rad(12.0)
    scans = [Scan(np.full(16, 3.0), -np.deg2rad(90.0), step, 0.0, 30.0, float(k)) for k in range(3)]
    log = tmp_path / "coarse.clf"
    write_carmen(log, [Record(s) for s in scans])
    base = ["compare", str(log), "--methods", "split_merge", "--sigma", "0.01", "--no-progress",
            "--set", "extractor.split_merge.breakpoint_lambda=0.5"]
    assert main(base + ["--out", str(tmp_path / "a")]) == 2
    assert "corners.breakpoint_lambda 10 deg" in capsys.readouterr().err
    assert main(base + ["--set", "extractor.split_merge.corners.breakpoint_lambda=0.5", "--out", str(tmp_path / "b")]) == 0
    capsys.readouterr()
    assert main(base + ["--set", "extractor.split_merge.corners={breakpoint_lambda: 0.5}", "--out", str(tmp_path / "c")]) == 0
    capsys.readouterr()
    assert main(base + ["--set", "extractor.split_merge.corners.bogus=1", "--out", str(tmp_path / "d")]) == 2
    # named as an unknown field of the method is (it said "corners: has no field 'bogus' (its fields: ...)", no method)
    assert capsys.readouterr().err == ("lmsbench compare: error: extractor.split_merge.corners.bogus: split_merge's "
                                       "corner step (corners) has no field 'bogus'; its fields: min_turn, max_gap_beams, "
                                       "max_distance, breakpoint_lambda, sigma\n")
