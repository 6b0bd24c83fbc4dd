"""The LMS200 sensor model configuration, with the source of every default.

Sources: SICK LMS200/211/221/291 Technical Description (8008970, 2006) - scanning angle 180 deg at
0.25/0.5/1 deg (0.25 deg only over 100 deg), mirror 75 rev/s (13.33 ms a turn; a 0.5 deg scan is two
interlaced 1 deg turns, a 0.25 deg scan four), range codes in mm (max 8.183 m) or cm (max
81.83 m), statistical error 5 mm (1 sigma) in mm mode; Ye & Borenstein, "Characterization of a 2-D
laser scanner for mobile robot obstacle negotiation", ICRA 2002 - mixed pixels at depth edges
(ranges between the two surfaces when the spot straddles them) and rare dropouts.
"""

from __future__ import annotations

from lms200.yamlio import load as load_yaml, size_problem, dump as dump_yaml

import math
import os
import warnings
from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from lms200 import LmsbenchError
from lms200.errors import InputError, LmsbenchWarning
from lms200.finite import is_one_of, printable
from lms200.codes import LMS200_MAX_RANGE, metres_per_unit
from lms200.laser_geometry import MIN_RANGE_MAX_M
from lms200.timing import MIRROR_TURN_S, scan_period, turns_per_scan

NOISE_REFERENCE_RANGE_M = 2.5  # m: noise_sigma holds at this range (the middle of 1-4 m)
OUTLIER_RANGE_SHARE = (0.1, 0.9)  # an outlier reads this share of the true range (uniform)
MIN_RESOLUTION_DEG = 0.25  # the LMS200's finest angular step (deg)
MAX_RESOLUTION_DEG = 1.0  # the LMS200's coarsest angular step (deg)
MIN_RESOLUTION = math.radians(MIN_RESOLUTION_DEG)  # rad, 0.004363
MAX_RESOLUTION = math.radians(MAX_RESOLUTION_DEG)  # rad, 0.017453
MAX_FOV_DEG = 180.0  # the LMS200's widest field of view (deg)
RESOLUTION_SLACK = 1e-4  # relative: a resolution written by hand to 6 decimals (0.004363 for 0.25 deg) is taken,
# in its bounds and in the field of view it spans (361 beams at 0.008727: 180.007 deg)
# The bounds of a sensor file's values (``lmsbench calibrate`` writes them; ``--sensor`` reads
# them), each physically plausible for a 2-D laser rangefinder with room to spare: a value
# written in mm or cm where metres are meant lies outside (noise_sigma: 0.5 meant as 5 mm in cm
# simulated 0.5 m of noise, and sim2real compared the log against it for minutes, exit 0).
MAX_NOISE_SIGMA_M = 0.1  # largest noise_sigma (m at 2.5 m): the datasheet's 0.005, the real logs' calibrations 0.004-0.027
MAX_TAIL_SIGMA_M = 1.0  # largest noise_tail_sigma (m): the logs' heavy tails are 0.05-0.07
MAX_NOISE_SLOPE = 0.05  # largest |noise_sigma_per_m| (m per m of range): the logs' 0.0006 at most (0.5 mm per m)
MAX_MIXED_GAP_M = 1.0  # largest mixed_gap (m): the default 0.1
MAX_BEAM_WIDTH_DEG = 10.0  # widest laser spot (deg); the LMS200's diverges by about 0.25 deg
MAX_BEAM_WIDTH = math.radians(MAX_BEAM_WIDTH_DEG)  # rad, 0.174533
#: The sensor config's angles are radians (issue #16: one angle unit in configs). Files written
#: before held these fields in degrees; they are read, converted, with a warning (see upgrade_fields).
DEGREE_FIELDS = {"resolution_deg": "resolution", "beam_width_deg": "beam_width"}
MIN_PATCH_M = 1e-3  # smallest rough / dark cell (m): one range code in mm mode
MAX_PATCH_M = 10.0  # largest rough / dark cell (m), a room's size: calibrate tries up to 2 m


