"""The sensor: the Scan type, SICK codes, log formats, the serial protocol, driver and virtual device."""

from __future__ import annotations

import importlib
from typing import Any

from .codes import codes_to_ranges, decode_logged_ranges, ranges_to_codes
from .errors import InputError, LmsbenchError, LogFormatError, ScanError
from .records import Pose2D, Record
from .scan import Scan

# Heavier parts load on first use, so `import lms200` stays cheap: name -> module.
_LAZY = {
    "read_log": ".logs",
    "write_log": ".logs",
    "BagError": ".bag",
    "LaserGeometry": ".laser_geometry",
    "LMS200": ".driver",
    "read_tum": ".tum",
    "estimate_range_noise": ".noise",
    "RangeNoise": ".noise",
    "write_tum": ".tum",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name], __name__), name)
    raise AttributeError(f"module 'lms200' has no attribute {name!r}")


__all__ = [
    "Scan",
    "Record",
    "Pose2D",
    "LmsbenchError",
    "LogFormatError",
    "ScanError",
    "InputError",
    "codes_to_ranges",
    "ranges_to_codes",
    "decode_logged_ranges",
    *_LAZY,
]
