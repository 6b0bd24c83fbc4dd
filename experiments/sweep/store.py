"""Where a sweep keeps its results: one small Parquet file per finished cell, written atomically.

Layout of a sweep folder::

    sweep.yaml            the sweep as run (resolved), for reproduction
    cells/KEY.parquet     one row per finished cell; KEY = cell_key(kind, params)
    results.parquet       every finished cell of the sweep, in the sweep's order (also results.csv)

A cell file is written to a temporary name in the same folder and renamed into place
(``os.replace`` is atomic on POSIX), so a sweep killed at any moment leaves only whole cell files.
A cell file damaged otherwise (a disk error, a copy cut short, an edit) is no finished cell: it is
computed again, with one warning line (it stopped the resumed sweep with "internal error:
ArrowInvalid: ... smaller than the minimum file footer", exit 1), and so is a whole file of another
cell's row under this cell's name (one cell's file copied over another's).
"""

from __future__ import annotations

import os
import tempfile
import warnings
from pathlib import Path
from typing import Any, Mapping

import pandas as pd

from lms200.errors import LmsbenchError, LmsbenchWarning
from lms200.finite import shown

from experiments.provenance import read_parquet, write_parquet

CELLS_DIR = "cells"
RESULT_TABLES = ("results.parquet", "results.csv")  # the tables write_atomic writes into a sweep folder


