"""Records: what every scan source yields (a log reader, the simulator, the serial driver)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .codes import NOT_NUMBER_ITEMS, unmasked
from .errors import InputError
from .finite import float_of
from .scan import MAX_STAMP_S as SCAN_MAX_STAMP_S, Scan, stamp_problem  # noqa: F401 - the readers' name for it

Pose2D = tuple[float, float, float]  # (x m, y m, theta rad) in the world / odometry frame

#: bad lines / messages a pass keeps with their reasons under ``skip_bad_lines`` (the rest are only
#: counted): 1,000,000 malformed FLASER, ODOM, TRUEPOS or PARAM lines, each kept, peaked at 190-264 MB traced
#: (221-299 MB resident); now 1.3 MB traced, 30 MB resident
MAX_SKIPPED_KEPT = 1000
MAX_REASON_CHARS = 300  # a kept reason is cut past this (a bad word of a 1 MB line is named in it whole)
#: s: the latest stamp a log reader takes (CARMEN ipc and logger timestamps, TUM and relations times),
#: and a Scan (``lms200.scan.MAX_STAMP_S``, the same); the earliest is 0. A log's clock is UNIX time or
#: seconds since its start, and 2^32 s (2106-02-07) is the end of ROS 1's time, which a bag cannot pass:
#: a stamp of 1e300 s was read, and ``info`` said "duration 1e+300 s, scan rate 1.9e-299 scans/s"; a
#: negative one is no clock's
MAX_STAMP_S = SCAN_MAX_STAMP_S

#: Largest |x|, |y| (m) a pose may hold (``logs.MAX_COORD_M``, every log and trajectory reader's and writer's
#: bound, :func:`pose_problem`): a FLASER pose of 1e308 m was read, and `compare --poses corrected` scored its
#: repeatability 0, exit 0.
MAX_COORD_M = 1e9

#: Largest |heading| (rad) a pose or relation may hold (``logs.MAX_HEADING_RAD``, :func:`pose_problem`): 160,000
#: turns of an odometry heading never wrapped, whose float spacing is still 1e-10 rad. Beyond ~1e16 rad a float
#: holds no angle at all: an odometry heading of 1e300 was read as it was (every step's turn from it noise), and
#: a relation's yaw of 1e300 scored 138.6 deg, exit 0 (fuzz4).
MAX_HEADING_RAD = 1e6


def angle_problem(angle: float, what: str) -> str | None:
    """Why ``angle`` (rad) is no angle a pose may hold (beyond +-:data:`MAX_HEADING_RAD`), as a message
    beginning with ``what``; None within the bound, and for nan (a lost pose, which each caller judges)."""
    if not abs(angle) > MAX_HEADING_RAD:
        return None
    return f"{what} {angle:.6g} rad lies beyond +-{MAX_HEADING_RAD:g} rad (damaged? wrap it into (-pi, pi])"


def pose_problem(x: float, y: float, theta: float, what: str) -> str | None:
    """Why (x m, y m, theta rad) is no pose the log and trajectory readers take (x or y beyond
    +-:data:`MAX_COORD_M`, theta beyond +-:data:`MAX_HEADING_RAD`), as a message beginning with ``what``
    (``"odom pose"``); None within the bounds, and for nan (a lost pose, which each caller judges).
    The one wording of the rule for every reader, writer and check (:func:`poses_problem` for arrays);
    the caller adds its context (file and line, item, row) and what refuses it."""
    if abs(x) > MAX_COORD_M or abs(y) > MAX_COORD_M:
        return f"{what} ({x:.6g}, {y:.6g}) m lies beyond +-{MAX_COORD_M:g} m (damaged, or not metres?)"
    return angle_problem(theta, f"{what}'s heading")


def poses_problem(poses: np.ndarray, what: str) -> tuple[int, str] | None:
    """The first row of ``poses`` ((n, 3): x m, y m, theta rad; nan rows pass) that :func:`pose_problem`
    refuses, and its message (beginning with ``what``); None when every row is within the bounds."""
    poses = np.asarray(poses, float)
    with np.errstate(invalid="ignore"):  # nan: a lost pose, not beyond the bound
        bad = (np.abs(poses[:, :2]) > MAX_COORD_M).any(axis=1) | (np.abs(poses[:, 2]) > MAX_HEADING_RAD)
    if not bad.any():
        return None
    k = int(np.argmax(bad))
    x, y, theta = (float(v) for v in poses[k, :3])
    problem = pose_problem(x, y, theta, what)
    assert problem is not None
    return k, problem


@dataclass
class SkipLog:
    """What a pass skipped under ``skip_bad_lines`` (the base of the log readers' stats).

    Attributes:
        skipped: the first ``MAX_SKIPPED_KEPT`` bad lines / messages skipped: (line number or
            message index, reason), a reason cut past ``MAX_REASON_CHARS`` characters.
        skipped_count: every bad line / message skipped, kept or not.
    """

    skipped: list[tuple[int, str]] = field(default_factory=list)
    skipped_count: int = 0

    def skip(self, at: int, reason: str) -> None:
        """Count a skipped line / message; keep it while fewer than ``MAX_SKIPPED_KEPT`` are kept."""
        self.skipped_count += 1
        if len(self.skipped) < MAX_SKIPPED_KEPT:
            cut = reason if len(reason) <= MAX_REASON_CHARS else f"{reason[:MAX_REASON_CHARS]}... ({len(reason)} characters)"
            self.skipped.append((at, cut))


@dataclass(frozen=True)
class Record:
    """One scan with what the source knows of the robot's pose at the scan's ``stamp``: the pose of
    the laser the scan was taken from (a CARMEN log's robot poses are moved by the laser's mounting on
    the robot, ``lms200.carmen.laser_mount``; docs/data.md, "Laser mounting").

    Attributes:
        scan: the laser scan; ``scan.stamp`` is the source's timestamp (s).
        odom: raw odometry pose (x, y, theta) or None where the source has none.
        truth: true pose (x, y, theta) or None where the source has none.
        corrected: a pose from a SLAM solution the source carries (x, y, theta; a Radish
            ``*-corrected`` CARMEN log's laser pose fields, :class:`lms200.carmen_odom.CorrectedChain`),
            or None: a published estimate, cm-level, not ground truth.

    Raises:
        InputError: (an ``LmsbenchError`` and a ``ValueError``) naming the field: ``scan`` not a
            Scan, a pose that is not three finite numbers (poses are stored as tuples of floats).
    """

    scan: Scan
    odom: Pose2D | None = None
    truth: Pose2D | None = None
    corrected: Pose2D | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.scan, Scan):
            raise InputError(f"scan: must be an lms200.Scan, got {type(self.scan).__name__}")
        for name in ("odom", "truth", "corrected"):
            pose = getattr(self, name)
            if pose is not None:
                object.__setattr__(self, name, pose_of(name, pose))


def pose_of(name: str, pose: object, *, optional: bool = True) -> Pose2D:
    """``pose`` as an (x, y, theta) tuple of floats; InputError naming ``name`` otherwise: text
    (``"123"`` was read as (1.0, 2.0, 3.0)), bools (True is not 1 m), ints beyond float64
    (10**400 was a raw OverflowError), nan / inf. Found by a review's reproduction. ``optional``:
    the message says None is taken (the caller's own check); False for a pose that must be given."""
    shape = f"{name}: must be {'None or ' if optional else ''}three numbers (x m, y m, theta rad)"
    pose = unmasked(pose)  # a masked item is no number: nan, refused below (it was read as 0.0)
    if isinstance(pose, (str, bytes)):
        raise InputError(f"{shape}, got {type(pose).__name__} {pose!r}")
    try:
        items: tuple[object, ...] = tuple(pose)  # type: ignore[arg-type]
    except TypeError:
        raise InputError(f"{shape}, got {type(pose).__name__}") from None
    if len(items) != 3:
        raise InputError(f"{shape}, got {len(items)} items")
    values = []
    for v in items:
        if isinstance(v, np.ndarray) and v.ndim == 0:
            v = v.item()
        if isinstance(v, NOT_NUMBER_ITEMS):
            raise InputError(f"{shape}, got {type(v).__name__} {v!r} among them")
        try:
            values.append(float_of(v, name, InputError))
        except (TypeError, ValueError) as exc:
            if isinstance(exc, InputError):
                raise
            raise InputError(f"{shape}, got {type(v).__name__} among them") from None
    x, y, th = values
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(th)):
        raise InputError(f"{name}: must be finite (x m, y m, theta rad), got {pose!r}")
    return (x, y, th)
