"""Summaries of a scan source (a log, a bag, a simulator run): counts, geometry, rates, validity."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Iterable

import numpy as np

from lms200 import Record
from lms200.finite import fixed


@dataclass(frozen=True)
class LogSummary:
    """What ``lmsbench info`` prints. Angles in degrees, times in seconds."""

    scans: int
    beams: str  # "361", or "180-361" when the log mixes scan sizes
    fov_deg: float
    resolution_deg: float
    angle_min_deg: float
    scan_rate_hz: float
    duration_s: float
    no_return_fraction: float
    invalid_fraction: float
    odometry: bool
    truth: bool
    stamps_back: int = 0  # scans stamped before the previous scan of the log
    corrected: int = 0  # scans with corrected poses (a Radish corrected log: odometry from its ODOM lines)
    stamps_repeated: int = 0  # scans stamped like the previous scan of the log
    odometry_scans: int = 0  # scans with odometry (``odometry``: any); "yes" read as every scan's
    truth_scans: int = 0  # scans with a true pose

    def as_dict(self) -> dict:
        """The fields as JSON-ready values, numbers as numbers: ``beams`` is the beam count (int)
        when every scan has the same size, else None; ``beams_min`` / ``beams_max`` always ints."""
        out = asdict(self)
        low, _, high = self.beams.partition("-")
        out["beams"] = int(low) if not high else None
        out["beams_min"], out["beams_max"] = int(low), int(high or low)
        return out

    def _share(self, n: int) -> str:
        """", on N of M scans" where some scans but not all have it (1 of 40 read as "yes", as every scan's)."""
        return f", on {n:,} of {self.scans:,} scans" if 0 < n < self.scans else ""

    @property
    def _first(self) -> str:
        """Where the log mixes scan sizes, the geometry shown is the first scan's (it read as the log's)."""
        return ", the first scan's" if "-" in self.beams else ""

    def lines(self) -> list[str]:
        return [
            f"scans           {self.scans}",
            f"beams per scan  {self.beams}",
            f"field of view   {fixed(self.fov_deg, 2)} deg (from {fixed(self.angle_min_deg, 2)} deg){self._first}",
            f"resolution      {fixed(self.resolution_deg, 3)} deg{self._first}",
            "scan rate       " + (f"{fixed(self.scan_rate_hz, 2)} scans/s" if self.scan_rate_hz > 0 else
                                  "unknown (one scan)" if self.scans < 2 else "unknown (every scan stamped alike)"),
            f"duration        {fixed(self.duration_s, 2)} s",
            f"no return (inf) {100 * self.no_return_fraction:.2f} % of readings",
            f"invalid         {100 * self.invalid_fraction:.2f} % of readings (nan, -inf, 0 or out of limits)",
            f"odometry        {'yes' if self.odometry else 'no'}{self._share(self.odometry_scans)}"
            + (" (raw: the ODOM lines between scans, chained)" if self.corrected else ""),
            f"true poses      {'yes' if self.truth else 'no'}{self._share(self.truth_scans)}",
            *([f"corrected poses {self.corrected} scans (the laser lines' pose fields: the log's own SLAM solution, "
               "not ground truth)"] if self.corrected else []),
            "time order      " + (f"{self.stamps_back} scan{'s' * (self.stamps_back != 1)} stamped before the previous one "
                                  "(slam needs --skip-bad-lines)" if self.stamps_back else "yes")
            + (f"; {self.stamps_repeated} scan{'s' * (self.stamps_repeated != 1)} stamped like the previous one "
               "(the same scan twice, or a coarse clock)" if self.stamps_repeated else ""),
        ]


def summarise(records: Iterable[Record]) -> LogSummary:
    """Summarise every record of a source in one pass."""
    n = 0
    sizes: set[int] = set()
    stamps: list[float] = []
    readings = inf = nan = 0
    odom_n = truth_n = 0
    back = corrected = repeated = 0
    first = None
    for rec in records:
        s = rec.scan
        first = first or s
        n += 1
        sizes.add(len(s))
        back += bool(stamps) and s.stamp < stamps[-1]
        repeated += bool(stamps) and s.stamp == stamps[-1]  # "time order yes" for a log of every line twice
        stamps.append(s.stamp)
        readings += len(s)
        inf += int(np.isposinf(s.ranges).sum())
        nan += int(np.count_nonzero(~s.valid & ~np.isposinf(s.ranges)))  # nan, -inf (too close), 0 and out-of-limits readings
        odom_n += rec.odom is not None
        truth_n += rec.truth is not None
        corrected += rec.corrected is not None
    if first is None:
        return LogSummary(0, "0", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False, False)
    duration = max(stamps) - min(stamps) if n > 1 else 0.0
    rate = (n - 1) / duration if duration > 0 else 0.0
    beams = str(min(sizes)) if len(sizes) == 1 else f"{min(sizes)}-{max(sizes)}"
    return LogSummary(
        scans=n,
        beams=beams,
        fov_deg=float(np.degrees(first.angle_max - first.angle_min)),
        resolution_deg=float(np.degrees(first.angle_increment)),
        angle_min_deg=float(np.degrees(first.angle_min)),
        scan_rate_hz=rate,
        duration_s=duration,
        no_return_fraction=inf / readings,
        invalid_fraction=nan / readings,
        odometry=odom_n > 0,
        truth=truth_n > 0,
        stamps_back=back,
        corrected=corrected,
        stamps_repeated=repeated,
        odometry_scans=odom_n,
        truth_scans=truth_n,
    )
