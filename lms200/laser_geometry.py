"""Beam geometry of CARMEN laser messages that carry no angles (FLASER, RLASER).

A FLASER line holds only a beam count. Its geometry comes, in this order of precedence, from

1. an explicit override (``read_log(path, geometry=LaserGeometry(...))``, or the CLI flags
   ``--laser-fov-deg``, ``--laser-resolution-deg``, ``--laser-angle-min-deg``, ``--laser-range-max``);
2. the log's PARAM lines (CARMEN names, degrees and metres):
   ``laser_front_laser_resolution`` / ``laser_rear_laser_resolution`` (deg),
   ``laser_front_laser_fov`` / ``laser_rear_laser_fov`` (deg),
   ``robot_front_laser_max`` / ``robot_rear_laser_max`` (m);
3. the CARMEN convention from the count n: a 180 deg field of view centred ahead; an even n spans
   -90 .. +90 - 180/n deg (step 180/n: the last beam of the sweep is not logged), an odd n spans
   -90 .. +90 deg (step 180/(n-1)).

Each field is taken separately: an override of the resolution alone keeps the log's field of view.
With the resolution r known and the field of view F not, F is n*r (even n) or (n-1)*r (odd n), so
the counts of the convention keep their meaning. With F known and r not, r follows from F as in the
convention. With both, the count must fit: n = F/r + 1 (odd style, both ends) or n = F/r (even
style), else the line is malformed. The scan is centred unless an ``angle_min`` is given.

| beams | resolution | first beam | last beam |
|---|---|---|---|
| 180 | 1 deg | -90 deg | +89 deg |
| 181 | 1 deg | -90 deg | +90 deg |
| 360 | 0.5 deg | -90 deg | +89.5 deg |
| 361 | 0.5 deg | -90 deg | +90 deg |
| 720 | 0.25 deg | -90 deg | +89.75 deg |
| 721 | 0.25 deg | -90 deg | +90 deg |
| n even | 180/n deg | -90 deg | +90 - 180/n deg |
| n odd | 180/(n-1) deg | -90 deg | +90 deg |
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from .codes import NOT_NUMBER_ITEMS
from .errors import InputError
from .finite import check_integer, float_of

CONVENTION_FOV_DEG = 180.0  # CARMEN's assumed field of view of a FLASER scan without PARAM lines
FIT_TOLERANCE_BEAMS = 0.25  # a declared fov / resolution must give the count to within this many beams
#: how the error of a declared geometry that does not fit a line's beam count reads (callers tell it by this)
MISFIT_WORDS = "do not fit a field of view"

MAX_RANGE_M = 10_000.0  # m: the largest range_max accepted (long-range 2-D lidars reach ~300 m)
#: m: the smallest range_max accepted: no laser rangefinder's maximum range is shorter (the shortest-range
#: 2-D scanners reach 2-4 m); ``range_max: 1e-320`` (a subnormal) or 0.001 made every reading invalid, silently
MIN_RANGE_MAX_M = 0.1
#: rad (0.00057 deg): finer than any rangefinder's step, and 20 times the rounding a reader snaps to 0
#: (``lms200.scan.SNAP_TEXT_ERROR_RAD``): --laser-resolution-deg 1e-300 was read as 0 and blamed on a log line
MIN_RESOLUTION_RAD = 1e-5
ANGLE_FIELDS = ("fov", "resolution", "angle_min")


def _shown(name: str, value: float) -> str:
    """A field's value for an error message: angles in rad and deg (the CLI flags take degrees)."""
    if name in ANGLE_FIELDS and math.isfinite(value):
        return f"{value:.6g} rad ({math.degrees(value):.6g} deg)"
    return f"{value:g}" + (" m" if name == "range_max" and math.isfinite(value) else "")


# PARAM names per laser message: (resolution deg, fov deg, max range m)
PARAM_NAMES = {
    "FLASER": ("laser_front_laser_resolution", "laser_front_laser_fov", "robot_front_laser_max"),
    "RLASER": ("laser_rear_laser_resolution", "laser_rear_laser_fov", "robot_rear_laser_max"),
}
GEOMETRY_PARAMS = {name: (kind, field)
                   for kind, names in PARAM_NAMES.items()
                   for name, field in zip(names, ("resolution", "fov", "range_max"))}


