"""A pipe in a sweep's cells/ (a fuzzing round): resuming the sweep opened it to read its footer and
waited for ever (`lmsbench sweep` hung). It is no finished cell: computed again, with the one warning
a damaged cell file gets, its file replaced."""

from __future__ import annotations

import os
import threading
import warnings
from pathlib import Path

from experiments.sweep.store import CellStore


def test_a_pipe_among_the_cell_files_is_a_damaged_cell_not_a_hang(tmp_path: Path) -> None:
    store = CellStore(tmp_path)
    store.write("aaaa", {"cell": "aaaa", "status": "ok", "x": 1.0})
    os.mkfifo(store.path("bbbb"))
    found: list = []

    def look() -> None:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            found.append((store.done(), store.status("bbbb"), [str(w.message) for w in caught]))

    worker = threading.Thread(target=look, daemon=True)
    worker.start()
    worker.join(10)
    assert not worker.is_alive()  # old: blocked opening the pipe
    done, status, said = found[0]
    assert done == {"aaaa"} and status is None
    assert said == [f"{store.cells}: 1 cell file cannot be read as a finished cell (damaged: bbbb.parquet); "
                    "computed again"]
    store.write("bbbb", {"cell": "bbbb", "status": "ok", "x": 2.0})  # the pipe replaced by the cell's file
    assert store.done() == {"aaaa", "bbbb"}


def test_a_folder_among_the_cell_files_is_refused_before_any_cell(tmp_path: Path) -> None:
    """A folder named like a cell file was counted damaged, its cell computed, and the write failed with
    IsADirectoryError (no LmsbenchError: a traceback) after the work (a review). Refused when the
    finished cells are listed, before any cell runs, naming it."""
    import pytest

    from lms200 import LmsbenchError

    store = CellStore(tmp_path)
    store.write("aaaa", {"cell": "aaaa", "status": "ok", "x": 1.0})
    store.path("bbbb").mkdir()
    with pytest.raises(LmsbenchError) as err:
        store.done()
    assert str(err.value) == (f"{store.path('bbbb')}: a folder where a cell's file goes: move it out of {store.cells} "
                              "(the sweep would compute that cell and fail to write it)")


def test_a_sweep_folder_whose_name_is_not_utf8_resumes_its_cells_and_its_tables_read(tmp_path: Path) -> None:
    """pyarrow opens no path that is not UTF-8: in a sweep folder b<0xff> every finished cell was
    "damaged" and computed again on resume, and `figures --sweep` / `--tables` of such a folder
    refused its tables (compare / figures --out there failed after the work)."""
    import pandas as pd

    from experiments.sweep.store import write_atomic

    root = tmp_path / os.fsdecode(b"b\xff")
    store = CellStore(root)
    store.write("aaaa", {"cell": "aaaa", "status": "ok", "x": 1.0})
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the old code's "cannot be read as a finished cell" warning
        assert store.done() == {"aaaa"} and store.status("aaaa") == "ok"
    assert store.read(["aaaa"])["x"].tolist() == [1.0]
    from experiments.provenance import read_parquet, write_parquet

    write_atomic(store.read(["aaaa"]), root / "results.parquet")
    assert read_parquet(root / "results.parquet")["cell"].tolist() == ["aaaa"]
    write_parquet(pd.DataFrame({"y": [2.0]}), root / "t.parquet")
    assert read_parquet(root / "t.parquet")["y"].tolist() == [2.0]


def test_a_file_named_cells_is_not_a_folder_not_a_permission_error(tmp_path: Path) -> None:
    """A regular file where the sweep's cells/ folder goes, read without creating the store (a sweep's
    checks): it was said "cannot be read (permission denied)"."""
    import pytest

    from lms200.errors import LmsbenchError

    (tmp_path / "cells").write_text("mine\n")
    with pytest.raises(LmsbenchError, match=r"cells: is not a folder"):
        CellStore(tmp_path, create=False).done()
