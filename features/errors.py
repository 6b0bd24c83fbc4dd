"""The errors of the extractors' configs."""

from __future__ import annotations

from lms200 import LmsbenchError


class ConfigError(LmsbenchError, ValueError):
    """A config field whose value cannot work; the message starts with the field's name."""


class NumbaUnavailableError(LmsbenchError, ImportError):
    """numba, which compiles the extractors, is not installed or cannot be loaded."""


class ScanTypeError(LmsbenchError, TypeError):
    """An extractor was given something other than an ``lms200.Scan`` (a log record, a bare array)."""