@dataclass(frozen=True)
class LaserGeometry:
    """Some or all of a laser's beam geometry; None = not known here (taken from elsewhere).

    Attributes:
        fov: field of view (rad) from the first beam's bearing to the last's, or to one step beyond
            it for the even-count convention (see the module docstring).
        resolution: angle between neighbouring beams (rad), > 0.
        angle_min: bearing of beam 0 (rad, sensor frame, CCW); None = centred on the x axis.
        range_max: largest valid range (m), in [MIN_RANGE_MAX_M, MAX_RANGE_M] = [0.1, 10000] m.

    Raises:
        InputError: (an ``LmsbenchError`` and a ``ValueError``) naming the field: text, bools,
            ints beyond float64, nan / inf or values out of range.
    """

    fov: float | None = None
    resolution: float | None = None
    angle_min: float | None = None
    range_max: float | None = None

    def __post_init__(self) -> None:
        for name in ("fov", "resolution", "angle_min", "range_max"):
            value = getattr(self, name)
            if value is None:
                continue
            if isinstance(value, NOT_NUMBER_ITEMS):  # float() takes "3" and True (1 rad)
                raise InputError(f"{name}: must be a number, got {type(value).__name__} {value!r}")
            try:
                value = float_of(value, name, InputError)  # 10**400: InputError, not OverflowError
            except (TypeError, ValueError) as exc:
                if isinstance(exc, InputError):
                    raise
                raise InputError(f"{name}: must be a number, got {value!r}") from None
            shown = _shown(name, value)
            if not math.isfinite(value):
                raise InputError(f"{name}: must be finite, got {shown}")
            if name != "angle_min" and value <= 0:
                raise InputError(f"{name}: must be > 0, got {shown}")
            if name in ("fov", "resolution") and value > 2 * math.pi + 1e-9:
                raise InputError(f"{name}: must be at most 2 pi rad (360 deg), got {shown}")
            if name in ("fov", "resolution") and value < MIN_RESOLUTION_RAD:
                raise InputError(f"{name}: must be at least {MIN_RESOLUTION_RAD:g} rad "
                                 f"({math.degrees(MIN_RESOLUTION_RAD):.5f} deg; finer than any rangefinder's step), "
                                 f"got {shown}")
            if name == "angle_min" and abs(value) > 2 * math.pi + 1e-9:
                raise InputError(f"{name}: a bearing must be within +-2 pi rad (+-360 deg), got {shown}")
            if name == "range_max" and value < MIN_RANGE_MAX_M:
                raise InputError(f"{name}: must be at least {MIN_RANGE_MAX_M:g} m (no laser rangefinder's maximum range "
                                 f"is shorter; with it every reading would be invalid), got {shown}")
            if name == "range_max" and value > MAX_RANGE_M:
                raise InputError(f"{name}: must be at most {MAX_RANGE_M:g} m (no 2-D rangefinder reaches farther), "
                                 f"got {shown}")
            object.__setattr__(self, name, value)

    def merged(self, fallback: "LaserGeometry") -> "LaserGeometry":
        """These fields where set, the fallback's elsewhere."""
        return replace(self, **{k: getattr(fallback, k) for k in ("fov", "resolution", "angle_min", "range_max")
                                if getattr(self, k) is None})


def beam_angles(n: int, geometry: LaserGeometry | None = None) -> tuple[float, float]:
    """(angle_min, angle_increment) in rad of an n-beam scan of partly known geometry.

    Raises:
        InputError: (a ValueError) when n is no integer >= 1 (a plain ValueError before, a TypeError
            for None) or the declared field of view and resolution do not fit n beams.
    """
    n = check_integer(n, "n", 1, 2**31, what="(beams)")  # 10**400 was an OverflowError
    g = geometry or LaserGeometry()
    steps_even, steps_odd = n, n - 1  # steps the field of view spans in each convention
    fov, res = g.fov, g.resolution
    if res is None:
        fov = fov if fov is not None else math.radians(CONVENTION_FOV_DEG)
        res = fov / (steps_even if n % 2 == 0 else max(steps_odd, 1))
    elif fov is None:
        fov = res * (steps_even if n % 2 == 0 else steps_odd)
    else:
        ratio = fov / res
        if abs(ratio - steps_odd) > FIT_TOLERANCE_BEAMS and abs(ratio - steps_even) > FIT_TOLERANCE_BEAMS:
            raise InputError(
                f"{n} beams {MISFIT_WORDS} of {math.degrees(fov):.3f} deg at "
                f"{math.degrees(res):.4f} deg (that is {round(ratio)} or {round(ratio) + 1} beams); "
                "override the geometry (read_log(..., geometry=LaserGeometry(...)) or --laser-resolution-deg / "
                "--laser-fov-deg)"
            )
    if res < MIN_RESOLUTION_RAD:  # a field of view of 1e-9 deg over the scan's beams read as 0 apart, blamed on the log
        raise InputError(f"{n} beams over {math.degrees(fov):.3g} deg are {math.degrees(res):.3g} deg apart, finer than "
                         f"any rangefinder's step ({math.degrees(MIN_RESOLUTION_RAD):.5f} deg); override the geometry "
                         "(--laser-fov-deg / --laser-resolution-deg)")
    if (n - 1) * res > 2 * math.pi + 1e-9:
        raise InputError(f"{n} beams at {math.degrees(res):.4f} deg span more than 360 deg")
    angle_min = g.angle_min if g.angle_min is not None else -0.5 * fov
    return angle_min, res


def from_params(kind: str, params: dict[str, float]) -> LaserGeometry:
    """The geometry a log's PARAM values (CARMEN units: deg, m) declare for a laser message kind."""
    names = PARAM_NAMES.get(kind)
    if names is None:
        return LaserGeometry()
    res, fov, rmax = (params.get(name) for name in names)
    return LaserGeometry(
        fov=math.radians(fov) if fov is not None else None,
        resolution=math.radians(res) if res is not None else None,
        range_max=rmax,
    )
