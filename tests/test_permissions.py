"""Inputs and outputs the user cannot read or write (a permission fuzz round, run as a user
without root's powers): each is refused before any work, one line, exit 2, naming the path and
saying it cannot be read or written, and nothing of an earlier run is lost.

Root reads and writes every file whatever its mode (``os.access`` says yes, ``open`` succeeds),
so these tests skip when run as root: a mode of 000 or 0444 is no obstacle there. They were
checked as an unprivileged user (``su fuzzer -c 'python -m pytest tests/test_permissions.py'``).

What lets root pass over a file's mode is two capabilities, CAP_DAC_OVERRIDE and CAP_DAC_READ_SEARCH, not
the user id. So under root (as on CI) `test_the_permission_tests_pass_without_root_powers` runs this module
again in a child process whose capability bounding set lacks those two: a root process then obeys file
modes like any user (``open`` and ``os.access`` both refuse), and the tests below run there instead of
skipping."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
import yaml

from experiments.cli import main

CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH = 1, 2  # linux/capability.h
PR_CAPBSET_DROP = 24  # linux/prctl.h


def _capabilities(field: str) -> int | None:
    """This process's capability set `field` ("CapEff", "CapPrm", "CapBnd") as a bit mask, None off Linux."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith(field + ":"):
                return int(line.split()[1], 16)
    except OSError:
        pass
    return None


def _overrides_modes() -> bool:
    """Whether this process reads and writes files whatever their modes (root with its usual capabilities)."""
    eff = _capabilities("CapEff")
    if eff is None:
        return os.geteuid() == 0
    return bool(eff & (1 << CAP_DAC_OVERRIDE | 1 << CAP_DAC_READ_SEARCH))


OVERRIDES_MODES = _overrides_modes()
needs_modes_obeyed = pytest.mark.skipif(OVERRIDES_MODES, reason="this process reads and writes any file whatever its "
                                        "mode (root), so an unreadable or read-only path cannot be made for it; "
                                        "test_the_permission_tests_pass_without_root_powers runs them without it")


@pytest.fixture
def unlock(tmp_path):
    """Give back every mode a test took away (pytest removes its temporary folders afterwards)."""
    yield
    for root, dirs, files in os.walk(tmp_path):
        for d in dirs:
            os.chmod(os.path.join(root, d), 0o755)
    for root, dirs, files in os.walk(tmp_path):
        for f in files:
            os.chmod(os.path.join(root, f), 0o644)


