"""A kinematic robot touring a world: waypoints planned on the world's route graph, driven as
turn-on-the-spot then straight legs with trapezoidal (continuous) speed and turn-rate profiles,
pauses at the rooms it visits. Poses are exact functions of time (no integration error)."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from lms200 import LmsbenchError
from lms200.angles import wrap
from lms200.codes import real_vector
from lms200.errors import InputError
from lms200.timing import MAX_DURATION_S

from .world import World

_STREAM_TOUR = 3
STILL, DRIVE, TURN = 0, 1, 2


@dataclass(frozen=True)
class RobotLimits:
    """Limits of a Pioneer-class robot (m, s, rad), each checked against BOUNDS when made (a
    ``simulate --config`` with ``robot: {v_max: 1e300}`` planned a tour for ever, ``v_max: -1`` or
    ``a_max: 0`` drove a tour of nan or no motion silently, ``a_max: 1e-300`` a robot standing still,
    ``pause_s: [5, 1]`` was an internal error).

    Raises:
        InputError: naming the field, for a value that is not a finite number within its bounds.
    """

    v_max: float = 0.5  # m/s forward speed
    a_max: float = 0.5  # m/s^2
    w_max: float = 1.0  # rad/s turn rate
    alpha_max: float = 2.0  # rad/s^2
    radius: float = 0.25  # m, for collision checks
    pause_s: tuple[float, float] = (0.5, 2.0)  # pause at each visited room (uniform range)

    #: (lowest, highest, lowest excluded, unit) of each number: highest far beyond any indoor robot
    #: (a Pioneer drives at most 1.5 m/s), yet a tour of MAX_DURATION_S at V_MAX plans in seconds;
    #: lowest 0.01 (1 cm/s, 1 cm/s^2, 0.01 rad/s and rad/s^2: a half turn of 314 s, a start to
    #: the default 0.5 m/s of 50 s), far below any robot that moves: a_max 1e-300 was taken and ran
    #: a robot that never left its first pose, exit 0; radius 0 is a point robot
    BOUNDS = {"v_max": (0.01, 10.0, False, "m/s"), "a_max": (0.01, 100.0, False, "m/s^2"),
              "w_max": (0.01, 20.0, False, "rad/s"), "alpha_max": (0.01, 200.0, False, "rad/s^2"),
              "radius": (0.0, 2.0, False, "m")}

    def __post_init__(self) -> None:
        from .checks import check_number  # noqa: PLC0415 - sim.checks is light; kept beside its use

        for name, (lo, hi, lo_open, unit) in self.BOUNDS.items():
            object.__setattr__(self, name, check_number(getattr(self, name), name, lo, hi, lo_open=lo_open, unit=unit))
        pause = self.pause_s
        if isinstance(pause, (str, bytes)) or not hasattr(pause, "__len__") or len(pause) != 2:
            raise InputError(f"pause_s: must be two numbers of seconds [shortest, longest], got {pause!r}")
        lo, hi = (check_number(p, "pause_s", 0.0, MAX_DURATION_S, unit="s") for p in pause)
        if lo > hi:
            raise InputError(f"pause_s: the shortest pause must not exceed the longest, got {list(pause)!r}")
        object.__setattr__(self, "pause_s", (lo, hi))

    def to_dict(self) -> dict:
        return asdict(self)


def _trapezoid(amount: np.ndarray, vmax: np.ndarray | float, amax: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(accel time, cruise time, peak rate) covering |amount| from rest to rest."""
    a = np.abs(amount)
    t_acc = np.minimum(vmax / amax, np.sqrt(a / amax))
    peak = amax * t_acc
    with np.errstate(invalid="ignore", divide="ignore"):
        t_cruise = np.where(peak > 0, (a - amax * t_acc**2) / np.where(peak > 0, peak, 1.0), 0.0)
    return t_acc, np.maximum(t_cruise, 0.0), peak


