"""What ``lmsbench slam`` and ``run_slam`` check at the first scan (``slam.run.check_first_scan``).

A config that cannot work on the run's scans is refused at the first scan, as the log is read:
``alignment.stride`` (the default preset), ``observations.min_line_points`` above the scan's beams
(no line observed, silently) and a baseline extractor's breakpoint_lambda not below the beam step.
``lmsbench slam`` refused the stride and the step only after reading the whole log (22 s for a
100,000-scan log), the step with the default preset only after the whole run."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from experiments.cli import main
from lms200 import Record, Scan, write_log
from slam import SlamConfig, run_slam
from slam.run import SlamInputError


def _room(step_deg: float, stamp: float) -> Scan:
    """A 6 m square room seen from its middle over 180 deg at ``step_deg``."""
    n = int(round(180 / step_deg)) + 1
    b = np.deg2rad(np.arange(n) * step_deg - 90.0) + 1e-9
    r = np.minimum(np.minimum(np.abs(3 / np.cos(b)), np.abs(3 / np.sin(b))), 7.9)
    return Scan(r, -np.pi / 2, np.deg2rad(step_deg), 0.0, 8.0, stamp=stamp)


def _log_damaged_after(tmp_path: Path, step_deg: float, scans: int = 3) -> Path:
    """A log of ``scans`` good scans and then a malformed line: a command that reads the whole log
    before checking the first scan says the malformed line, one that checks at the first scan does not."""
    log = tmp_path / "room.clf"
    write_log(log, [Record(_room(step_deg, 0.2 * k)) for k in range(scans)])
    with log.open("a") as f:
        f.write("ROBOTLASER1 garbage\n")
    return log


STEP_MESSAGE = ("{log}: scan 0: the beam step 12 deg is not below split_merge's breakpoint_lambda 10 deg (0.174533 rad): "
                "the adaptive breakpoint distance r sin(step) / sin(breakpoint_lambda - step) (Borges & Aldon) has no "
                "meaning there (at the step every beam connects, beyond it none: no line); set breakpoint_lambda above "
                "the step, e.g. 1.5708 rad (90 deg)")


@pytest.mark.parametrize("preset", ["paper", "default"])
def test_slam_refuses_the_extractors_step_at_the_first_scan(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                           preset: str) -> None:
    """Old: the log read whole first (here: its malformed last line said instead), then the paper preset's
    first batch (or, default preset, the keyframes' extraction after the whole run) refused 'scan: ...'."""
    log = _log_damaged_after(tmp_path, 12.0)
    config = tmp_path / "c.yaml"
    config.write_text("alignment: {stride: 1}\n")  # 16 beams: the default stride 3 keeps too few (its own refusal)
    given = ["--config", str(config)] if preset == "default" else []  # the paper preset reads no alignment (refused)
    rc = main(["slam", str(log), "--extractor", "split_merge", "--preset", preset, *given,
               "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.strip().splitlines()[-1] == "lmsbench slam: error: " + STEP_MESSAGE.format(log=log)


def test_slam_refuses_a_stride_at_the_first_scan_not_after_the_read(tmp_path: Path,
                                                                    capsys: pytest.CaptureFixture[str]) -> None:
    log = _log_damaged_after(tmp_path, 12.0)
    rc = main(["slam", str(log), "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.strip().splitlines()[-1] == ("lmsbench slam: error: alignment.stride: 3 keeps 6 of the first scan's 16 "
                                            "beams, fewer than the 13 points the scan matcher needs; at most 1 for "
                                            "these scans")


@pytest.mark.parametrize("preset, found", [("paper", "the filter would observe no line"),
                                           ("default", "the map would hold no line")])
def test_min_line_points_above_the_scans_beams_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                          preset: str, found: str) -> None:
    """observations.min_line_points up to 16,384 was taken on 181-beam scans: every line dropped, no
    observation (the paper preset ran on its motion model alone), exit 0. Now refused at the first scan;
    the scan's own beam count is taken."""
    message = (f"observations.min_line_points: 182 is more than the first scan's 181 beams: no line of these scans "
               f"has that many points, so {found}; at most 181 for these scans")
    records = [Record(_room(1.0, 0.2 * k)) for k in range(3)]
    with pytest.raises(SlamInputError) as info:
        run_slam(records, SlamConfig(preset=preset, observations={"min_line_points": 182}))
    assert str(info.value) == message
    assert len(run_slam(records, SlamConfig(preset=preset, observations={"min_line_points": 181})).trajectory) == 3
    log = _log_damaged_after(tmp_path, 1.0)
    config = tmp_path / "c.yaml"
    config.write_text(f"preset: {preset}\nobservations: {{min_line_points: 182}}\n")
    rc = main(["slam", str(log), "--config", str(config), "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.strip().splitlines()[-1] == f"lmsbench slam: error: {message}"


def test_a_scan_too_short_to_match_is_not_refused_for_the_default_min_line_points() -> None:
    """A 7-beam log with nothing set was refused by the default min_line_points 8 ("at most 7 for these
    scans", a field the user never gave; a review): such a scan is too short for the scan matcher at any
    setting and runs to its "not healthy" warning, as the stride check leaves it."""
    records = [Record(_room(30.0, 0.2 * k)) for k in range(3)]
    assert records[0].scan.ranges.size == 7
    result = run_slam(records, SlamConfig())
    assert len(result.trajectory) == 3 and not result.diagnostics["healthy"]


def test_run_slam_refuses_the_step_at_its_first_record() -> None:
    """run_slam (the library) names the record; with the default preset it refused only after the whole run."""
    from features.errors import ConfigError

    records = [Record(_room(12.0, 0.2 * k)) for k in range(3)]
    with pytest.raises(ConfigError) as info:
        run_slam(records, SlamConfig(extractor="iepf", alignment={"stride": 1}))
    assert str(info.value).startswith("records[0]: the beam step 12 deg is not below iepf's breakpoint_lambda 10 deg")
