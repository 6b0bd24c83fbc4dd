"""Line and corner extraction: the paper's sensor-coordinate method, Cartesian baselines, scoring."""

from .errors import ConfigError
from .registry import available_methods, extract, get_method, make_config, register
from .types import Corner, FeatureSet, Line

__all__ = [
    "ConfigError",
    "extract",
    "available_methods",
    "get_method",
    "make_config",
    "register",
    "FeatureSet",
    "Line",
    "Corner",
]