@dataclass(frozen=True)
class Tour:
    """A planned run: phases (still, drive straight, turn on the spot) back to back.

    Attributes:
        start: (P,) start time of each phase (s); duration: (P,) its length (s).
        kind: (P,) STILL, DRIVE or TURN; amount: (P,) metres driven or radians turned (signed).
        pose0: (P, 3) pose at the start of each phase (theta unwrapped).
        accel: (P,) acceleration used (m/s^2 or rad/s^2); t_acc, peak: profile shape per phase.
        waypoints: (k, 2) points the tour drives through, in order.
    """

    start: np.ndarray
    duration: np.ndarray
    kind: np.ndarray
    amount: np.ndarray
    pose0: np.ndarray
    accel: np.ndarray
    t_acc: np.ndarray
    peak: np.ndarray
    waypoints: np.ndarray

    @property
    def end_time(self) -> float:
        return float(self.start[-1] + self.duration[-1])

    def _phase(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        if not (isinstance(t, np.ndarray) and t.dtype == np.float64 and t.ndim == 1 and np.isfinite(t).all()):
            t = real_vector(t, "t", "s")  # None, nan and text were the tour's end pose, 10**400 an OverflowError
        k = np.clip(np.searchsorted(self.start, t, side="right") - 1, 0, len(self.start) - 1)
        tau = np.clip(t - self.start[k], 0.0, self.duration[k])
        ta, pk, acc, T = self.t_acc[k], self.peak[k], self.accel[k], self.duration[k]
        # every branch is computed, the one chosen stays finite (the deceleration's only where T - tau
        # <= ta): a phase of 1e300 s (limits of v_max 1e-300 m/s) overflowed in the others, a
        # RuntimeWarning on stderr per pose asked
        with np.errstate(over="ignore", invalid="ignore"):
            s = np.where(tau < ta, 0.5 * acc * tau**2,
                         np.where(tau < T - ta, 0.5 * acc * ta**2 + pk * (tau - ta), np.abs(self.amount[k]) - 0.5 * acc * (T - tau) ** 2))
            rate = np.where(tau < ta, acc * tau, np.where(tau < T - ta, pk, acc * (T - tau)))
        sign = np.sign(self.amount[k])
        s = np.where(self.kind[k] == STILL, 0.0, s * sign)
        rate = np.where(self.kind[k] == STILL, 0.0, rate * sign)
        return k, s, rate, t

    def pose_at(self, t: np.ndarray | float) -> np.ndarray:
        """(n, 3) true pose (x m, y m, theta rad wrapped to (-pi, pi]) at times t (s); constant
        after the tour's end. InputError for ``t`` that are not finite real numbers (a number or
        any shape of them)."""
        k, s, _, _ = self._phase(t)
        x0, y0, th0 = self.pose0[k].T
        drive = self.kind[k] == DRIVE
        turn = self.kind[k] == TURN
        x = x0 + np.where(drive, s * np.cos(th0), 0.0)
        y = y0 + np.where(drive, s * np.sin(th0), 0.0)
        th = th0 + np.where(turn, s, 0.0)
        return np.column_stack((x, y, wrap(th)))

    def twist_at(self, t: np.ndarray | float) -> np.ndarray:
        """(n, 2) forward speed (m/s) and turn rate (rad/s) at times t."""
        k, _, rate, _ = self._phase(t)
        return np.column_stack((np.where(self.kind[k] == DRIVE, rate, 0.0), np.where(self.kind[k] == TURN, rate, 0.0)))


#: route nodes a tour passes at most: the mit world's longest tour (3,600 s at 10 m/s) passes a few
#: thousand; a world whose route targets lie 1e-7 m apart planned ever more legs, for ever
MAX_WAYPOINTS = 200_000


def plan_waypoints(world: World, rng: np.random.Generator, length_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Waypoints (k, 2) visiting random route targets by shortest paths until the path is at
    least ``length_m`` long, and a (k,) mask of the targets reached (pause points).

    Raises:
        LmsbenchError: when the world has no route graph.
    """
    nodes, edges = world.route_nodes, world.route_edges
    if len(edges) == 0 or len(world.route_targets) == 0:
        raise LmsbenchError(f"world {world.name!r} has no route graph to plan a tour on")
    lengths = np.hypot(*(nodes[edges[:, 0]] - nodes[edges[:, 1]]).T)
    graph = coo_matrix((lengths, (edges[:, 0], edges[:, 1])), shape=(len(nodes), len(nodes)))
    dist, pred = dijkstra(graph, directed=False, return_predecessors=True)
    targets = world.route_targets
    current = int(targets[rng.integers(len(targets))])
    path, is_target, total = [current], [True], 0.0
    while total < length_m:
        choices = [int(t) for t in targets if t != current and np.isfinite(dist[current, t])]
        if not choices:
            break
        goal = choices[int(rng.integers(len(choices)))]
        leg = [goal]
        while leg[-1] != current:
            leg.append(int(pred[current, leg[-1]]))
        leg = leg[::-1][1:]
        path += leg
        if len(path) > MAX_WAYPOINTS:  # route targets 1e-7 m apart: ever more legs, for ever (a hang)
            raise LmsbenchError(f"world {world.name!r}: a tour of {length_m:g} m would pass more than "
                                f"{MAX_WAYPOINTS:,} route nodes (its route targets are too close together for "
                                f"the run's duration and speed: {total:.3g} m of path so far)")
        is_target += [False] * (len(leg) - 1) + [True]
        total += float(dist[current, goal])
        current = goal
    return nodes[path], np.array(is_target)


def tour_path(world: World, seed: int, length_m: float) -> np.ndarray:
    """The start of the route :func:`robot_tour` (same ``world`` and ``seed``) drives, as (k, 2)
    waypoints (m, world frame, no two alike) cut on its last edge to a path of exactly ``length_m`` m.

    Raises:
        LmsbenchError: when the world's route graph joins no two route targets.
    """
    pts, _ = plan_waypoints(world, np.random.default_rng([int(seed), _STREAM_TOUR]), length_m=length_m)
    pts = pts[np.concatenate(([True], np.hypot(*np.diff(pts, axis=0).T) > 1e-9))]
    arc = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))))
    if arc[-1] < length_m:  # no leg: one target alone, or none reachable from the first
        raise LmsbenchError(f"world {world.name!r}: its route graph joins no two route targets, so the robot "
                            "has nowhere to drive (route_edges must connect route_targets)")
    k = int(np.searchsorted(arc, length_m))  # arc[k - 1] < length_m <= arc[k]
    t = (length_m - arc[k - 1]) / (arc[k] - arc[k - 1])
    return np.vstack((pts[:k], pts[k - 1] + t * (pts[k] - pts[k - 1])))


def check_duration(duration: object) -> None:
    """``duration`` is a number of seconds in (0, MAX_DURATION_S] (numpy numbers too); InputError naming it."""
    ok = not isinstance(duration, (bool, np.bool_)) and isinstance(duration, (int, float, np.integer, np.floating))
    if not ok or not 0 < duration <= MAX_DURATION_S:  # type: ignore[operator]
        raise InputError(f"duration: must be a number of seconds in (0, {MAX_DURATION_S:g}], got {duration!r}")


def robot_tour(world: World, seed: int = 0, duration: float = 120.0, limits: RobotLimits | None = None) -> Tour:
    """A collision-free tour of ``world`` lasting at least ``duration`` s (seeded).

    Raises:
        InputError: naming the argument: a world that is no World, a seed that is not a whole number
            >= 0, a duration that is not a number of seconds in (0, MAX_DURATION_S] (1e9 s planned
            for minutes and ran out of memory; -1 s gave a tour, silently), limits that are no RobotLimits.
    """
    from .checks import check_instance  # noqa: PLC0415 - sim.checks is light; kept beside its use
    from .worlds import check_seed  # noqa: PLC0415 - sim.worlds imports this module's users

    check_instance(world, World, "world", optional=False)
    check_seed(seed)
    check_duration(duration)
    check_instance(limits, RobotLimits, "limits")
    lim = limits if limits is not None else RobotLimits()
    rng = np.random.default_rng([int(seed), _STREAM_TOUR])
    # enough path for the duration at cruise speed, then phases until the duration is covered
    pts, is_target = plan_waypoints(world, rng, length_m=duration * lim.v_max + 5.0)
    phases: list[tuple[int, float, float, float]] = []  # kind, amount, v_max, a_max
    d0 = pts[1] - pts[0] if len(pts) > 1 else np.array([1.0, 0.0])
    heading = float(np.arctan2(d0[1], d0[0])) + float(rng.uniform(-0.5, 0.5))
    theta0 = heading
    for k in range(1, len(pts)):
        d = pts[k] - pts[k - 1]
        dist = float(np.hypot(*d))
        if dist < 1e-9:
            continue
        turn = float(wrap(np.arctan2(d[1], d[0]) - heading))
        if abs(turn) > 1e-9:
            phases.append((TURN, turn, lim.w_max, lim.alpha_max))
            heading += turn
        phases.append((DRIVE, dist, lim.v_max, lim.a_max))
        if is_target[k]:
            phases.append((STILL, float(rng.uniform(*lim.pause_s)), 0.0, 0.0))
    if not phases:
        raise LmsbenchError(f"world {world.name!r}: its route graph joins no two route targets, so the robot "
                            "has nowhere to drive (route_edges must connect route_targets)")
    kind = np.array([p[0] for p in phases], dtype=int)
    amount = np.array([p[1] for p in phases])
    vmax = np.array([p[2] for p in phases])
    amax = np.array([p[3] for p in phases])
    t_acc, t_cruise, peak = _trapezoid(np.where(kind == STILL, 0.0, amount), np.where(kind == STILL, 1.0, vmax),
                                       np.where(kind == STILL, 1.0, amax))
    dur = np.where(kind == STILL, amount, 2 * t_acc + t_cruise)
    start = np.concatenate(([0.0], np.cumsum(dur)[:-1]))
    pose0 = np.zeros((len(phases), 3))
    x, y, th = float(pts[0][0]), float(pts[0][1]), theta0
    for i, (kd, am, _, _) in enumerate(phases):
        pose0[i] = (x, y, th)
        if kd == DRIVE:
            x, y = x + am * np.cos(th), y + am * np.sin(th)
        elif kd == TURN:
            th += am
    return Tour(start, dur, kind, amount, pose0, np.where(kind == STILL, 0.0, amax), np.where(kind == STILL, 0.0, t_acc),
                np.where(kind == STILL, 0.0, peak), pts)
