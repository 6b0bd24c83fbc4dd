"""One entry point for every log format: ``read_log`` and ``write_log``.

CARMEN text logs (plain or ``.gz``) and ROS 1 / ROS 2 bags are told apart by their content and
name; both yield :class:`lms200.Record` objects.
"""

from __future__ import annotations

from pathlib import Path
from typing import Iterable

from .bag import BagReader, is_bag, write_bag
from .carmen import CarmenReader, write_carmen
from .records import Record


def read_log(path: str | Path, skip_bad_lines: bool = False, topic: str | None = None) -> CarmenReader | BagReader:
    """Open a log for iteration: ``for rec in read_log(path): rec.scan, rec.odom, rec.truth``.

    Args:
        path: a CARMEN log (plain or gzip), a ROS 1 ``.bag`` file or a ROS 2 bag folder.
        skip_bad_lines: CARMEN only: skip malformed lines and count them in ``reader.stats.skipped``
            instead of raising.
        topic: bags only: the LaserScan topic to read (default: every LaserScan topic).

    Raises:
        FileNotFoundError: when the path does not exist.
        LogFormatError: (while iterating) a malformed CARMEN line, naming the file and line.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"no such log: {p}")
    if is_bag(p):
        return BagReader(p, topic=topic)
    if p.is_dir():
        raise FileNotFoundError(f"{p} is a folder but not a ROS 2 bag (no metadata.yaml)")
    return CarmenReader(p, skip_bad_lines=skip_bad_lines)


def write_log(path: str | Path, records: Iterable[Record], fmt: str | None = None) -> int:
    """Write Records to ``path``; returns the number of scans written.

    ``fmt``: "robotlaser1" (default for CARMEN) or "flaser" for CARMEN text (``.gz`` compresses),
    "bag" for a ROS 1 bag (default for ``*.bag``), "bag2" for a ROS 2 bag folder.
    """
    p = Path(path)
    if fmt is None:
        fmt = "bag" if p.suffix == ".bag" else "robotlaser1"
    if fmt in ("bag", "bag2"):
        if fmt == "bag" and p.suffix != ".bag":
            raise ValueError(f"path: a ROS 1 bag must end in .bag, got {p.name}")
        if fmt == "bag2" and p.suffix == ".bag":
            raise ValueError(f"path: a ROS 2 bag is a folder; do not name it {p.name}")
        return write_bag(p, records)
    return write_carmen(p, records, fmt=fmt)
