"""``lmsbench slam`` reads a simulate folder's config.yaml ``sensor.interlaced`` to choose the de-skew
(``experiments.slamrun.simulated_interlaced``). A value that is no true / false (``"no"``, ``0``) was read as
"does not say": a run simulated without interlacing was de-skewed as an interlaced LMS200's, exit 0 (compare
refuses such a file). Now one line naming the file and the field, exit 2, before the log is read."""

from __future__ import annotations

from pathlib import Path

import pytest

from experiments.cli import main
from sim_folder import write_sim_folder


@pytest.mark.parametrize("value, shown", [('"no"', "'no'"), ("0", "0")])
def test_slam_refuses_an_interlaced_that_is_no_bool(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                    value: str, shown: str) -> None:
    from sim import simulate_records

    run = write_sim_folder(tmp_path / "run", simulate_records("office", seed=0, duration=0.5, rate_hz=10))
    (run / "config.yaml").write_text(f"world: office\nseed: 0\nsensor:\n  interlaced: {value}\n")
    rc = main(["slam", str(run), "--out", str(tmp_path / "out"), "--quiet", "--no-paper-baseline"])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.strip().splitlines() == [
        f"lmsbench slam: error: {run / 'config.yaml'}: sensor.interlaced: must be true or false (whether the scans were "
        f"simulated with the LMS200's interlaced sweeps, which decides their de-skew), got {shown}"]
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