@dataclass(frozen=True)
class SensorConfig:
    """Configuration of the emulated LMS200.

    Attributes:
        n_beams: beams per scan (361 at 0.5 deg, 181 at 1 deg, 401 at 0.25 deg over 100 deg).
        resolution: angular step between beams (rad; default 0.5 deg); the scan is centred on
            straight ahead.
        units: "mm" (1 mm codes, max range 8.183 m) or "cm" (1 cm codes, max 81.83 m).
        noise_sigma: Gaussian range noise, 1 sigma (m); datasheet mm mode: 5 mm.
        quantise: round ranges to the unit (1 mm or 1 cm) as the device's codes do.
        dropout_prob: probability that a beam returns an invalid reading (nan).
        mixed_pixels: a beam whose spot straddles a depth edge returns a range between the two
            surfaces (weighted by the share of the spot on each).
        beam_width: width of the laser spot used for mixed pixels (rad; default 0.5 deg).
        mixed_gap: smallest depth step (m) inside a spot that makes a mixed pixel.
        interlaced: each beam is taken from the pose at its own time (mirror turns of 13.3 ms),
            so a moving scanner distorts the scan; False = every beam from the scan's pose.
        noise_sigma_per_m: growth of the noise with range (m per m): a beam at range r has
            sigma ``max(0, noise_sigma + noise_sigma_per_m * (r - 2.5 m))``.
        no_return_prob: probability that a beam which hits a surface returns no echo (+inf).
        outlier_prob: probability that a beam which hits a surface returns an isolated spurious
            echo nearer than the surface (uniform in 10-90 % of its range: dust, stray light);
            the echo is not the surface's, so it is read in front of a dark cell too and carries
            the core noise in front of a rough one (those cells are looked up where the beam
            meets its surface).
        max_reading: when set (m), no-returns are logged as this finite range instead of +inf
            (loggers that write their cap, e.g. 50 m, for "nothing").
        noise_tail_prob, noise_tail_sigma: with this probability a beam's range error is drawn
            from a wider Gaussian of this sigma (m) instead of the core: the heavy tail real scans
            show (surfaces rougher than the worlds' planes, the spot's footprint).
        noise_tail_patch_m: 0: each beam draws the wide Gaussian on its own (probability
            ``noise_tail_prob``); > 0: the world's surfaces are cut into square cells of this size
            (m, world frame, a grid at a random offset) of which a share ``noise_tail_prob`` is
            rough (a hash of the cell and the simulator's seed), and every beam ending in a rough
            cell draws from the wide Gaussian: rough stretches of surface (shelves, radiators,
            curtains, clutter against walls) that stay where they are from scan to scan.
        dropout_patch_m: 0: each beam reads nan on its own with probability ``dropout_prob``;
            > 0: beams that meet a surface read nan where they end in a dark cell of a grid of
            this size (world frame, its own random offset and hash; a share ``dropout_prob`` of
            the cells), so no-returns come in stretches of surface (dark or shiny things) that
            stay from scan to scan, as in real logs; beams that meet nothing still drop one by
            one.

    The last eight fields default to the datasheet model (none of these effects);
    ``lmsbench calibrate`` fits all of them to a real log.

    Checked when built (an ``InputError`` names the field): every number finite; resolution
    in [0.004363, 0.017453] rad (0.25-1 deg) and a field of view of at most 180 deg (so at most
    721 beams), both to 1 part in 10^4 (0.5 deg written to 6 decimals, 0.008727, over 361 beams is
    taken, simulated as written); noise_sigma in [0, 0.1] m, noise_tail_sigma in [0, 1] m and |noise_sigma_per_m|
    <= 0.05 m per m (metres: a 5 meant as millimetres or a 0.5 meant as centimetres is refused,
    not simulated); mixed_gap in [0, 1] m; beam_width in [0, 0.174533] rad (0-10 deg: a 0.5 meant
    as degrees is refused); probabilities in [0, 1); the two cell sizes 0 or in [1 mm, 10 m].
    Angles are radians, as everywhere in configs; files with the older ``resolution_deg`` /
    ``beam_width_deg`` are read by :meth:`from_dict` / :meth:`from_yaml` (converted, with a
    warning).
    """

    n_beams: int = 361
    resolution: float = math.radians(0.5)
    units: Literal["mm", "cm"] = "mm"
    noise_sigma: float = 0.005
    quantise: bool = True
    dropout_prob: float = 0.001
    mixed_pixels: bool = True
    beam_width: float = math.radians(0.5)
    mixed_gap: float = 0.1
    interlaced: bool = True
    noise_sigma_per_m: float = 0.0
    no_return_prob: float = 0.0
    outlier_prob: float = 0.0
    max_reading: float | None = None
    noise_tail_prob: float = 0.0
    noise_tail_sigma: float = 0.0
    noise_tail_patch_m: float = 0.0
    dropout_patch_m: float = 0.0

    def __post_init__(self) -> None:
        for f in fields(self):  # each value of its field's type (a YAML "abc" failed deep in the simulation)
            value, kind = getattr(self, f.name), str(f.type)
            is_bool = isinstance(value, (bool, np.bool_))
            if kind == "bool" and not is_bool:
                raise InputError(f"{f.name}: must be true or false, got {value!r}")
            if kind == "int" and (is_bool or not isinstance(value, (int, np.integer))):
                raise InputError(f"{f.name}: must be a whole number, got {value!r}")
            if kind.startswith("float") and not (value is None and "None" in kind):
                if is_bool or not isinstance(value, (int, float, np.integer, np.floating)):
                    raise InputError(f"{f.name}: must be a number, got {value!r}")
                try:  # an int beyond float's range (a YAML 1 followed by 400 zeros) is not finite either
                    finite = bool(np.isfinite(float(value)))
                except OverflowError:
                    finite = False
                if not finite:  # nan passes every comparison below: refuse it (and inf) first
                    raise InputError(f"{f.name}: must be finite, got {value}")
        if not is_one_of(self.units, ("mm", "cm")):
            raise InputError(f"units: must be 'mm' or 'cm', got {self.units!r}")
        if self.n_beams < 2:
            raise InputError(f"n_beams: must be >= 2, got {self.n_beams}")
        slack = 1 + RESOLUTION_SLACK  # the bounds as written to 6 decimals (0.004363) are taken
        if not MIN_RESOLUTION / slack <= self.resolution <= MAX_RESOLUTION * slack:  # the LMS200's steps: finer
            # ones made 10^8-beam scans (a hang) or overflowed; a 0.5 meant as degrees is 29 deg
            raise InputError(f"resolution: must be in [{MIN_RESOLUTION:.6f}, {MAX_RESOLUTION:.6f}] rad "
                             f"({MIN_RESOLUTION_DEG:g}-{MAX_RESOLUTION_DEG:g} deg, the LMS200's steps), got "
                             f"{self.resolution}{_degrees_hint(self.resolution, MAX_RESOLUTION, MAX_RESOLUTION_DEG)}")
        if self.fov_deg > MAX_FOV_DEG * slack:  # 361 beams at 0.008727 (0.5 deg to 6 decimals) span 180.007 deg:
            # taken, as the bound is, and simulated as written (an exact step is exactly 180 deg)
            raise InputError(f"n_beams, resolution: field of view {self.fov_deg:g} deg exceeds {MAX_FOV_DEG:g} deg "
                             f"({math.radians(MAX_FOV_DEG):.6f} rad)")
        for name, most in (("noise_sigma", MAX_NOISE_SIGMA_M), ("noise_tail_sigma", MAX_TAIL_SIGMA_M)):
            value = getattr(self, name)  # metres: 5 meant as mm simulated 5 m of noise, 0.5 meant as cm 0.5 m
            if not 0 <= value <= most:
                raise InputError(f"{name}: must be in [0, {most:g}] m (a 1-sigma range error in metres; "
                                 f"the datasheet's is 0.005: a value in mm or cm is refused), got {value}")
        if abs(self.noise_sigma_per_m) > MAX_NOISE_SLOPE:  # 0.5 meant as mm per m grew the noise by 3 m at 8 m
            raise InputError(f"noise_sigma_per_m: must be within +-{MAX_NOISE_SLOPE:g} m per m of range (metres of "
                             f"noise per metre; real logs' are below 0.001), got {self.noise_sigma_per_m}")
        if not 0 <= self.mixed_gap <= MAX_MIXED_GAP_M:  # 10 meant as cm made no mixed pixel at all
            raise InputError(f"mixed_gap: must be in [0, {MAX_MIXED_GAP_M:g}] m (a depth step in metres; the default "
                             f"is 0.1), got {self.mixed_gap}")
        for name in ("dropout_prob", "no_return_prob", "outlier_prob"):
            value = getattr(self, name)
            if not 0 <= value < 1:
                raise InputError(f"{name}: must be in [0, 1), got {value}")
        if not 0 <= self.beam_width <= MAX_BEAM_WIDTH:  # 1e300 cast sub-rays at meaningless bearings
            raise InputError(f"beam_width: must be in [0, {MAX_BEAM_WIDTH:.6f}] rad (0-{MAX_BEAM_WIDTH_DEG:g} deg), "
                             f"got {self.beam_width}{_degrees_hint(self.beam_width, MAX_BEAM_WIDTH, MAX_BEAM_WIDTH_DEG)}")
        if not 0 <= self.noise_tail_prob < 1:
            raise InputError(f"noise_tail_prob: must be in [0, 1), got {self.noise_tail_prob}")
        for name in ("noise_tail_patch_m", "dropout_patch_m"):  # 1e-300 m cells overflowed the cell index
            value = getattr(self, name)
            if not (value == 0 or MIN_PATCH_M <= value <= MAX_PATCH_M):  # 30 meant as cm: cells of 30 m
                raise InputError(f"{name}: must be 0 (beam by beam) or a cell size in [{MIN_PATCH_M:g}, {MAX_PATCH_M:g}] m, "
                                 f"got {value}")
        if self.max_reading is not None and not MIN_RANGE_MAX_M <= self.max_reading <= self.range_max:
            # 1e-320 (a subnormal) logged every reading as 1e-320 m: no laser's cap is under 0.1 m
            raise InputError(f"max_reading: must be in [{MIN_RANGE_MAX_M:g}, range_max = {self.range_max}] m, "
                             f"got {self.max_reading}")

    # -- presets ------------------------------------------------------------------------------
    @classmethod
    def ideal(cls, **changes: Any) -> "SensorConfig":
        """Exact geometry: no noise, quantisation, dropouts, mixed pixels or interlacing."""
        base = dict(noise_sigma=0.0, quantise=False, dropout_prob=0.0, mixed_pixels=False, interlaced=False)
        base.update(changes)
        return cls(**base)  # type: ignore[arg-type]

    @classmethod
    def lms200_1deg(cls, **changes: Any) -> "SensorConfig":
        """181 beams at 1 deg (one mirror turn a scan, 75 scans/s)."""
        return cls(**{"n_beams": 181, "resolution": math.radians(1.0), **changes})

    @classmethod
    def lms200_quarter_deg(cls, **changes: Any) -> "SensorConfig":
        """401 beams at 0.25 deg over 100 deg (four interlaced turns, 18.75 scans/s)."""
        return cls(**{"n_beams": 401, "resolution": math.radians(0.25), **changes})

    def replace(self, **changes: Any) -> "SensorConfig":
        """A copy with ``changes``; an old degree field (``resolution_deg=1.0``) is converted, with a
        warning, as in a file."""
        return replace(self, **upgrade_fields(changes, None))

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict[str, Any], where: str = "sensor") -> "SensorConfig":
        """A config from a mapping of field names; keys other than fields raise, naming them.

        Raises:
            LmsbenchError: for unknown keys or a bad value (the message names ``where``).
        """
        if not isinstance(d, dict):
            raise LmsbenchError(f"{where}: a sensor config must be a mapping of fields, got {type(d).__name__}")
        d = upgrade_fields(d, where)
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(d) - known, key=str)  # YAML keys may be numbers, null, true: `1: 2` was
        if unknown:  # "not a sensor model (sequence item 0: expected str instance, int found)"
            raise LmsbenchError(f"{where}: unknown sensor field(s) {', '.join(map(str, unknown))}; "
                                f"known: {', '.join(sorted(known))}")
        try:
            return cls(**d)
        except (TypeError, ValueError) as exc:
            raise LmsbenchError(f"{where}: {exc}") from None

    @classmethod
    def from_yaml(cls, path: str | Path, data: bytes | None = None) -> "SensorConfig":
        """Read a sensor YAML: the fields at top level (as ``lmsbench calibrate`` writes them; its
        ``calibration`` section of estimates is metadata and skipped), or a run's config.yaml
        with a ``sensor`` section. ``data``: the file's bytes, read already (a sweep cell parses the
        bytes it keyed itself by); ``path`` then only names it.

        Raises:
            LmsbenchError: for a missing or unreadable file, unknown fields or bad values.
        """
        if not isinstance(path, (str, os.PathLike)) or isinstance(path, bytes):  # None raised TypeError from Path
            raise InputError(f"path: must be a str or os.PathLike naming a sensor YAML, got {type(path).__name__}")
        p = Path(path)
        if data is not None:
            return cls._from_text(p, data)
        if p.is_dir():  # was "no such sensor file"
            raise InputError(f"{p} is a folder, not a sensor YAML")
        if p.exists() and not p.is_file():  # a pipe (--sensor <(cat s.yaml)) was "no such sensor file"
            raise InputError(f"{p}: not a regular file (a pipe, a device or a socket): a sensor YAML must be a regular "
                             "file; give the file itself (or save the stream to a file first)")
        if p.is_symlink() and not p.exists():  # as every other input's link to nothing: was "no such sensor file"
            raise InputError(f"{p}: a symbolic link to {os.readlink(p)}, which does not exist (or a loop of links)")
        if not p.is_file():
            raise LmsbenchError(f"{p}: no such sensor file")
        too_big = size_problem(p.stat().st_size, "a sensor YAML")
        if too_big:
            raise InputError(f"{p}: {too_big}")
        return cls._from_text(p, p.read_bytes())

    @classmethod
    def _from_text(cls, p: Path, data: bytes) -> "SensorConfig":
        """:meth:`from_yaml` of the bytes ``data`` of the file ``p``."""
        import yaml

        too_big = size_problem(len(data), "a sensor YAML")
        if too_big:
            raise InputError(f"{p}: {too_big}")
        try:
            d = load_yaml(data.decode("utf-8"))
        except (yaml.YAMLError, UnicodeDecodeError) as exc:
            raise LmsbenchError(f"{p}: not valid YAML ({' '.join(str(exc).split())})") from None
        if d is None:  # `calibrate LOG > s.yaml` that failed leaves it empty: was "got NoneType"
            raise InputError(f"{p}: empty (no sensor field, only comments or nothing); a sensor YAML holds the "
                             "fields `lmsbench calibrate` writes")
        if isinstance(d, dict) and isinstance(d.get("sensor"), dict):
            d = d["sensor"]
        if isinstance(d, dict):
            fields = {k: v for k, v in d.items() if k != "calibration"}
            if not fields and "calibration" in d:  # was the default sensor, silently
                raise InputError(f"{p}: holds a calibration section but no sensor fields (a YAML from "
                                 "`lmsbench calibrate` has both)")
            d = fields
        return cls.from_dict(d, where=str(p))

    def to_yaml(self, path: str | Path, header: str = "", extra: dict[str, Any] | None = None) -> None:
        """Write the fields as YAML (``header`` as # comment lines, ``extra`` as more sections). A lone
        surrogate in ``header`` (a path's undecodable bytes, as ``os.fsdecode`` gives them) is written
        as its escape (``lms200.finite.printable``; YAML writes one in ``extra`` as ``\\uDCFF``): it failed UTF-8's encoding (``lmsbench calibrate``
        of a log under such a folder, an internal error after the whole calibration)."""

        lines = "".join(f"# {line}\n" for line in printable(header).splitlines())
        body = dump_yaml(self.to_dict(), sort_keys=False)
        if extra:
            body += dump_yaml(extra, sort_keys=False)
        Path(path).write_text(lines + body, encoding="utf-8")

    def sigma_at(self, ranges: np.ndarray) -> np.ndarray:
        """Range noise 1 sigma (m) at each range (m)."""
        r = np.asarray(ranges, dtype=float)
        return np.maximum(self.noise_sigma + self.noise_sigma_per_m * (r - NOISE_REFERENCE_RANGE_M), 0.0)

    # -- derived ------------------------------------------------------------------------------
    @property
    def resolution_deg(self) -> float:
        """The angular step in degrees, for display (configs hold ``resolution``, rad)."""
        return math.degrees(self.resolution)

    @property
    def fov_deg(self) -> float:
        """Field of view from first to last beam (deg), for display and the 180 deg check."""
        return (self.n_beams - 1) * self.resolution_deg

    @property
    def angle_min(self) -> float:
        """Bearing of beam 0 (rad). Computed through degrees as before the config held radians, so
        the scans stay the same to the bit (at 0.25, 0.5 and 1 deg the degrees are exact)."""
        return -np.deg2rad(self.fov_deg) / 2

    @property
    def angle_increment(self) -> float:
        """Bearing step between beams (rad): ``resolution``."""
        return float(self.resolution)

    @property
    def angles(self) -> np.ndarray:
        """Bearing of every beam (rad), sensor frame."""
        return self.angle_min + np.arange(self.n_beams) * self.angle_increment

    @property
    def range_max(self) -> float:
        """The maximum range (m): 8.183 (mm) or 81.83 (cm); farther returns are +inf."""
        return LMS200_MAX_RANGE[self.units]

    @property
    def unit_m(self) -> float:
        """Size of one range code (m): 0.001 (mm) or 0.01 (cm)."""
        return metres_per_unit(self.units)

    @property
    def turns_per_scan(self) -> int:
        """Interlaced mirror turns per scan: 1 at 1 deg, 2 at 0.5 deg, 4 at 0.25 deg."""
        return turns_per_scan(self.angle_increment)

    @property
    def scan_period(self) -> float:
        """Seconds between scans: 1/75 s a turn times the turns per scan (0.5 deg: 37.5 scans/s)."""
        return scan_period(self.angle_increment)

    @property
    def beam_time_offsets(self) -> np.ndarray:
        """Time of each beam after the scan's first beam (s): beam i lies in turn i mod turns, at
        its bearing's share of the turn."""
        i = np.arange(self.n_beams)
        return ((i % self.turns_per_scan) + i * self.resolution_deg / 360.0) * MIRROR_TURN_S