class CellStore:
    """The finished cells of one sweep folder."""

    def __init__(self, root: str | Path, create: bool = True) -> None:
        """The store of the sweep folder ``root``; ``create``: make its cells/ folder (and clear what a
        kill left in it), else only read it (a sweep's checks count its cells left before any write)."""
        self.root = Path(root)
        self.cells = self.root / CELLS_DIR
        if not create:
            return
        self.cells.mkdir(parents=True, exist_ok=True)
        for stale in self.cells.glob(".*.tmp"):  # left by a kill between write and rename
            stale.unlink(missing_ok=True)
        for table in RESULT_TABLES:  # write_atomic's of the tables, as a kill left them (they stayed for ever)
            for stale in self.root.glob(f".{table}.*.tmp"):
                if stale.is_file() and not stale.is_symlink():
                    stale.unlink(missing_ok=True)

    @staticmethod
    def finished(root: str | Path) -> bool:
        """Whether the sweep folder ``root`` holds a finished cell (without making its cells/ folder)."""
        return any((Path(root) / CELLS_DIR).glob("*.parquet"))

    def path(self, key: str) -> Path:
        return self.cells / f"{key}.parquet"

    def done(self, params_of: Mapping[str, Mapping[str, Any]] | None = None) -> set[str]:
        """Keys of every cell with a finished file (a Parquet file of one cell's row, by its footer:
        a damaged one is computed again, said in one warning). The footer alone: reading every
        cell's row here cost a resumed sweep 1.6 ms a cell (3.2 s for 2,000) before any work.
        ``params_of`` (key -> the parameters of the sweep's cell of that key): a file of one of these
        keys whose row records other parameters (edited by hand: the key is a hash of them) is no
        finished cell either, computed again with one warning naming it; its row was taken into the
        table as the cell's, the parameters it records beside metrics computed with others."""
        keys, damaged, foreign = set(), [], []  # foreign: a whole file of another cell's row (its `cell` not its name)
        edited: list[str] = []
        if not self.cells.exists() and not self.cells.is_symlink():  # a new sweep (a store not created)
            return keys
        if not self.cells.is_dir():  # a file there was said "cannot be read (permission denied)"
            raise LmsbenchError(f"{self.cells}: is not a folder (a file, or a link to none, where the sweep keeps its "
                                "finished cells); move it out of the sweep folder to resume the sweep")
        if not os.access(self.cells, os.R_OK | os.X_OK):  # "sw/cells: permission denied" named no reason
            raise LmsbenchError(f"{self.cells}: the sweep's folder of finished cells cannot be read (permission "
                                "denied); make it readable (chmod u+rx) to resume the sweep")
        for p in sorted(self.cells.glob("*.parquet")):
            if p.is_dir():  # its cell would be computed, then not written: os.replace's IsADirectoryError (a review)
                raise LmsbenchError(f"{p}: a folder where a cell's file goes: move it out of {self.cells} (the sweep "
                                    "would compute that cell and fail to write it)")
            if p.is_file() and not os.access(p, os.R_OK):  # was "damaged ...; computed again": the finished cell lost
                raise LmsbenchError(f"{p}: a finished cell's file that cannot be read (permission denied); make it "
                                    f"readable (chmod u+r) to resume the sweep with it, or remove it to compute the cell again")
            if (meta := _whole_parquet(p)) is None:
                damaged.append(p.name)
            elif (held := _cell_of(p, meta)) != p.stem:
                foreign.append(f"{p.name} holds {held}")
            elif params_of is not None and p.stem in params_of and (
                    differ := _params_differ(p, meta, params_of[p.stem])) is not None:
                edited.append(f"{p.name}: {differ}")
            else:
                keys.add(p.stem)
        if damaged:
            warnings.warn(f"{self.cells}: {len(damaged)} cell file{'s' if len(damaged) > 1 else ''} cannot be read as "
                          f"a finished cell (damaged: {', '.join(damaged[:3])}{', ...' if len(damaged) > 3 else ''}); "
                          "computed again", LmsbenchWarning, stacklevel=2)
        if foreign:
            warnings.warn(f"{self.cells}: {len(foreign)} cell file{'s' if len(foreign) > 1 else ''} hold{'s' if len(foreign) == 1 else ''} "
                          f"the row of another cell than {'their' if len(foreign) > 1 else 'its'} name "
                          f"({'; '.join(foreign[:3])}{', ...' if len(foreign) > 3 else ''}: copied or renamed by hand); "
                          "computed again", LmsbenchWarning, stacklevel=2)
        if edited:
            warnings.warn(f"{self.cells}: {len(edited)} cell file{'s' if len(edited) > 1 else ''} record{'s' if len(edited) == 1 else ''} "
                          f"other parameters than the sweep's cell of {'their' if len(edited) > 1 else 'its'} name "
                          f"({'; '.join(edited[:3])}{', ...' if len(edited) > 3 else ''}: edited by hand); computed again",
                          LmsbenchWarning, stacklevel=2)
        return keys

    def check_writable(self) -> None:
        """Raise LmsbenchError when cells cannot be written into the cells folder, as it is, or, where it
        is yet to be made (a new sweep folder), into the nearest existing folder it is made in: a resumed
        sweep whose cells/ was read-only computed its first cell, then failed naming a temporary file
        (``cells/.KEY.xxxx.tmp: permission denied``), and a new folder beneath a read-only one failed
        with a PermissionError making it. One check, before any cell is computed or a scheduler reached
        (``runner.plan_sweep``; the run checked an existing folder a second time)."""
        if self.cells.is_dir():
            if not os.access(self.cells, os.W_OK | os.X_OK):
                raise LmsbenchError(f"{self.cells}: the sweep's folder of finished cells is not writable, and cells "
                                    "are left to compute; make it writable (chmod u+w) to resume the sweep")
            return
        if self.cells.exists() or self.cells.is_symlink():  # a file (or a broken link) there: making it says so
            return
        _check_made_in(self.cells, "the sweep's folder of finished cells", "and cells are left to compute")

    def check_root_writable(self) -> None:
        """Raise LmsbenchError when the sweep folder (``root``) cannot be written, or, where it is yet to be made,
        made: every run writes its sweep.yaml, versions.yaml and tables there, finished or not, so a read-only
        folder whose cells/ was writable failed writing sweep.yaml (a PermissionError naming its temporary
        file), and a new folder beneath a regular file a NotADirectoryError, tracebacks from the library
        (the command line's ``check_out`` said both first). Before any cell (``runner.plan_sweep``)."""
        what, why = "the sweep folder", "and every run writes its sweep.yaml, versions.yaml and tables there"
        if not self.root.exists() and not self.root.is_symlink():
            _check_made_in(self.root, what, why)
        elif self.root.is_dir() and not os.access(self.root, os.W_OK | os.X_OK):
            raise LmsbenchError(f"{self.root}: {what} is not writable, {why}; make it writable (chmod u+w), or give "
                                "another folder")

    def status(self, key: str) -> str | None:
        """"ok", "error", or None when the cell has no file (or a damaged one)."""
        row = _cell_row(self.path(key), ["status"])
        return None if row is None else str(row["status"].iloc[0])

    def write(self, key: str, row: dict[str, Any]) -> Path:
        """Write one cell's row atomically (temporary file, fsync, rename)."""
        table = _tidy(pd.DataFrame([row]))
        fd, tmp = tempfile.mkstemp(dir=self.cells, prefix=f".{key}.", suffix=".tmp")
        try:
            os.fchmod(fd, user_mode())  # mkstemp makes 0600; a result file gets the user's umask
            with os.fdopen(fd, "wb") as handle:
                table.to_parquet(handle, index=False)
                handle.flush()
                os.fsync(handle.fileno())
            os.replace(tmp, self.path(key))
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        return self.path(key)

    def read(self, keys: list[str]) -> pd.DataFrame:
        """The rows of the given cells that have files, in the given order."""
        rows = (_cell_row(self.path(k)) for k in keys)
        frames = [f for f in rows if f is not None]
        if not frames:
            return pd.DataFrame()
        columns = list(dict.fromkeys(c for f in frames for c in f.columns))
        frames = [f.dropna(axis=1, how="all") for f in frames]  # all-null cells must not decide dtypes
        return _tidy(pd.concat(frames, ignore_index=True, sort=False).reindex(columns=columns))


