"""The errors of the extractors' configs."""

from __future__ import annotations

from typing import Any

from lms200 import LmsbenchError
from lms200.errors import NumbaUnavailableError as NumbaUnavailableError  # re-exported: its home before sim and slam used it


class ConfigError(LmsbenchError, ValueError):
    """A config field whose value cannot work; the message starts with the field's name."""


class ScanGeometryError(LmsbenchError, ValueError):
    """A scan (or batch) whose geometry a method cannot handle: too many beams, a Log-Hough template
    or Hough accumulator beyond its memory bound, scans of different geometry in one batch."""


class BatchSizeError(LmsbenchError, ValueError):
    """A batch ``extract_many`` cannot hold: an iterator or generator of scans that does not end
    within ``features.batch.MAX_ITERATOR_BEAMS`` beams (``itertools.repeat(scan)`` never ended)."""


class ScanTypeError(LmsbenchError, TypeError):
    """An extractor was given something other than an ``lms200.Scan`` (a log record, a bare array)."""


def not_a_scan(obj: Any, where: str) -> ScanTypeError:
    """The error for ``obj`` given where a Scan belongs, with the fix for the common cases."""
    from lms200 import Scan

    hint = ""
    if isinstance(getattr(obj, "scan", None), Scan):
        hint = " (a log record: pass record.scan)"
    elif hasattr(obj, "__array__") or isinstance(obj, (list, tuple)):
        hint = " (build one with lms200.Scan.lms200(ranges) or lms200.Scan(...))"
    return ScanTypeError(f"{where}: expected an lms200.Scan, got {type(obj).__name__}{hint}")
