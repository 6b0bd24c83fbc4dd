"""Simulated runs: a robot tour scanned by the emulated LMS200, as lms200 Records."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Callable

import numpy as np

from lms200 import Record
from lms200.errors import InputError
from lms200.timing import MAX_DURATION_S as MAX_DURATION_S  # re-exported: sim's bound
from lms200.timing import check_scan_rate

from .lidar import LMS200Sim
from .checks import check_instance
from .robot import RobotLimits, Tour, check_duration, robot_tour, wrap
from .sensor import SensorConfig
from .world import World
from .worlds import check_seed, make_world

_STREAM_ODOMETRY = 4


@dataclass(frozen=True)
class OdometryConfig:
    """Wheel odometry with the odometry motion model's noise (Thrun, Burgard and Fox,
    Probabilistic Robotics, 2005, sec. 5.4): each step's rotation-translation-rotation gets zero
    mean Gaussian noise of standard deviation alpha1 |rot| + alpha2 |trans| (rotations) and
    alpha3 |trans| + alpha4 (|rot1| + |rot2|) (translation). Starts at the true first pose."""

    alpha1: float = 0.05  # rad/rad
    alpha2: float = 0.01  # rad/m
    alpha3: float = 0.05  # m/m
    alpha4: float = 0.01  # m/rad

    MAX_ALPHA = 10.0  # per unit of motion: ten times the motion itself, far beyond any wheel odometry

    def __post_init__(self) -> None:
        """Each alpha a finite number in [0, MAX_ALPHA] (``alpha1: x`` was an internal error deep in
        numpy, ``alpha1: -1`` and ``alpha2: 1e300`` ran, silently)."""
        from .checks import check_number  # noqa: PLC0415 - sim.checks is light; kept beside its use

        for name in ("alpha1", "alpha2", "alpha3", "alpha4"):
            object.__setattr__(self, name, check_number(getattr(self, name), name, 0.0, self.MAX_ALPHA))

    def to_dict(self) -> dict:
        return asdict(self)


def odometry_poses(truth: np.ndarray, config: OdometryConfig, rng: np.random.Generator) -> np.ndarray:
    """(n, 3) noisy odometry poses integrated along the (n, 3) true poses."""
    d = np.diff(truth, axis=0)
    trans = np.hypot(d[:, 0], d[:, 1])
    moving = trans > 1e-9
    rot1 = np.where(moving, wrap(np.arctan2(d[:, 1], d[:, 0]) - truth[:-1, 2]), 0.0)
    rot2 = wrap(d[:, 2] - rot1)
    c = config
    n1, n2, n3 = rng.standard_normal((3, len(d)))
    rot1_n = rot1 + n1 * (c.alpha1 * np.abs(rot1) + c.alpha2 * trans)
    trans_n = trans + n2 * (c.alpha3 * trans + c.alpha4 * (np.abs(rot1) + np.abs(rot2)))
    rot2_n = rot2 + n3 * (c.alpha1 * np.abs(rot2) + c.alpha2 * trans)
    out = np.empty_like(truth)
    out[0] = truth[0]
    th = truth[0, 2] + np.cumsum(rot1_n + rot2_n)
    heading = np.concatenate(([truth[0, 2]], th[:-1])) + rot1_n
    out[1:, 0] = truth[0, 0] + np.cumsum(trans_n * np.cos(heading))
    out[1:, 1] = truth[0, 1] + np.cumsum(trans_n * np.sin(heading))
    out[1:, 2] = wrap(th)
    return out


def check_rate(rate_hz: object, sensor: SensorConfig) -> None:
    """``rate_hz`` (scans/s kept) is None (every scan) or a number in (0, the sensor's scan rate]
    (:func:`lms200.timing.check_scan_rate`); InputError naming it otherwise."""
    check_scan_rate(rate_hz, sensor.angle_increment)


def scan_stamps(sensor: SensorConfig, duration: float, rate_hz: float | None = None) -> np.ndarray:
    """Times (s) of the first beam of each scan kept: every scan of the sensor (37.5/s at 0.5 deg)
    whose last beam falls within ``duration``, decimated to about ``rate_hz`` when given."""
    period = sensor.scan_period
    last_beam = float(sensor.beam_time_offsets.max())
    n = max(int(np.floor((duration - last_beam) / period + 1e-9)) + 1, 0)
    step = 1
    if rate_hz is not None:  # keep every step-th scan; a rate this low keeps the first alone
        kept_share = period * rate_hz  # scans kept per scan made: 1e-320 scans/s made 1 / share inf
        step = max(n, 1) if kept_share * max(n, 1) <= 1.0 else max(1, int(round(1.0 / kept_share)))
    return np.arange(0, n, step) * period


def simulate_tour(world: World, tour: Tour, stamps: np.ndarray, sensor: SensorConfig, seed: int = 0,
                  odometry: OdometryConfig | None = None,
                  progress: Callable[[int, int], None] | None = None) -> list[Record]:
    """Scan ``world`` along ``tour`` at ``stamps``; each beam from the pose at its own time.
    ``progress(done, total)`` is called after each scan (a driver's progress bar)."""
    truth = tour.pose_at(stamps)
    odom = odometry_poses(truth, odometry, np.random.default_rng([int(seed), _STREAM_ODOMETRY])) if odometry else None
    offsets = sensor.beam_time_offsets if sensor.interlaced else np.zeros(sensor.n_beams)
    records = []
    with LMS200Sim(world, sensor, seed) as sim:
        for j, t in enumerate(stamps):
            scan = sim.scan_from_beam_poses(tour.pose_at(t + offsets), float(t))
            pose = (float(odom[j, 0]), float(odom[j, 1]), float(odom[j, 2])) if odom is not None else None
            records.append(Record(scan=scan, odom=pose,
                                  truth=(float(truth[j, 0]), float(truth[j, 1]), float(truth[j, 2]))))
            if progress is not None:
                progress(j + 1, len(stamps))
    return records




def simulate_records(world: str | World = "office", seed: int = 0, duration: float = 120.0,
                     sensor: SensorConfig | None = None, odometry: OdometryConfig | None = None,
                     rate_hz: float | None = None, limits: RobotLimits | None = None,
                     progress: Callable[[int, int], None] | None = None) -> list[Record]:
    """A simulated run as Records: the robot tours ``world`` (a name, built with ``seed``, or a
    World) for ``duration`` s and the LMS200 scans at its rate (decimated to ``rate_hz``).

    Every record has the true scanner pose at its stamp (the time of its first beam); odometry
    only when ``odometry`` is given. ``progress(done, total)`` is called after each scan.

    Raises:
        InputError: (an ``LmsbenchError`` and a ``ValueError``) naming the argument, for a duration
            that is not a number of seconds in (0, MAX_DURATION_S],
            a rate that is not in (0, the sensor's scan rate], a seed that is not a whole number >= 0, or an unknown world.
    """
    check_seed(seed)
    check_duration(duration)  # np.float32(0.5) and np.int64(1) were refused, np.float64 taken
    check_instance(sensor, SensorConfig, "sensor")
    check_instance(odometry, OdometryConfig, "odometry")
    check_instance(limits, RobotLimits, "limits")
    if progress is not None and not callable(progress):
        raise InputError(f"progress: must be None or callable (done, total), got {progress!r}")
    s = sensor if sensor is not None else SensorConfig()
    check_rate(rate_hz, s)
    rate = None if rate_hz is None else float(rate_hz)  # np.float32(5) kept in float32 rounds 7.5 scans a step down
    stamps = scan_stamps(s, float(duration), rate)  # type: ignore[arg-type]
    if stamps.size == 0:  # 1e-9 s or 1 ms gave an empty list, silently
        raise InputError(f"duration: {float(duration):g} s is shorter than one scan (its last beam is measured "  # type: ignore[arg-type]
                         f"{float(s.beam_time_offsets.max()):.4g} s after its first)")
    w = world if isinstance(world, World) else make_world(world, seed)
    tour = robot_tour(w, seed, float(duration), limits)  # type: ignore[arg-type]
    return simulate_tour(w, tour, stamps, s, seed, odometry, progress)
