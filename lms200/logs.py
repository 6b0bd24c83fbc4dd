"""One entry point for every log format: ``read_log`` and ``write_log``.

CARMEN text logs (plain or ``.gz``) and ROS 1 / ROS 2 bags are told apart by their content and
name; both yield :class:`lms200.Record` objects.
"""

from __future__ import annotations

from pathlib import Path
from typing import Iterable

from .bag import BagError, BagReader, is_bag, write_bag
from .carmen import CarmenReader, write_carmen
from .laser_geometry import LaserGeometry
from .records import Record


def read_log(
    path: str | Path,
    skip_bad_lines: bool = False,
    topic: str | None = None,
    geometry: LaserGeometry | None = None,
) -> CarmenReader | BagReader:
    """Open a log for iteration: ``for rec in read_log(path): rec.scan, rec.odom, rec.truth``.

    Args:
        path: a CARMEN log (plain or gzip), a ROS 1 ``.bag`` file or a ROS 2 bag folder.
        skip_bad_lines: skip malformed lines (CARMEN) or unreadable messages (bags) instead of
            raising; what was skipped is in ``reader.stats.skipped`` as (line or message index,
            reason), and ``reader.stats.stopped`` says why a pass ended early, if it did.
        topic: the laser to read: a bag's LaserScan topic (needed when the bag has several), or a
            CARMEN laser message kind (FLASER, RLASER, ROBOTLASER1, ROBOTLASER2; default: the first
            kind in the log).
        geometry: CARMEN FLASER / RLASER only: beam geometry (rad, m) that overrides the log's
            PARAM lines and the convention from the beam count (see :mod:`lms200.laser_geometry`).

    Raises:
        FileNotFoundError: when the path does not exist.
        LogFormatError: (while iterating) a CARMEN line that cannot be read, naming file and line.
        BagError: (while iterating) a bag that cannot be read, naming the topic and message index.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"no such log: {p}")
    if is_bag(p):
        if geometry is not None and geometry != LaserGeometry():
            raise BagError(f"{p}: a bag's LaserScan messages carry their geometry; no geometry override")
        return BagReader(p, topic=topic, skip_bad_lines=skip_bad_lines)
    if p.is_dir():
        raise FileNotFoundError(f"{p} is a folder but not a ROS 2 bag (no metadata.yaml)")
    return CarmenReader(p, skip_bad_lines=skip_bad_lines, topic=topic, geometry=geometry)


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