def _error(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


@pytest.fixture(scope="module")
def sim(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("sim") / "run"
    assert main(["simulate", "--duration", "1", "--out", str(out), "--quiet"]) == 0
    return out


@pytest.fixture(scope="module")
def tables(tmp_path_factory) -> Path:
    """A tables folder Fig. 7 alone is drawn from (about a second)."""
    import pandas as pd

    t = tmp_path_factory.mktemp("tables")
    (t / "study.yaml").write_text(yaml.safe_dump({"world": "office", "seed": 0, "duration": 1.0, "resolved": {"sensor": {}}}))
    pd.DataFrame({"method": ["sensor"] * 3, "scan": [0, 1, 2], "time_ms": [0.05, 0.04, 0.06]}).to_parquet(
        t / "timing.parquet", index=False)
    return t


def _sweep(tmp_path: Path, k: list[int]) -> tuple[Path, Path]:
    spec = tmp_path / "s.yaml"
    spec.write_text(yaml.safe_dump({"name": "p", "kind": "extract", "fixed": {"duration": 0.5, "rate_hz": 4.0},
                                    "grid": {"extractor.k": k}}))
    return spec, tmp_path / "sw"


@needs_modes_obeyed
def test_figures_over_a_read_only_figure_is_refused_before_drawing(tables, tmp_path, capsys, unlock):
    out = tmp_path / "o"
    assert main(["figures", "--tables", str(tables), "--out", str(out)]) == 0
    record = (out / "figures.yaml").read_bytes()
    (out / "fig7_timing.png").chmod(0o444)
    capsys.readouterr()
    assert main(["figures", "--tables", str(tables), "--out", str(out)]) == 2
    # it drew up to that figure (the whole study first, without --tables), then said "o/fig7_timing.png: permission denied"
    assert _error(capsys) == (f"lmsbench figures: error: --out {out}: {out / 'fig7_timing.png'} cannot be written (permission "
                              "denied: read-only), and this run would replace it; make it writable (chmod u+w), or give "
                              "another folder")
    assert (out / "figures.yaml").read_bytes() == record


@needs_modes_obeyed
def test_a_read_only_tables_folder_of_a_study_is_refused_before_the_study(tmp_path, capsys, unlock, monkeypatch):
    import experiments.figures.study as study

    out = tmp_path / "o"
    (out / "tables").mkdir(parents=True)
    (out / "figures.yaml").write_text("command: lmsbench figures\n")
    (out / "tables").chmod(0o555)
    monkeypatch.setattr(study, "run_study", lambda *a, **k: pytest.fail("the study ran"))
    assert main(["figures", "--no-slam", "--duration", "1", "--out", str(out)]) == 2
    assert _error(capsys) == (f"lmsbench figures: error: --out {out}: {out / 'tables'} is not a writable folder, and this "
                              "run writes its outputs there; make it writable (chmod u+w), or give another folder")


@needs_modes_obeyed
def test_calibrate_does_not_replace_a_read_only_or_unreadable_sensor_yaml(sim, tmp_path, capsys, unlock):
    out = tmp_path / "s.yaml"
    text = "# lmsbench calibrate run\nnoise_sigma: 0.01\n"
    out.write_text(text)
    out.chmod(0o444)
    assert main(["calibrate", str(sim), "--max-scans", "5", "--fit-duration", "1", "--out", str(out)]) == 2
    assert _error(capsys) == f"lmsbench calibrate: error: --out {out} is read-only; make it writable (chmod u+w), or give a new file name"
    out.chmod(0o644)
    assert out.read_text() == text  # it was replaced, exit 0
    out.chmod(0o000)
    assert main(["calibrate", str(sim), "--max-scans", "5", "--fit-duration", "1", "--out", str(out)]) == 2
    assert _error(capsys) == (f"lmsbench calibrate: error: --out {out} cannot be read (permission denied), so calibrate "
                              "cannot tell whether it wrote it; make it readable, or give a new file name")


@needs_modes_obeyed
def test_an_unreadable_record_in_out_is_said_unreadable(sim, tmp_path, capsys, unlock):
    out = tmp_path / "o"
    assert main(["compare", str(sim), "--methods", "sensor", "--out", str(out)]) == 0
    (out / "config.yaml").chmod(0o000)
    capsys.readouterr()
    assert main(["compare", str(sim), "--methods", "sensor", "--out", str(out)]) == 2
    # it said "holds config.yaml, which this run would replace but no earlier lmsbench compare run wrote"
    assert _error(capsys) == (f"lmsbench compare: error: --out {out}: {out / 'config.yaml'} cannot be read (permission "
                              "denied), so this run cannot tell whether an earlier lmsbench compare run wrote it; make it "
                              "readable, or give another folder")


@needs_modes_obeyed
@pytest.mark.parametrize("mode", [0o000, 0o600])
def test_an_unreadable_simulate_folder_is_named(sim, tmp_path, capsys, unlock, mode):
    import shutil

    run = tmp_path / "run"
    shutil.copytree(sim, run)
    run.chmod(mode)
    assert main(["info", str(run)]) == 2
    # it named the hidden marker: "run/.simulate-unfinished: permission denied"
    assert _error(capsys) == f"lmsbench info: error: {run}: folder cannot be read (permission denied: its files cannot be opened)"


@needs_modes_obeyed
def test_a_resumed_sweep_whose_cells_are_read_only_is_refused_before_computing(tmp_path, capsys, unlock, monkeypatch):
    import experiments.sweep.runner as runner

    spec, out = _sweep(tmp_path, [3, 5])
    assert main(["sweep", str(spec), "--inprocess", "--no-progress", "--out", str(out)]) == 0
    cells = sorted((out / "cells").glob("*.parquet"))
    cells[0].unlink()
    (out / "cells").chmod(0o555)
    monkeypatch.setattr(runner, "run_cell", lambda *a, **k: pytest.fail("a cell was computed"))
    capsys.readouterr()
    assert main(["sweep", str(spec), "--inprocess", "--no-progress", "--out", str(out)]) == 2
    # it computed the cell, then said "sw/cells/.KEY.xxxx.tmp: permission denied"
    assert _error(capsys) == (f"lmsbench sweep: error: {out / 'cells'}: the sweep's folder of finished cells is not "
                              "writable, and cells are left to compute; make it writable (chmod u+w) to resume the sweep")


@needs_modes_obeyed
def test_a_resumed_sweep_with_an_unreadable_cell_keeps_it(tmp_path, capsys, unlock):
    spec, out = _sweep(tmp_path, [3, 5])
    assert main(["sweep", str(spec), "--inprocess", "--no-progress", "--out", str(out)]) == 0
    cell = sorted((out / "cells").glob("*.parquet"))[0]
    kept = cell.read_bytes()
    cell.chmod(0o000)
    capsys.readouterr()
    assert main(["sweep", str(spec), "--inprocess", "--no-progress", "--out", str(out)]) == 2
    # it warned "1 cell file cannot be read as a finished cell (damaged ...); computed again" and replaced it, exit 0
    assert _error(capsys) == (f"lmsbench sweep: error: {cell}: a finished cell's file that cannot be read (permission "
                              "denied); make it readable (chmod u+r) to resume the sweep with it, or remove it to compute "
                              "the cell again")
    cell.chmod(0o644)
    assert cell.read_bytes() == kept


@needs_modes_obeyed
def test_unreadable_tables_and_sweep_folders_are_named(tables, tmp_path, capsys, unlock):
    import shutil

    t = tmp_path / "t"
    shutil.copytree(tables, t)
    t.chmod(0o000)
    assert main(["figures", "--tables", str(t), "--out", str(tmp_path / "o")]) == 2
    # it said "t/study.yaml: permission denied" (0o000) or "no study.yaml and tables" (0o100)
    assert _error(capsys) == (f"lmsbench figures: error: --tables {t}: folder cannot be read (permission denied), so the "
                              "tables in it cannot be read; make it readable (chmod u+rx)")
    t.chmod(0o755)
    sw = tmp_path / "sw"
    sw.mkdir()
    (sw / "results.parquet").write_bytes(b"")
    (sw / "results.parquet").chmod(0o000)
    assert main(["figures", "--tables", str(t), "--sweep", str(sw), "--out", str(tmp_path / "o")]) == 2
    # it said "not a Parquet table (PermissionError)"
    assert _error(capsys) == f"lmsbench figures: error: --sweep {sw / 'results.parquet'}: cannot be read (permission denied)"
    sw.chmod(0o000)
    assert main(["figures", "--tables", str(t), "--sweep", str(sw), "--out", str(tmp_path / "o")]) == 2
    assert _error(capsys) == (f"lmsbench figures: error: --sweep {sw}: folder cannot be read (permission denied), so the "
                              "sweep's results in it cannot be read; make it readable (chmod u+rx)")


def _drop_mode_override() -> None:
    """In the child before exec: take CAP_DAC_OVERRIDE and CAP_DAC_READ_SEARCH out of the bounding set, so the
    program it runs (as root) gets neither and obeys file modes."""
    import ctypes

    libc = ctypes.CDLL(None, use_errno=True)
    for cap in (CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH):
        if libc.prctl(PR_CAPBSET_DROP, cap, 0, 0, 0) != 0:
            raise OSError(ctypes.get_errno(), f"prctl(PR_CAPBSET_DROP, {cap})")


@pytest.mark.skipif(not OVERRIDES_MODES or os.geteuid() != 0 or _capabilities("CapBnd") is None,
                    reason="only root on Linux passes over file modes here (the tests above run themselves)")
def test_the_permission_tests_pass_without_root_powers() -> None:
    import subprocess
    import sys

    tests = [name for name in globals() if name.startswith("test_") and name != "test_the_permission_tests_pass_without_root_powers"]
    child = subprocess.run([sys.executable, "-m", "pytest", "-q", "-n", "0", "-p", "no:cacheprovider", "-rs", __file__],
                           capture_output=True, text=True, preexec_fn=_drop_mode_override, cwd=Path(__file__).parents[1],
                           timeout=600)
    assert child.returncode == 0, child.stdout[-3000:] + child.stderr[-3000:]
    # every test of this module ran there and passed; none but this one skipped
    import re

    summary = re.match(r"(\d+) passed, 1 skipped in ", child.stdout.splitlines()[-1])
    assert summary and int(summary[1]) >= len(tests), child.stdout[-2000:]