def _check_made_in(folder: Path, what: str, why: str) -> None:
    """Raise LmsbenchError when ``folder`` (absent) cannot be made: its nearest existing ancestor is no folder
    (a regular file: NotADirectoryError) or not a writable one (PermissionError)."""
    from experiments.options import nearest_existing

    parent = nearest_existing(folder.parent, links=True)
    if not parent.is_dir():
        raise LmsbenchError(f"{folder}: {what} cannot be made: {parent} is not a folder (a file, or a link to none), "
                            f"{why}; give a folder that can be written")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise LmsbenchError(f"{folder}: {what} cannot be made: {parent} is not writable, {why}; give a folder that "
                            "can be written")


def _whole_parquet(path: Path) -> Any:
    """The footer (pyarrow's ``FileMetaData``) of ``path`` where it holds a whole Parquet file of one
    row with a ``status`` and a ``cell`` column, else None: by its footer alone (a cut file has none;
    the row itself is read by :meth:`CellStore.read`)."""
    import pyarrow.parquet as pq

    if not path.is_file():  # a pipe in cells/ was waited on for ever (`lmsbench sweep` resuming hung; fuzzing)
        return None
    try:
        with open(path, "rb") as fh:  # pyarrow opens no path that is not UTF-8 (a sweep folder b<0xff>)
            meta = pq.read_metadata(fh)
    except Exception:  # noqa: BLE001 - pyarrow's ArrowInvalid, OSError: damaged
        return None
    return meta if meta.num_rows == 1 and {"status", "cell"} <= set(meta.schema.names) else None


def _cell_of(path: Path, meta: Any) -> str | None:
    """The key in the ``cell`` column of a whole cell file, from the statistics of its footer
    ``meta`` (the one :func:`_whole_parquet` read: a resume reads each cell's footer once); the
    runner's files carry them, and the column is read where they are missing. A file of another cell's row under this name was taken as this cell finished: a sweep
    said "3 already done", exit 0, and its table lacked the cell (copied over by the other's row),
    which `figures --sweep` then asked to finish by running the sweep again, which did nothing."""
    try:
        stats = meta.row_group(0).column(meta.schema.names.index("cell")).statistics if meta.num_row_groups == 1 else None
        if stats is not None and stats.has_min_max and stats.min == stats.max and isinstance(stats.min, str):
            return stats.min
        row = _cell_row(path, ["status"])
    except Exception:  # noqa: BLE001 - pyarrow's ArrowInvalid, OSError: damaged since the footer was read
        return None
    return None if row is None else str(row["cell"].iloc[0])


