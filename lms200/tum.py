"""TUM trajectory files: one pose a line, ``t x y z qx qy qz qw`` (s, m, unit quaternion).

Planar poses (x, y, theta) are written with z = 0 and a rotation about z only.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .codes import real_rows, real_vector
from .errors import InputError, LogFormatError
from .logs import path_of, regular_file


def yaw_to_quaternion(theta: np.ndarray) -> np.ndarray:
    """(n,) yaw angles (rad) -> (n, 4) quaternions (qx, qy, qz, qw) about z."""
    half = 0.5 * np.asarray(theta, dtype=float)
    zeros = np.zeros_like(half)
    return np.column_stack((zeros, zeros, np.sin(half), np.cos(half)))


def quaternion_to_yaw(q: np.ndarray) -> np.ndarray:
    """(n, 4) quaternions (qx, qy, qz, qw) -> (n,) yaw (rad, in (-pi, pi])."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    qx, qy, qz, qw = q.T
    return np.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))


def write_tum(path: str | Path, stamps: np.ndarray, poses: np.ndarray) -> None:
    """Write planar poses (n, 3: x m, y m, theta rad) stamped in seconds to a TUM file.

    Raises:
        InputError: a ``path`` that is no str or os.PathLike; ``stamps`` that are not n finite
            numbers in non-decreasing order, or ``poses`` that are no (n, 3) array of real numbers
            (found by fuzzing: (3k, 4) poses, a whole trajectory with its stamps, were written as
            4k garbled rows, and decreasing or nan stamps made a file ``read_tum`` refuses).
            Poses that are not finite (a lost SLAM run's) are written as nan.
    """
    path = path_of(path)
    stamps = real_vector(stamps, "stamps", "s")
    poses = real_rows(poses, "poses", 3, "x m, y m, theta rad", finite=False)
    if stamps.size != poses.shape[0]:
        raise InputError(f"stamps: {stamps.size} stamps for {poses.shape[0]} poses")
    if np.any(np.diff(stamps) < 0):
        k = int(np.nonzero(np.diff(stamps) < 0)[0][0]) + 1
        raise InputError(f"stamps: must not decrease (stamp {k}: {stamps[k].item()!r} s after {stamps[k - 1].item()!r} s)")
    q = yaw_to_quaternion(poses[:, 2])
    with open(path, "w", encoding="ascii") as f:
        f.write("# timestamp x y z qx qy qz qw\n")
        for t, (x, y, _), (qx, qy, qz, qw) in zip(stamps, poses, q):
            f.write(f"{t:.6f} {x:.6f} {y:.6f} 0.000000 {qx:.9f} {qy:.9f} {qz:.9f} {qw:.9f}\n")


def read_tum(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Read a TUM file: (stamps (n,) s, poses (n, 3) x, y, yaw). Raises LogFormatError with the line
    (a row that is not 8 finite numbers, a stamp before the previous one), InputError for a path
    that is no str or PathLike, LogNotFoundError for one that is no regular file."""
    stamps: list[float] = []
    poses: list[tuple[float, float, float]] = []
    with open(regular_file(path, "TUM file"), encoding="ascii", errors="replace") as f:
        for no, line in enumerate(f, 1):
            s = line.strip()
            if not s or s.startswith("#"):
                continue
            parts = s.split()
            if len(parts) != 8:
                raise LogFormatError(path, no, f"TUM rows need 8 entries (t x y z qx qy qz qw), got {len(parts)}")
            try:
                v = [float(p) for p in parts]
            except ValueError:
                raise LogFormatError(path, no, f"TUM row has a non-number: {s[:60]!r}") from None
            if not all(math.isfinite(x) for x in v):  # slam on a folder with a nan here: "internal error"
                raise LogFormatError(path, no, f"TUM row has a non-finite number: {s[:60]!r}")
            if stamps and v[0] < stamps[-1]:
                raise LogFormatError(path, no, f"TUM stamps go backwards ({v[0]:.6f} s after {stamps[-1]:.6f} s)")
            stamps.append(v[0])
            poses.append((v[1], v[2], float(quaternion_to_yaw(np.array(v[4:8]))[0])))
    return np.array(stamps), np.array(poses).reshape(-1, 3)
