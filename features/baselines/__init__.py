"""Cartesian baselines behind ``features.extract``: ``split_merge``, ``iepf``, ``hough``, ``ransac``.
Each module registers its method on import (``features.registry`` imports them lazily)."""