def _params_differ(path: Path, meta: Any, params: Mapping[str, Any]) -> str | None:
    """The first of ``params`` that the one-row cell file ``path`` (its footer ``meta``) records
    otherwise, as ``NAME=RECORDED, not GIVEN`` (or ``NAME missing``), else None. From the footer's
    statistics, as :func:`_cell_of` reads the key (a value of one row is its column's min and max), and
    from the row where a column has none; a bool is not the number 1, numbers compare by value."""
    names = meta.schema.names
    recorded: dict[str, Any] = {}
    unread = []
    for name in params:
        if name not in names:
            return f"{name} missing"
        try:
            column = meta.row_group(0).column(names.index(name))
            stats = column.statistics if meta.num_row_groups == 1 else None
            null = str(meta.schema.column(names.index(name)).logical_type) == "Null"
        except Exception:  # noqa: BLE001 - no statistics: read below
            stats, null = None, False
        if null:  # a parameter of None: Arrow's null column, written with no statistics (its row was read: a
            recorded[name] = None  # resume of 2,000 such cells took 4.4 s, 0.5 s from the footers alone)
        elif stats is not None and stats.has_min_max and stats.min == stats.max:
            recorded[name] = stats.min
        elif stats is not None and stats.null_count == 1:
            recorded[name] = None
        else:
            unread.append(name)
    if unread:
        row = _cell_row(path, [*unread, "status"] if "status" not in unread else unread)
        if row is None:
            return "unreadable"
        recorded.update({name: _plain(row[name].iloc[0]) for name in unread})
    for name, given in params.items():
        held = recorded[name]
        if isinstance(held, bytes):
            held = held.decode("utf-8", "replace")
        if isinstance(held, bool) != isinstance(given, bool) or held != given:
            return f"{name}={shown(held, 40)}, not {shown(given, 40)}"
    return None


def _plain(value: Any) -> Any:
    """A table's value as Python's (numpy's scalars as their values, a missing value as None)."""
    if value is None or (isinstance(value, float) and value != value):
        return None
    return value.item() if hasattr(value, "item") else value


def _cell_row(path: Path, columns: list[str] | None = None) -> pd.DataFrame | None:
    """A cell file's row (``columns`` of it), or None where there is no file or it does not read
    as one row with a ``status`` and a ``cell`` column (a damaged file, or no regular file: a pipe waits)."""
    if not path.is_file():
        return None
    try:
        table = read_parquet(path, columns=columns if columns is None else [*columns, "cell"])
    except FileNotFoundError:
        return None
    except Exception:  # noqa: BLE001 - pyarrow's ArrowInvalid, OSError, KeyError of a column: damaged
        return None
    if len(table) != 1 or "status" not in table.columns or "cell" not in table.columns:
        return None
    return table


def user_mode() -> int:
    """The mode a plain ``open(path, "w")`` would give a new file: 0666 less the umask."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def write_atomic(table: pd.DataFrame, path: Path) -> None:
    """Write a table as Parquet (or CSV for a .csv path) via a temporary file and a rename."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.fchmod(fd, user_mode())  # mkstemp makes 0600; a result file gets the user's umask
    os.close(fd)
    try:
        if path.suffix == ".csv":
            table.to_csv(tmp, index=False)
        else:
            write_parquet(_tidy(table), tmp)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _tidy(table: pd.DataFrame) -> pd.DataFrame:
    """Make object columns Parquet-safe: a column mixing strings with numbers becomes strings."""
    for name in table.columns:
        col = table[name]
        if col.dtype == object:
            kinds = {type(v) for v in col if v is not None and not (isinstance(v, float) and pd.isna(v))}
            if len(kinds) > 1 and str in kinds:
                table[name] = col.map(lambda v: v if v is None or isinstance(v, str) else str(v))
    return table
