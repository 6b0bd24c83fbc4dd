"""A sweep whose ``kind: mysw:cell`` names a module in the current folder failed: "cannot import
mysw:cell: No module named 'mysw'" (it ran with PYTHONPATH=.), while ``compare --methods
myext:lines`` and an extract sweep's ``method: myext:lines`` import from the current folder (a
researcher's walkthrough, 2026-12-05). Both now go through one function
(``experiments.user_methods.import_named``), with one hint, and a local cluster's workers find
the module too."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import yaml

CELL = '''
def cell(params):
    return {"y": params["x"] * 10 + params["seed"]}
'''

HINT = "it must be importable from the current folder or PYTHONPATH"


def _sweep(folder: Path, kind: str) -> Path:
    (folder / "mysw.py").write_text(CELL)
    spec = folder / "s.yaml"
    spec.write_text(yaml.safe_dump({"name": "mine", "kind": kind, "grid": {"x": [1, 2]}, "seeds": [0, 1]}))
    return spec


def test_a_sweep_kind_in_the_current_folder_runs_in_process(tmp_path, monkeypatch, capsys):
    from experiments.cli import main

    _sweep(tmp_path, "mysw:cell")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "path", [p for p in sys.path if p not in ("", ".", str(tmp_path))])
    monkeypatch.delitem(sys.modules, "mysw", raising=False)
    assert main(["sweep", "s.yaml", "--inprocess", "--no-progress"]) == 0, capsys.readouterr().err
    table = pd.read_parquet(tmp_path / "results" / "sweeps" / "mine" / "results.parquet")
    assert list(table["y"]) == [10, 11, 20, 21] and set(table["status"]) == {"ok"}
    from experiments.user_methods import FolderFinder

    assert str(tmp_path) not in sys.path  # searched after every other place: shadows nothing installed
    assert [f.folder for f in sys.meta_path if isinstance(f, FolderFinder)].count(str(tmp_path)) == 1


def test_a_missing_sweep_kind_gives_the_extractors_hint(tmp_path, monkeypatch, capsys):
    from experiments.cli import main
    from experiments.sweep import SweepSpecError
    from experiments.sweep.cells import resolve_kind
    from experiments.user_methods import UserMethodError, ensure_method

    _sweep(tmp_path, "nomodule_here:cell")
    monkeypatch.chdir(tmp_path)
    assert main(["sweep", "s.yaml", "--inprocess", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.endswith("cell kind 'nomodule_here:cell': cannot import module 'nomodule_here' (No module named "
                        f"'nomodule_here'); {HINT}"), err
    with pytest.raises(UserMethodError, match=f"nomodule_here:f: cannot import module 'nomodule_here' .*; {HINT}$"):
        ensure_method("nomodule_here:f")
    with pytest.raises(SweepSpecError, match=r"^cell kind 'mysw:nosuch': module 'mysw' has no 'nosuch'$"):
        resolve_kind("mysw:nosuch")
    for kind in (":", ":cell", "mysw:", "mysw:a..b", ".mysw:cell", "mysw.:cell", "a..b:cell"):  # a part empty: "importing '' failed: ValueError: Empty module
        with pytest.raises(SweepSpecError, match=rf"^cell kind '{re.escape(kind)}': not MODULE:FUNCTION, a module and a "
                           r"callable of it \(e\.g\. myext:extract\)$"):  # name", "module 'mysw' has no ''", as an
            resolve_kind(kind)  # extractor's name was checked


def test_a_sweep_kind_in_the_current_folder_runs_on_the_local_cluster(tmp_path):
    """Through the installed `lmsbench` script (its path starts in .venv/bin, not the current
    folder, as a user's shell runs it), on its own local Dask cluster: the workers import the kind
    by name, from the same folder."""
    script = Path(sys.executable).parent / "lmsbench"
    if not script.is_file():
        pytest.skip("no lmsbench script beside this Python")
    _sweep(tmp_path, "mysw:cell")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    run = subprocess.run([str(script), "sweep", "s.yaml", "--workers", "1", "--no-progress"], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    table = pd.read_parquet(tmp_path / "results" / "sweeps" / "mine" / "results.parquet")
    assert list(table["y"]) == [10, 11, 20, 21] and set(table["status"]) == {"ok"}, table["error"].tolist()


def test_a_worker_that_cannot_import_the_kind_records_error_rows(tmp_path, monkeypatch):
    """The kind goes to a worker by name and is imported at its first call: a worker without the
    module (another folder: a remote scheduler's) gives each cell an error row with the hint. By
    reference, the worker's unpickler failed ("Failed to deserialize") and the sweep hung."""
    import pickle

    from experiments.sweep.cells import UserKind, resolve_kind, run_cell

    _sweep(tmp_path, "mysw:cell")
    monkeypatch.chdir(tmp_path)
    monkeypatch.delitem(sys.modules, "mysw", raising=False)
    fn = resolve_kind("mysw:cell")
    assert isinstance(fn, UserKind) and fn({"x": 3, "seed": 1}) == {"y": 31}
    sent = pickle.dumps(fn)
    assert b"mysw:cell" in sent
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    monkeypatch.delitem(sys.modules, "mysw")
    # a worker's own process: the driver's folder, searched by this process for lazy imports, is not by its
    monkeypatch.setattr(sys, "path", [p for p in sys.path if p != str(tmp_path)])
    for finder in [f for f in sys.meta_path if getattr(f, "folder", None) == str(tmp_path)]:
        sys.meta_path.remove(finder)  # in place: the list swapped back would drop finders added meanwhile (conftest)
    worker = pickle.loads(sent)  # no import yet
    row = run_cell("mysw:cell", {"x": 3, "seed": 1}, worker)
    assert row["status"] == "error" and row["error"].startswith(
        f"SweepSpecError: cell kind 'mysw:cell': cannot import module 'mysw' (No module named 'mysw'); {HINT}")
    monkeypatch.chdir(tmp_path)
    assert run_cell("mysw:cell", {"x": 3, "seed": 1}, pickle.loads(sent))["y"] == 31
