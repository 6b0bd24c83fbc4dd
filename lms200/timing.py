"""LMS200 timing and the LaserScan fields a Scan does not carry (time_increment, scan_time, range_min).

Source: SICK LMS200/211/221/291 Technical Description (8008970, 2006): the mirror turns at 75 rev/s
(13.33 ms a turn) and one turn sweeps the 180 deg field at 1 deg; a 0.5 deg scan is two interlaced
1 deg turns offset by 0.5 deg, a 0.25 deg scan four. Distance codes count 1 mm or 1 cm units, so
the smallest reading that is a distance is one unit.

ROS ``sensor_msgs/LaserScan`` cannot describe interlacing: its ``time_increment`` is the time
between consecutive measurements along one mirror sweep. We write the mirror's own rate,
``angle_increment / (2 pi) / 75 s`` (exact for 1 deg scans; for interlaced scans the time along one
turn, the best a LaserScan can say), and ``scan_time`` as the sensor's scan period (1/75 s times
the turns per scan). The simulator's ``SensorConfig.beam_time_offsets`` is the true interlaced timing.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import InputError
from .finite import overflow_text

MIRROR_TURN_S = 1.0 / 75.0  # s: one mirror revolution (75 Hz)
ONE_TURN_RESOLUTION_RAD = float(np.deg2rad(1.0))  # one mirror turn measures every 1 deg
CM_MODE_MIN_RANGE_MAX_M = 10.0  # m: a scan whose range_max exceeds this holds cm codes (81.83 m max)
#: longest simulated run (s) of one call or command: 135,000 scans at 37.5 scans/s (~0.4 GB of ranges,
#: held in memory); a duration of 1e9 s planned a tour for 35 minutes and more before running out of
#: memory. Here, beside the scan rate, so that the simulator and the light command-line options share it.
MAX_DURATION_S = 3600.0
#: shortest simulated run (s): one that holds a scan in every LMS200 mode (a 0.25 deg scan's last beam
#: comes 43.7 ms after its first); 0.001 s simulated no scan and then wrote an empty run (simulate),
#: failed after 15 s of calibration (sim2real) or with an IndexError (figures).
MIN_DURATION_S = 0.1
#: lowest rate (scans/s) a run may be decimated to: one scan an hour, the longest simulated run. Below it
#: no run keeps a second scan: `simulate --rate-hz 1e-308` (also compare --rate, sim2real / figures / demo
#: --rate-hz, sim configs' and sweeps' rate_hz, slam --rate-hz) ran, kept the first scan alone, exit 0.
MIN_RATE_HZ = 1.0 / MAX_DURATION_S


def turns_per_scan(angle_increment: float) -> int:
    """Interlaced mirror turns per scan: 1 at 1 deg (or coarser), 2 at 0.5 deg, 4 at 0.25 deg."""
    if not (np.isfinite(angle_increment) and angle_increment > 0):
        raise ValueError(f"angle_increment: must be finite and > 0 rad, got {angle_increment}")
    return max(1, int(round(ONE_TURN_RESOLUTION_RAD / angle_increment)))


def scan_period(angle_increment: float) -> float:
    """Seconds between scans of the sensor: 1/75 s per interlaced turn (0.5 deg: 26.7 ms, 37.5/s)."""
    return turns_per_scan(angle_increment) * MIRROR_TURN_S


#: what MIN_RATE_HZ means, in the messages of the checks that refuse a lower rate
RATE_FLOOR_TEXT = (f"1/{MAX_DURATION_S:g} scans/s (one scan an hour, the longest simulated run: a lower rate keeps "
                   "the first scan alone)")


def check_scan_rate(rate_hz: object, angle_increment: float, name: str = "rate_hz") -> None:
    """``rate_hz`` (scans/s kept of a run) is None (every scan) or a number in [``MIN_RATE_HZ``, the
    sensor's scan rate at ``angle_increment``]: a higher rate cannot be kept (37.5 scans/s at 0.5 deg,
    75 at 1 deg), a lower one keeps only the first scan of any run (one scan an hour, 1/3600 scans/s).

    Raises:
        InputError: naming ``name`` (an argument or a command-line flag) otherwise.
    """
    if rate_hz is None:
        return
    ok = not isinstance(rate_hz, (bool, np.bool_)) and isinstance(rate_hz, (int, float, np.integer, np.floating))
    try:  # np.float32(5.0) was refused, 10**400 an OverflowError formatting the message
        value = float(rate_hz) if ok else math.nan  # type: ignore[arg-type]
    except OverflowError:
        value = math.inf
    if not 0 < value < math.inf:
        shown = repr(rate_hz) if value != math.inf or not isinstance(rate_hz, int) else overflow_text(rate_hz)
        raise InputError(f"{name}: must be a finite number of scans/s > 0 (or None: every scan), got {shown}")
    rate_hz = value
    if rate_hz < MIN_RATE_HZ:
        raise InputError(f"{name}: {rate_hz:g} scans/s is below the lowest rate kept, {RATE_FLOOR_TEXT}")
    most = 1.0 / scan_period(angle_increment)
    if rate_hz > most * (1 + 1e-9):
        raise InputError(f"{name}: {rate_hz:g} scans/s is more than the sensor gives ({most:g} scans/s at "
                         f"{math.degrees(angle_increment):g} deg)")


def mirror_time_increment(angle_increment: float) -> float:
    """Seconds the mirror takes to turn by ``angle_increment`` rad (0.5 deg: 18.5 us)."""
    if not (np.isfinite(angle_increment) and angle_increment > 0):
        raise ValueError(f"angle_increment: must be finite and > 0 rad, got {angle_increment}")
    return float(angle_increment / (2.0 * np.pi) * MIRROR_TURN_S)


def beam_time_offsets(n_beams: int, angle_increment: float) -> np.ndarray:
    """Time (s) of each of ``n_beams`` beams after the scan's first beam: an interlaced scan
    measures beam i in mirror turn ``i mod turns`` at its bearing's share of the turn (a 1 deg scan:
    one 180 deg sweep, 6.7 ms; 0.5 deg: the even beams in the first turn, the odd ones 13.3 ms later,
    the last at 20 ms)."""
    turns = turns_per_scan(angle_increment)
    i = np.arange(int(n_beams))
    return ((i % turns) + i * angle_increment / (2.0 * np.pi)) * MIRROR_TURN_S


LMS200_RESOLUTIONS_DEG = (1.0, 0.5, 0.25)  # the device's angular resolutions (deg)
LMS200_MAX_FOV_DEG = 180.0  # its widest field of view (deg; the other variant spans 100)
_RESOLUTION_TOLERANCE = 1e-3  # relative: a logged or float32 step still reads as the device's


def lms200_shaped(n_beams: int, angle_increment: float) -> bool:
    """True where an LMS200 could have taken a scan of ``n_beams`` beams ``angle_increment`` rad
    apart: a resolution of 1, 0.5 or 0.25 deg and at most 180 deg from first to last beam. Only such
    a scan has the LMS200's interlaced beam timing (:func:`beam_time_offsets`); a Hokuyo's 1081
    beams over 270 deg at 0.25 deg or 683 at 0.352 deg are swept in beam order by another clock."""
    deg = math.degrees(angle_increment)
    if not any(abs(deg - r) <= _RESOLUTION_TOLERANCE * r for r in LMS200_RESOLUTIONS_DEG):
        return False
    return (int(n_beams) - 1) * deg <= LMS200_MAX_FOV_DEG * (1.0 + _RESOLUTION_TOLERANCE)


def smallest_range(range_max: float) -> float:
    """The smallest reading that is a distance (m): one code unit, 1 cm for cm-mode scans
    (range_max > 10 m) and 1 mm otherwise. A code of 0 is no measurement."""
    return 0.01 if range_max > CM_MODE_MIN_RANGE_MAX_M else 0.001