def _degrees_hint(value: float, most: float, most_deg: float) -> str:
    """`` (degrees given as radians?)`` for a value above its bound in radians that is within it
    read as degrees (``resolution: 0.5``, ``beam_width: 0.5`` from a file of the old spelling)."""
    return " (degrees given as radians?)" if most < value <= most_deg else ""


def upgrade_fields(d: Mapping[str, Any], where: str | None = "sensor") -> dict[str, Any]:
    """``d`` with the old degree fields (``resolution_deg``, ``beam_width_deg``: sensor files,
    sweep axes and overrides written before the config held radians) converted to their radian
    fields, each with a one-line :class:`LmsbenchWarning` naming ``where`` (a file) and the value
    to write instead. A value that is not a number is passed on as is, for the field's own check.

    Raises:
        InputError: when ``d`` gives a field in both spellings.
    """
    out = dict(d)
    for old, new in DEGREE_FIELDS.items():
        if old not in out:
            continue
        place = f"{where}: " if where else ""
        if new in out:
            raise InputError(f"{place}gives both {old} (deg, the old spelling) and {new} (rad); give {new} only")
        value = out.pop(old)
        if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_)):
            try:
                value = math.radians(value)
            except OverflowError:  # an int beyond float's range: the field's check says "must be finite"
                value = math.inf
            warnings.warn(f"{place}{old}: {d[old]} (deg) is the old spelling, read as {new}: {value!r} (rad); "
                          f"write `{new}: {value!r}` instead", LmsbenchWarning, stacklevel=3)
        out[new] = value
    return out
