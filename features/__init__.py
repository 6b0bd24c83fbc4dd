"""Line and corner extraction: the paper's sensor-coordinate method, Cartesian baselines, scoring."""

from .errors import ConfigError, ScanTypeError
from .registry import available_methods, extract, extract_many, get_method, make_config, register
from .types import Corner, Corners, FeatureSet, Line, Lines

__all__ = [
    "ConfigError",
    "ScanTypeError",
    "extract",
    "extract_many",
    "available_methods",
    "get_method",
    "make_config",
    "register",
    "FeatureSet",
    "Line",
    "Corner",
    "Lines",
    "Corners",
]
