"""The speed ratios the README and docs state in words are the ones their bench table gives.

The table is docs/features.md's `lmsbench bench features` table (scans/s per method, single calls
and batches, office and MIT CSAIL); the words are the ranges of the ratios to the sensor method
over both modes and both scan sets (on MIT CSAIL the sensor method with the log's noise given, as
the pages say). When the table is re-measured, these words have to follow it.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ROW = re.compile(r"^\| (sim office|MIT CSAIL) \| ([^|]+?) \| ([\d,]+) \([^)]*\) \| ([\d,]+) \([^)]*\) \|", re.M)
SENSOR = {"sim office": "sensor", "MIT CSAIL": "sensor (noise given)"}


def bench_table() -> dict[tuple[str, str], tuple[float, float]]:
    """(scans, method) -> (single, batch) scans/s of docs/features.md's bench table."""
    text = (ROOT / "docs" / "features.md").read_text()
    rows = {(m[1], m[2].strip()): (float(m[3].replace(",", "")), float(m[4].replace(",", ""))) for m in ROW.finditer(text)}
    assert len(rows) >= 11, "the bench table of docs/features.md was not found"
    return rows


def ratio_range(method: str, faster: str) -> tuple[float, float]:
    """Least and largest speed ratio of ``faster`` over the other (``method`` and the sensor
    method, one of them ``faster``), over single calls and batches on both scan sets."""
    rows = bench_table()
    ratios = []
    for scans, sensor in SENSOR.items():
        for mode in (0, 1):
            a, b = rows[(scans, method)][mode], rows[(scans, sensor)][mode]
            ratios.append(a / b if faster == method else b / a)
    return min(ratios), max(ratios)


def stated(page: str, pattern: str) -> list[tuple[str, str]]:
    found = re.findall(pattern, re.sub(r"\s+", " ", (ROOT / page).read_text()))
    assert found, f"{page}: {pattern!r} not found"
    return found


def test_the_sensor_method_against_hough_and_ransac_is_the_tables_range() -> None:
    lo = min(ratio_range(m, "sensor")[0] for m in ("hough (numpy)", "ransac (numpy)"))
    hi = max(ratio_range(m, "sensor")[1] for m in ("hough (numpy)", "ransac (numpy)"))
    table = (str(round(lo)), str(round(hi)))
    assert stated("README.md", r"The sensor method is (\d+)-(\d+)x faster than the full Hough transform and RANSAC") == [table]
    assert stated("docs/features.md", r"Hough transform and RANSAC \(vectorised numpy\): the sensor method is (\d+)-(\d+)x "
                                      r"faster") == [table]
    assert stated("docs/baselines.md", r"full Hough transform and RANSAC \(vectorised numpy, (\d+)-(\d+)x slower\)") == [table]


def test_split_merge_and_iepf_against_the_sensor_method_are_the_tables_ranges() -> None:
    table = tuple(f"{v:.1f}" for m in ("split_merge", "iepf") for v in ratio_range(m, m))
    for page in ("README.md", "docs/baselines.md"):
        assert stated(page, r"split-and-merge is (\d+\.\d)-(\d+\.\d)x and IEPF (\d+\.\d)-(\d+\.\d)x faster") == [table], page
