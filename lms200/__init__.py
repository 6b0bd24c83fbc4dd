"""The sensor: the Scan type, SICK codes, log formats, the serial protocol, driver and virtual device."""

from .errors import LmsbenchError, LogFormatError
from .codes import codes_to_ranges, decode_logged_ranges, ranges_to_codes
from .records import Pose2D, Record
from .scan import Scan

__all__ = [
    "Scan",
    "LmsbenchError",
    "LogFormatError",
    "Record",
    "Pose2D",
    "codes_to_ranges",
    "ranges_to_codes",
    "decode_logged_ranges",
]
