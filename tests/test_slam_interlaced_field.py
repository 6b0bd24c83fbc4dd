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


@pytest.mark.parametrize("content, reason", [
    (b"[1, 2]\n", r"expected a mapping of world, seed, duration, sensor, \.\.\., got list"),
    (b"", r"expected a mapping .*got an empty file"),
    (b"world: office\n\xff\n", r"'utf-8' codec can't decode byte 0xff"),
    (b"sensor: {interlaced: [\n", r"line 2, column 1: "),
])
def test_slam_refuses_a_config_yaml_it_cannot_read(tmp_path: Path, content: bytes, reason: str) -> None:
    """A config.yaml that is no YAML mapping (a list, empty, not UTF-8, cut) was passed over as "does not
    say", and the run de-skewed as an interlaced LMS200's whatever the folder was simulated with, exit 0
    (fuzzing, 2026-12-07; compare refuses such a file)."""
    from experiments.slamrun import simulated_interlaced
    from lms200 import LmsbenchError

    (tmp_path / "scans.clf").write_text("")
    (tmp_path / "config.yaml").write_bytes(content)
    with pytest.raises(LmsbenchError, match=rf"^{tmp_path / 'config.yaml'}: not a simulate config \({reason}.*\); its "
                                            r"sensor.interlaced decides the scans' de-skew: restore it, or simulate the folder again$"):
        simulated_interlaced(tmp_path)
    (tmp_path / "config.yaml").write_text("world: office\nsensor: {n_beams: 361}\n")
    assert simulated_interlaced(tmp_path) is None  # a sensor that does not say: as before
