"""TUM trajectory files: one pose a line, ``t x y z qx qy qz qw`` (s, m, quaternion; read
normalised, so any positive norm gives the same yaw).

Planar poses (x, y, theta) are written with z = 0 and a rotation about z only, every number as the
shortest decimal that reads back as the same float64 (as evo and any float parser read it).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .codes import real_rows, real_vector
from .errors import InputError, LogFormatError
from .finite import fixed
from .records import MAX_STAMP_S, pose_problem, poses_problem, stamp_problem


def yaw_to_quaternion(theta: np.ndarray) -> np.ndarray:
    """(n,) yaw angles (rad) -> (n, 4) quaternions (qx, qy, qz, qw) about z; InputError for
    ``theta`` that are not real numbers (text was numpy's ValueError)."""
    half = 0.5 * real_vector(theta, "theta", "yaw rad", finite=False)
    zeros = np.zeros_like(half)
    return np.column_stack((zeros, zeros, np.sin(half), np.cos(half)))


def quaternion_to_yaw(q: np.ndarray) -> np.ndarray:
    """(n, 4) quaternions (qx, qy, qz, qw) -> (n,) yaw (rad, in (-pi, pi]) of the rotations they
    stand for. A quaternion of any positive finite norm is normalised first (``(0, 0, 1, 1)`` is
    90 deg; the unit formula gave 116.57 deg); a zero or non-finite one gives nan (no rotation).
    InputError for ``q`` that is no (4,) or (n, 4) array of real numbers (None, [nan] or three
    numbers were Python's "not enough values to unpack", text numpy's ValueError)."""
    if isinstance(q, np.ndarray) and q.dtype == np.float64 and q.ndim in (1, 2) and q.shape[-1] == 4:
        q = q.reshape(-1, 4)  # the readers' own quaternions, one a pose: nothing to check, no copy
    else:
        try:
            one = np.ndim(q) == 1  # type: ignore[arg-type]
        except ValueError:  # a ragged list: refused by real_rows
            one = False
        q = real_rows([q] if one else q, "q", 4, "qx, qy, qz, qw", finite=False)
    scale = np.max(np.abs(q), axis=1)  # divide by it first: no overflow or underflow in the squares
    ok = np.isfinite(q).all(axis=1) & (scale > 0)
    u = q / np.where(ok, scale, 1.0)[:, None]
    qx, qy, qz, qw = u.T
    # atan2(2 (wz + xy), 1 - 2 (y^2 + z^2)) for a unit q, written so that it holds for any norm
    yaw = np.arctan2(2.0 * (qw * qz + qx * qy), qw * qw + qx * qx - qy * qy - qz * qz)
    return np.where(ok, yaw, np.nan)


def write_tum(path: str | Path, stamps: np.ndarray, poses: np.ndarray) -> None:
    """Write planar poses (n, 3: x m, y m, theta rad) stamped in seconds to a TUM file.

    Every number is written as the shortest decimal that reads back as the same float64 (Python's
    repr: an exponent for magnitudes below 1e-4), so ``read_tum`` gives back the stamps, x and y
    exactly and the yaw of the very quaternion written: theta to within 2 units in the last
    place (4.4e-16 rad; 84 % of angles exactly; no unit quaternion reads back as some angles
    under the yaw formula). Before, 6 decimals (9 for the quaternion) moved epoch stamps by up to
    477 ns, x and y by up to 0.5 um and the yaw by up to 1.3e-9 rad (1,000 random poses).

    Raises:
        InputError: a ``path`` that is no str or os.PathLike; ``stamps`` that are not n finite
            numbers in non-decreasing order, or ``poses`` that are no (n, 3) array of real numbers
            (found by fuzzing: (3k, 4) poses, a whole trajectory with its stamps, were written as
            4k garbled rows, and decreasing or nan stamps made a file ``read_tum`` refuses).
            Poses that are nan (a lost SLAM run's) are written as nan, which
            ``read_tum(path, allow_nan=True)`` reads back; an infinite pose entry, or an x or y beyond
            +-``logs.MAX_COORD_M`` (1e9 m), a heading beyond +-``logs.MAX_HEADING_RAD`` (1e6 rad), or a stamp outside 0 .. ``records.MAX_STAMP_S`` (2^32 s),
            which no reader takes, is an InputError naming its row; so
            is no pose at all (``read_tum`` refuses a file of none). A ``path`` that is a folder or a device, or in
            a folder that does not exist, or that cannot be written, is an InputError naming it
            (they were a raw IsADirectoryError, FileNotFoundError, ...: the wrong-input hunt).
    """
    from .logs import path_of, write_whole  # not at the top: logs imports bag, which imports this module

    path = path_of(path)
    if not path.parent.is_dir():
        raise InputError(f"path: the folder {path.parent} does not exist")
    if path.exists() and not path.is_file():
        raise InputError(f"path: {path} exists and is not a regular file (a folder or a device); "
                         "name a file to write the trajectory to")
    stamps = real_vector(stamps, "stamps", "s")
    poses = real_rows(poses, "poses", 3, "x m, y m, theta rad", finite=False)
    if np.isinf(poses).any():  # was written as 'inf', which read_tum refuses
        k = int(np.nonzero(np.isinf(poses).any(axis=1))[0][0])
        raise InputError(f"poses: row {k} is infinite ({poses[k].tolist()}); a lost pose is written as nan")
    problem = poses_problem(poses, "pose")
    if problem is not None:  # read_tum refuses such a row (1e300 rad: its quaternion noise): a file its reader does not take
        raise InputError(f"poses: row {problem[0]}: {problem[1]}, which read_tum refuses; a lost pose is written as nan")
    if stamps.size != poses.shape[0]:
        raise InputError(f"stamps: {stamps.size} stamps for {poses.shape[0]} poses")
    if not stamps.size:  # read_tum refuses a file of no pose: a file written that its own reader does not take
        raise InputError("poses: none to write (a TUM file of no pose is refused by read_tum, as a cut or emptied file)")
    outside = (stamps < 0) | (stamps > MAX_STAMP_S)
    if outside.any():  # read_tum refuses such a row: a file written that its own reader does not take
        k = int(np.nonzero(outside)[0][0])
        raise InputError(f"stamps: stamp {k} ({stamps[k].item()!r} s) is outside 0 .. 2^32 s, which read_tum refuses "
                         "(lms200.records.MAX_STAMP_S)")
    if np.any(np.diff(stamps) < 0):
        k = int(np.nonzero(np.diff(stamps) < 0)[0][0]) + 1
        raise InputError(f"stamps: must not decrease (stamp {k}: {stamps[k].item()!r} s after {stamps[k - 1].item()!r} s)")
    rows = np.column_stack((stamps, poses[:, :2], np.zeros(stamps.size), yaw_to_quaternion(poses[:, 2])))
    # whole or not at all (a hidden temporary file beside it, renamed into place), as write_log: a full disk
    # left a cut trajectory (slam's trajectory.tum of 0 bytes beside its config.yaml), or an earlier one emptied
    # (an existing file keeps its permission bits, a symbolic link's target is replaced: write_whole)
    def write(tmp: Path) -> None:
        with open(tmp, "w", encoding="ascii") as f:
            f.write("# timestamp x y z qx qy qz qw\n")
            f.writelines(" ".join(map(repr, row)) + "\n" for row in rows.tolist())

    try:
        write_whole(path, write)
    except OSError as exc:
        raise InputError(f"path: cannot write {path}: {exc.strerror or exc}") from None


#: deg: a TUM pose tilted further from upright (the angle between its z axis and the plane's normal)
#: is refused: its frame's z is not up (a camera's optical frame, z forward, is tilted 90 deg), so its
#: yaw is no heading in the plane. A ground robot tilts a few degrees (uneven floors, ramps of up to
#: 8 deg, a sensor mount, motion capture noise); streets of 17 deg are the steepest of them
MAX_TILT_DEG = 30.0
#: deg: a tilt above this (and up to MAX_TILT_DEG) is read, with one warning for the file: the yaw is the
#: heading of the pose's x axis projected onto the plane (exact for any tilt short of 90 deg) and x, y
#: are the position's projection, but the trajectory is not planar (at 5 deg a pose's x axis is
#: foreshortened by under 0.4 %)
TILT_NOTE_DEG = 5.0


def tilt_deg(q: np.ndarray) -> float:
    """The angle (deg) between the z axis of the rotation a quaternion (qx, qy, qz, qw, any positive
    finite norm) stands for and the world's z: 0 for a rotation about z alone (a planar pose's)."""
    qx, qy, qz, qw = np.asarray(q, dtype=float) / np.max(np.abs(q))
    return _tilt_of_cos(1.0 - 2.0 * (qx * qx + qy * qy) / (qx * qx + qy * qy + qz * qz + qw * qw))


def tilt_of_roll_pitch_deg(roll: float, pitch: float) -> float:
    """The tilt (deg) of a rotation given by roll and pitch (rad; any yaw, z-y-x order): the angle
    between its z axis and the world's, acos(cos roll cos pitch), as ``tilt_deg`` of its quaternion."""
    return _tilt_of_cos(math.cos(roll) * math.cos(pitch))


def _tilt_of_cos(cos_tilt: float) -> float:
    """The angle (deg) whose cosine is ``cos_tilt``, clamped to [-1, 1] first (rounding can pass 1)."""
    return math.degrees(math.acos(min(1.0, max(-1.0, cos_tilt))))


def read_tum(path: str | Path, allow_nan: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Read a TUM file: (stamps (n,) s, poses (n, 3) x, y, yaw). A quaternion of any positive norm
    is normalised (``0 0 0 0 0 0 1 1`` is 90 deg).

    Args:
        allow_nan: read a nan in a row's pose (``write_tum``'s lost pose) as nan (x, y as
            written; yaw nan when any of qx qy qz qw is) instead of refusing the row. Stamps must
            be finite and nothing may be infinite either way.

    Raises:
        LogNotFoundError: (an ``LmsbenchError`` and a ``FileNotFoundError``) a path that does not
            exist or is a folder (were a raw FileNotFoundError / IsADirectoryError), a device or
            a pipe (read until memory ran out).
        LogFormatError: naming the line: a row that is not 8 finite numbers (nan allowed in the pose
            with ``allow_nan``; no ``_`` in a number), x or y beyond +-``logs.MAX_COORD_M``, a zero
            quaternion, a quaternion tilted more than ``MAX_TILT_DEG`` (30 deg) from a rotation about
            z (a frame whose z is not up: its yaw is no heading; was read as one, silently), a stamp
            before the previous one or outside 0 .. ``records.MAX_STAMP_S`` (2^32 s), a line longer than ``logs.MAX_ROW_CHARS``; naming the file alone,
            a file of no pose (empty, or blank and comment lines only: it read as no poses).

    Warns:
        LmsbenchWarning: once for a file with poses tilted by more than ``TILT_NOTE_DEG`` (5 deg) and
            up to 30 deg (roll or pitch): read as their heading, naming the line of the largest tilt.
    """
    from .logs import regular_file, row_lines, row_numbers  # not at the top: logs imports bag, which imports this module

    if not isinstance(allow_nan, bool):
        raise InputError(f"allow_nan: must be True or False, got {type(allow_nan).__name__}")
    p = regular_file(path, "TUM file")  # a device or pipe too: /dev/zero was read until memory ran out
    stamps: list[float] = []
    poses: list[tuple[float, float, float]] = []
    tilted, most = 0, (0.0, 0)  # poses tilted beyond TILT_NOTE_DEG, and the largest tilt with its line
    lines = 0
    for no, line in row_lines(path, p, "a TUM trajectory"):  # a line of 3 GB (a file of zeros) was read whole: MemoryError
        lines = no
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        parts = s.split()
        if len(parts) != 8:
            raise LogFormatError(path, no, f"TUM rows need 8 entries (t x y z qx qy qz qw), got {len(parts)}")
        v = row_numbers(path, no, parts, "TUM row")
        lost = allow_nan and math.isfinite(v[0]) and not any(math.isinf(x) for x in v)
        if not lost and not all(math.isfinite(x) for x in v):  # slam on a folder with a nan here: "internal error"
            raise LogFormatError(path, no, f"TUM row has a non-finite number: {s[:60]!r}")
        problem = pose_problem(v[1], v[2], 0.0, "TUM row's pose")  # its heading, of a unit quaternion, is an angle
        if problem is not None:
            raise LogFormatError(path, no, problem)
        problem = stamp_problem(v[0], "TUM time")
        if problem is not None:
            raise LogFormatError(path, no, problem)
        if stamps and v[0] < stamps[-1]:
            raise LogFormatError(path, no, f"TUM stamps go backwards ({fixed(v[0])} s after {fixed(stamps[-1])} s)")
        yaw = float(quaternion_to_yaw(np.array(v[4:8]))[0])
        if math.isnan(yaw) and not any(math.isnan(x) for x in v[4:8]):  # (0, 0, 0, 0) read as yaw 0
            raise LogFormatError(path, no, f"TUM row's quaternion (qx qy qz qw) is zero: {s[:60]!r}")
        if not math.isnan(yaw):
            tilt = tilt_deg(np.array(v[4:8]))
            if tilt > MAX_TILT_DEG:
                raise LogFormatError(path, no, f"TUM row's rotation is tilted {tilt:.1f} deg from upright (roll or "
                                               f"pitch; at most {MAX_TILT_DEG:g} deg): its z axis is not up (a camera's "
                                               "optical frame?), so its yaw is no heading in the plane; give a "
                                               f"trajectory of the robot's base frame: {s[:60]!r}")
            if tilt > TILT_NOTE_DEG:
                tilted += 1
                if tilt > most[0]:
                    most = (tilt, no)
        stamps.append(v[0])
        poses.append((v[1], v[2], yaw))
    if not stamps:  # read as no poses, silently, as an empty CARMEN log was read as no scans
        held = f"holds only blank or comment lines ({lines:,})" if lines else "an empty file (0 bytes)"
        raise LogFormatError(path, None, f"no poses: {held}; a TUM file holds a row t x y z qx qy qz qw per pose "
                                         "(a cut or emptied file?)")
    if tilted:
        import warnings

        from .errors import LmsbenchWarning

        warnings.warn(f"{path}: {tilted} of its {len(stamps)} poses are tilted by more than {TILT_NOTE_DEG:g} deg "
                      f"(roll or pitch; up to {most[0]:.1f} deg, line {most[1]}): read as the heading of their x axis "
                      "and the projection of their position onto the plane", LmsbenchWarning, stacklevel=2)
    return np.array(stamps), np.array(poses).reshape(-1, 3)
