"""Records a command reads beside its inputs and outputs, of any size (a fuzzing round): a simulate
folder's config.yaml (compare read 3 GB whole: MemoryError; 35 MB parsed for minutes; a pipe in its
place was passed over, the default sensor scoring the scans, exit 0), the same file as slam's
de-skew hint, and the records `--out` folders are told by (`simulate --out DIR` read a 3 GB
DIR/config.yaml whole, 3.2 GB of memory and over 30 s, to find it was not its own)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from lms200 import LmsbenchError

from sim_folder import write_sim_folder


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    from sim import simulate_records

    return write_sim_folder(tmp_path_factory.mktemp("sim"), simulate_records("office", seed=0, duration=1.0,
                                                                              rate_hz=3.0), world_seed=0)


def _copy(folder: Path, tmp_path: Path) -> Path:
    run = tmp_path / "run"
    run.mkdir()
    for p in folder.iterdir():
        (run / p.name).write_bytes(p.read_bytes())
    return run


def _sparse(path: Path, size: int) -> None:
    with path.open("wb") as fh:
        fh.truncate(size)


def test_compare_refuses_a_simulate_config_beyond_a_configs_size_unread(folder, tmp_path, capsys,
                                                                         monkeypatch) -> None:
    import experiments.progress
    from experiments.cli import main
    from lms200.yamlio import MAX_YAML_BYTES

    run = _copy(folder, tmp_path)
    _sparse(run / "config.yaml", MAX_YAML_BYTES + 1)
    # before any work: it was refused after the kernels' warm-up (on a fresh checkout a 1-2 min compile; a review)
    monkeypatch.setattr(experiments.progress, "warm_up_kernels", lambda *a, **k: pytest.fail("warmed up first"))
    assert main(["compare", str(run), "--methods", "sensor", "--out", str(tmp_path / "out"), "--no-progress"]) == 2
    # old: read whole, then "not a simulate config (...)"; then "... a config or sweep file may hold (refused unread;
    # they are a few KB: a sweep's grid lists the values of each parameter, not every cell)", of a file no sweep's
    assert capsys.readouterr().err == (
        f"lmsbench compare: error: {run / 'config.yaml'}: 1,048,577 bytes, more than the 1,048,576 a simulate folder's "
        "config.yaml may hold (refused unread; lmsbench simulate writes one of a few KB at most)\n")


def test_compare_refuses_a_simulate_config_that_is_a_pipe(folder, tmp_path, capsys) -> None:
    from experiments.cli import main

    run = _copy(folder, tmp_path)
    os.mkfifo(run / "config.yaml")
    out = tmp_path / "out"
    assert main(["compare", str(run), "--methods", "sensor", "--out", str(out), "--no-progress"]) == 2  # old: 0
    assert capsys.readouterr().err == (f"lmsbench compare: error: {run / 'config.yaml'}: a simulate config must be a "
                                       "regular file, not a device or pipe\n")
    assert not out.exists()


def test_slams_deskew_hint_reads_no_config_beyond_a_configs_size(folder, tmp_path, monkeypatch) -> None:
    from experiments.slamrun import simulated_interlaced
    from lms200.yamlio import MAX_YAML_BYTES

    run = _copy(folder, tmp_path)
    (run / "config.yaml").write_text("sensor:\n  interlaced: false\n")
    assert simulated_interlaced(run) is False
    _sparse(run / "config.yaml", MAX_YAML_BYTES + 1)
    read: list[Path] = []
    real = Path.read_text
    monkeypatch.setattr(Path, "read_text", lambda self, *a, **k: read.append(self) or real(self, *a, **k))
    with pytest.raises(LmsbenchError, match=r"config\.yaml: 1,048,577 bytes, more than the 1,048,576 a simulate "
                                            r"folder's config\.yaml may hold"):
        simulated_interlaced(run)  # passed over, the run de-skewed as the LMS200's whatever the file said (a review)
    assert read == []  # old: read whole (3 GB: as much memory and 56 s), then passed over as damaged
    (run / "config.yaml").unlink()
    os.mkfifo(run / "config.yaml")
    with pytest.raises(LmsbenchError, match="a simulate config must be a regular file"):
        simulated_interlaced(run)


def test_an_out_folders_record_beyond_its_bound_is_no_record_and_is_not_read(tmp_path, capsys) -> None:
    from experiments.cli import main
    from experiments.options import MAX_RECORD_YAML_BYTES

    out = tmp_path / "out"
    out.mkdir()
    record = "world: office\nseed: 0\nduration: 1.0\nsensor: {}\n"  # what simulate's recogniser looks for
    (out / "config.yaml").write_text(record + "#" * (MAX_RECORD_YAML_BYTES - len(record) + 1) + "\n")
    assert main(["simulate", "--duration", "1", "--quiet", "--out", str(out)]) == 2  # old: parsed 4 MB, taken as its own
    assert capsys.readouterr().err == (f"lmsbench simulate: error: --out {out}: holds config.yaml, which this run would "
                                       "replace but no earlier lmsbench simulate run wrote; give a new or empty folder\n")
