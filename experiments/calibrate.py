"""`lmsbench calibrate`: the simulator's sensor model fitted to a real log.

The measurements are :func:`lms200.calibration.calibrate_scans` (from the log alone). They map
onto :class:`sim.SensorConfig` fields one to one, except two that depend on how the simulator
produces the effect, which are fitted by simulation (indirect inference, fixed seeds):

- ``beam_width`` (rad): the simulator makes a mixed pixel where a beam's spot straddles a depth
  step, so the share of steps with a mixed pixel grows with the spot's width. The same counter is
  run on short simulated runs at spot widths of 0-2 beam steps; the width whose share equals the
  log's is interpolated (capped at 2 beam steps).
- ``outlier_prob``: isolated outliers counted among the beams amid a straight stretch (8
  neighbours each side on one line, ``LogCalibration.outlier_straight_rate``), where the scene
  puts no one-beam object (thin legs, gaps, edges of small things make most of the isolated
  outliers elsewhere); the rate the same counter reads on the simulated run with the fitted spot
  width and no outliers is subtracted. Counted over all beams instead (``outlier_rate``, kept as a
  measurement), the log's scene went into the sensor: MIT CSAIL's 1.71 % of all trials against
  0.012 % amid straight stretches gave ``outlier_prob`` 1.21 % (in sim2real's fit), spurious echoes in the middle of every
  simulated wall that the log does not have, which cut the worlds' near walls into short lines
  (docs/simulator.md, "The CSAIL logs' lines per scan").
- ``noise_tail_prob``: the residual tail's weight includes the scene's own; the simulated weight at
  a few tail probabilities is interpolated to the log's.
- ``dropout_patch_m``: whether nan readings come beam by beam or in dark stretches of surface:
  the share of nan beams whose next beam is nan too (``LogCalibration.nan_clustering``)
  simulated with dark cells of 0-0.8 m, interpolated to the log's (only where the clustering,
  less 3 standard errors, exceeds twice the nan rate and 0.1: beams dropped one by one give
  about the nan rate). MIT CSAIL's nans come in
  stretches (0.82); dropped beam by beam they cut every wall, which the paper's extractor does
  not bridge.
- ``noise_tail_patch_m``: whether the tail comes beam by beam or in rough stretches of surface:
  the tail's clustering along the scan (``LogCalibration.tail_clustering``) simulated with rough
  cells of 0-2 m, interpolated to the log's. A real log's tail gathers in stretches (MIT CSAIL,
  Intel); spread over single beams it breaks every wall into short pieces, which split-and-merge
  drops and Hough / RANSAC do not.

Nothing else is tuned: noise_sigma is the 1-4 m sigma, noise_sigma_per_m the fitted slope,
dropout_prob the nan rate, no_return_prob the surface no-return rate, max_reading the log's cap.
"""

from __future__ import annotations

import io
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator, Sequence

import numpy as np

from lms200 import LmsbenchError, read_log
from lms200.errors import InputError
from lms200.finite import fixed
from lms200.calibration import LogCalibration, calibrate_scans
from lms200.laser_geometry import MIN_RANGE_MAX_M
from lms200.timing import LMS200_MAX_FOV_DEG

from experiments.logargs import report_skipped
from experiments.options import warnings_after_checks

WIDTH_GRID_STEPS = (0.0, 0.1, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0)  # spot widths tried, in beam steps
TAIL_GRID = (0.0, 0.1, 0.3)  # noise_tail_prob values tried
PATCH_GRID_M = (0.0, 0.1, 0.3, 1.0, 2.0)  # noise_tail_patch_m values tried (m)
DARK_GRID_M = (0.0, 0.1, 0.2, 0.4, 0.8)  # dropout_patch_m values tried (m)
NAN_CLUSTER_MIN = 0.1  # nan clustering (less 3 std) above this and twice the nan rate: nans gather, fit cells
FIT_DURATION_S = 30.0  # simulated seconds per spot width
MIN_FIT_DURATION_S = 1.0  # `calibrate --fit-duration`: 5 scans a fit run (a bootstrap needs 2)
MAX_FIT_DURATION_S = 600.0  # 3000 scans a fit run, held at once (16 runs take minutes)
FIT_RATE_HZ = 5.0  # scans kept per simulated second
FIT_SEED = 0


@dataclass(frozen=True)
class CalibrationResult:
    """The log's measurements, the sensor config fitted to them and the simulated share curve."""

    measured: LogCalibration
    sensor: Any  # sim.SensorConfig
    width_curve: list[tuple[float, float]]  # (beam_width in rad, simulated mixed share)
    outlier_baseline: float  # the outlier counter's rate amid straight stretches on the simulated run without outliers
    world: str
    tail_curve: list[tuple[float, float]] = ()  # type: ignore[assignment]  # (noise_tail_prob, simulated tail share)
    patch_curve: list[tuple[float, float]] = ()  # type: ignore[assignment]  # (noise_tail_patch_m, simulated clustering)
    dark_curve: list[tuple[float, float]] = ()  # type: ignore[assignment]  # (dropout_patch_m, simulated nan clustering)
    fit_duration: float = 30.0  # simulated seconds of each fit run (FIT_DURATION_S unless asked otherwise)


def monotone_curve(values: Sequence[float]) -> np.ndarray:
    """A probe curve made non-decreasing: running maximum, nan counted as 0."""
    return np.maximum.accumulate(np.nan_to_num(np.asarray(values, dtype=float)))


def invert_probe_curve(values: Sequence[float], probes: Sequence[float], target: float) -> float:
    """The simulator parameter at which a simulated statistic reaches a log's (indirect inference).

    ``values[i]`` is the statistic measured on probe runs at parameter ``probes[i]`` (``probes``
    ascending, in the parameter's own units). The curve values(probes) is made non-decreasing
    (running maximum; nan counts as 0) and interpolated piecewise linearly: for a target between
    its first and last values the result is the parameter at which it first reaches ``target``;
    ``probes[0]`` for a target at or below the first value or not finite, ``probes[-1]`` for one
    at or above the last (so the result stays within the probes).
    Used by :func:`fit_sensor` (tail, rough cells, dark cells) and by
    ``experiments.sim2real.fit_rough`` / ``fit_scale`` / ``fit_relief`` (the mit worlds' rough fill,
    room size and wall relief).
    """
    x = monotone_curve(values)
    y = np.asarray(probes, dtype=float)
    if not np.isfinite(target) or target <= x[0]:
        return float(y[0])
    if target >= x[-1]:
        return float(y[-1])
    k = int(np.searchsorted(x, target, side="left"))
    x0, x1 = x[k - 1], x[k]
    t = 0.0 if x1 <= x0 else (target - x0) / (x1 - x0)
    return float(y[k - 1] + t * (y[k] - y[k - 1]))


def _resolution_deg(angle_increment: float) -> float:
    deg = float(np.rad2deg(angle_increment))
    for known in (0.25, 0.5, 1.0):
        if abs(deg - known) < 0.01:
            return known
    raise LmsbenchError(f"angular resolution {fixed(deg, 4)} deg: the LMS200 model has 0.25, 0.5 or 1 deg")


def base_sensor(cal: LogCalibration):
    """The SensorConfig that the measurements give directly (spot width and outliers not yet fitted)."""
    from sim import SensorConfig
    from sim.sensor import MAX_NOISE_SIGMA_M, MAX_NOISE_SLOPE

    res = _resolution_deg(cal.angle_increment)
    n_beams = cal.n_beams
    widest = int(round(LMS200_MAX_FOV_DEG / res)) + 1
    if n_beams > widest:  # was cut to `widest`, silently: a 270 deg Hokuyo log gave a 180 deg sensor YAML
        raise LmsbenchError(f"its scans hold {n_beams} beams at {res:g} deg, {(n_beams - 1) * res:g} deg from first to "
                            f"last: the LMS200 model spans at most {LMS200_MAX_FOV_DEG:g} deg ({widest} beams at "
                            f"{res:g} deg); calibrate and sim2real cannot model this scanner")
    if not np.isfinite(cal.noise.sigma_m):
        raise LmsbenchError(f"too few straight runs of beams at 1-4 m in {cal.n_scans} scan(s) to estimate the range "
                            f"noise ({cal.noise.n_used} beam triples); calibrate needs a log of real surfaces within "
                            "1-4 m of the laser")
    sigma = cal.noise.sigma_m
    if sigma > MAX_NOISE_SIGMA_M:  # the sensor model refuses it (a value in cm where metres are meant): say why here
        raise LmsbenchError(f"its range noise at 1-4 m reads {sigma * 1000:.0f} mm (1 sigma), more than the "
                            f"{MAX_NOISE_SIGMA_M * 1000:g} mm a laser rangefinder's model takes (sim.SensorConfig.noise_sigma); "
                            "calibrate cannot model this scanner")

    def rate(estimate) -> float:  # a rate with nothing to count (no beams of that kind): none seen
        return float(min(estimate.value, 0.5)) if np.isfinite(estimate.value) else 0.0

    slope = cal.noise_slope.value if np.isfinite(cal.noise_slope.value) else 0.0
    slope = float(np.clip(slope, -MAX_NOISE_SLOPE, MAX_NOISE_SLOPE))  # the model's bound: real logs' are below 0.001
    units = cal.units
    cap = cal.max_reading
    range_max = 81.83 if units == "cm" else 8.183
    return SensorConfig(
        n_beams=n_beams, resolution=math.radians(res), units=units, noise_sigma=float(sigma), quantise=cal.quantum_m > 0,
        dropout_prob=rate(cal.nan_rate), mixed_pixels=True, interlaced=res < 1.0,
        noise_sigma_per_m=float(slope), no_return_prob=rate(cal.no_return_rate),
        outlier_prob=0.0, max_reading=float(cap) if cap is not None and MIN_RANGE_MAX_M <= cap <= range_max else None,
    )


def _simulated_measurement(sensor, world: Any, duration: float = FIT_DURATION_S):
    """The log measurements of a simulated run of ``world`` (a name or a built sim.World)."""
    from sim import make_world, simulate_records

    w = make_world(world, FIT_SEED) if isinstance(world, str) else world
    records = simulate_records(w, FIT_SEED, duration, sensor, rate_hz=FIT_RATE_HZ)
    return calibrate_scans(records, seed=FIT_SEED)


def fit_sensor(cal: LogCalibration, world: str = "office", duration: float = FIT_DURATION_S) -> CalibrationResult:
    """The SensorConfig fitted to a log's measurements (see the module docstring); ``duration``:
    simulated seconds per spot width (shorter is faster and noisier)."""
    from sim import make_world

    sensor = base_sensor(cal)
    built = make_world(world, FIT_SEED)  # once: every fit run goes through the same world
    curve: list[tuple[float, float]] = []
    widths_deg = []  # the grid in degrees, as interpolated and rounded before the config held radians
    for steps in WIDTH_GRID_STEPS:
        w = steps * sensor.resolution_deg
        m = _simulated_measurement(sensor.replace(beam_width=math.radians(w), mixed_pixels=w > 0), built, duration)
        curve.append((math.radians(w), float(m.mixed_share.value)))
        widths_deg.append(w)
    widths = np.array(widths_deg)
    shares = np.maximum.accumulate(np.nan_to_num(np.array([c[1] for c in curve])))  # monotone
    target = float(cal.mixed_share.value) if np.isfinite(cal.mixed_share.value) else 0.0
    if target >= shares[-1]:
        width = float(widths[-1])
    else:
        first = int(np.searchsorted(shares, target, side="left"))
        if first == 0:
            width = float(widths[0])
        else:
            s0, s1 = shares[first - 1], shares[first]
            t = 0.0 if s1 <= s0 else (target - s0) / (s1 - s0)
            width = float(widths[first - 1] + t * (widths[first] - widths[first - 1]))
    width = round(width, 4)  # deg
    with_width = sensor.replace(beam_width=math.radians(width), mixed_pixels=width > 0)
    tail_sigma = float(cal.tail_sigma_m * np.sqrt(1.5))  # a beam's sigma: residuals mix three beams
    tail_curve: list[tuple[float, float]] = []
    baseline = 0.0
    for eps in TAIL_GRID:
        m = _simulated_measurement(with_width.replace(noise_tail_prob=eps, noise_tail_sigma=tail_sigma), built, duration)
        tail_curve.append((eps, float(m.tail_share.value)))
        if eps == 0.0:
            baseline = float(m.outlier_straight_rate.value)
    tail_prob = invert_probe_curve([c[1] for c in tail_curve], [c[0] for c in tail_curve], float(cal.tail_share.value))
    with_width = with_width.replace(noise_tail_prob=round(tail_prob, 4),
                                    noise_tail_sigma=round(tail_sigma, 5) if tail_prob > 0 else 0.0)
    patch_curve: list[tuple[float, float]] = []
    if with_width.noise_tail_prob > 0 and np.isfinite(cal.tail_clustering.value):
        for size in PATCH_GRID_M:
            m = _simulated_measurement(with_width.replace(noise_tail_patch_m=size), built, duration)
            patch_curve.append((size, float(m.tail_clustering.value)))
        patch = invert_probe_curve([c[1] for c in patch_curve], [c[0] for c in patch_curve], float(cal.tail_clustering.value))
        with_width = with_width.replace(noise_tail_patch_m=round(patch, 3))
    dark_curve: list[tuple[float, float]] = []
    nc = cal.nan_clustering
    if with_width.dropout_prob > 0 and np.isfinite(nc.value) and nc.value - 3 * nc.std > max(2 * with_width.dropout_prob,
                                                                                          NAN_CLUSTER_MIN):
        for size in DARK_GRID_M:
            m = _simulated_measurement(with_width.replace(dropout_patch_m=size), built, duration)
            dark_curve.append((size, float(m.nan_clustering.value)))
        dark = invert_probe_curve([c[1] for c in dark_curve], [c[0] for c in dark_curve], float(cal.nan_clustering.value))
        with_width = with_width.replace(dropout_patch_m=round(dark, 3))
    log_rate = float(cal.outlier_straight_rate.value)
    outlier = max(log_rate - (baseline if np.isfinite(baseline) else 0.0), 0.0) if np.isfinite(log_rate) else 0.0
    fitted = with_width.replace(outlier_prob=min(outlier, 0.5))
    return CalibrationResult(cal, fitted, curve, baseline, world, tail_curve, patch_curve, dark_curve, duration)


def calibrate_log(path: str | Path, world: str = "office", stride: int = 1, max_scans: int | None = None,
                  fit_duration: float = FIT_DURATION_S, report_skips: bool = True, **read_options: Any) -> CalibrationResult:
    """Measure a log (every ``stride``-th scan, at most ``max_scans``) and fit the sensor model;
    ``read_options`` go to ``lms200.read_log`` (topic, skip_bad_lines, geometry). What
    ``skip_bad_lines`` skipped is said on stderr (``logargs.report_skipped``) unless not
    ``report_skips``: calibrate and sim2real skipped bad lines silently, where the option's help
    and every other command report them.

    Raises:
        LmsbenchError: for a log without laser scans, an unsupported resolution or more than 180 deg.
    """
    reader = read_log(path, **read_options)
    named: list[BaseException] = []  # the reader's errors: they name the file already

    def records() -> Iterator[Any]:
        it = iter(reader)
        while True:
            try:
                rec = next(it)
            except StopIteration:
                return
            except LmsbenchError as exc:
                named.append(exc)
                raise
            yield rec

    def scans():
        first = None
        for k, rec in enumerate(records()):
            if max_scans is not None and k // stride >= max_scans:
                break
            if k % stride == 0:
                first = first or (k, rec.scan)
                same_geometry(rec.scan, first[1], f"scan {k}", f"scan {first[0]}")
                yield rec.scan

    # the reader's warnings (ranges in millimetres, a damaged line skipped) are said once the log is measured:
    # a log refused here (a malformed line after scan 50, too few straight runs) is its error alone (it said the
    # units warning, then the error: two lines for a user error)
    skips = io.StringIO()  # what --skip-bad-lines skipped, said with the held warnings (a refused run: its error alone)
    with warnings_after_checks():
        try:  # the log's errors (reading it, measuring it) name it; the fit's own errors are not the log's
            cal = calibrate_scans(scans())
            if report_skips:
                report_skipped(reader, stream=skips)
            # ranges in millimetres: what the reader warns of (its tally of the pass's first scans), told by the
            # error it leads to (calibrate tallied the same scans a second time beside the reader)
            problem = reader.units.problem()
            if problem is not None and not np.isfinite(cal.noise.sigma_m):  # the units are why (base_sensor's error)
                raise LmsbenchError(f"too few straight runs of beams at 1-4 m in {cal.n_scans} scan(s) to estimate the "
                                    f"range noise ({cal.noise.n_used} beam triples): {problem}")
            base_sensor(cal)  # what the log gives directly: a log too poor for a sensor model is the log's error
        except LmsbenchError as exc:
            # told by where it came from, not by the path's text within the message: a mixed-geometry log
            # named `deg` ("... 1 deg ...") went unnamed
            if any(exc is e for e in named):
                raise
            raise _naming(exc, path) from None
        except ValueError as exc:
            raise InputError(f"{path}: {exc}") from None
    sys.stderr.write(skips.getvalue())
    return fit_sensor(cal, world, fit_duration)


def _naming(exc: LmsbenchError, path: str | Path) -> LmsbenchError:
    """``exc`` with the log's path before its message, of the same class where that class takes a
    message alone (an InputError stays a ValueError for API callers)."""
    try:
        return type(exc)(f"{path}: {exc}")
    except TypeError:
        return LmsbenchError(f"{path}: {exc}")


def same_geometry(scan: Any, first: Any, name: str, first_name: str) -> None:
    """A log mixing scan geometries (two lasers, or a 0.5 and a 1 deg mode) cannot be one sensor
    model: its beam counts and steps were averaged (181 and 361 beams read as 0.75 deg)."""
    if len(scan) != len(first) or not np.isclose(scan.angle_increment, first.angle_increment, rtol=1e-6, atol=0.0):
        raise LmsbenchError(
            f"{name} has {len(scan)} beams at {np.rad2deg(scan.angle_increment):g} deg, {first_name} "
            f"{len(first)} at {np.rad2deg(first.angle_increment):g} deg: a sensor model has one geometry, so every scan "
            "used must have it (a log of two lasers: choose one with --topic)")


def _est(e) -> dict[str, float]:
    return {"value": _round(e.value), "std": _round(e.std), "n": int(e.n)}


def _round(v: float) -> float | None:
    return None if v is None or not np.isfinite(v) else float(f"{v:.6g}")


def calibration_section(result: CalibrationResult, source: str) -> dict[str, Any]:
    """The ``calibration`` section of the YAML: every measurement with its standard error."""
    c = result.measured
    return {
        "calibration": {
            "source": source,
            "scans": c.n_scans,
            **({"repeated_scans_passed_over": c.repeated_scans} if c.repeated_scans else {}),
            "beams_per_scan": c.n_beams,
            "quantum_m": c.quantum_m,
            "noise_sigma_1_4m": {"value": _round(c.noise.sigma_m), "std": _round(c.noise.sigma_std_m),
                                 "n": c.noise.n_used, "resolved": c.noise.resolved},
            "noise_sigma_per_m": _est(c.noise_slope),
            "noise_by_range": [{k: _round(v) if isinstance(v, float) else v for k, v in row.items()}
                               for row in c.noise_bins],
            "nan_rate": _est(c.nan_rate),
            "inf_rate": _est(c.inf_rate),
            "max_reading_rate": _est(c.max_reading_rate),
            "max_reading_m": c.max_reading,
            "no_return_rate_on_surfaces": _est(c.no_return_rate),
            "mixed_pixel_share_at_steps": _est(c.mixed_share),
            "isolated_outlier_rate": _est(c.outlier_rate),
            "isolated_outlier_rate_amid_straight_stretches": _est(c.outlier_straight_rate),
            "fit_world": result.world,
            "fit_duration_s": result.fit_duration,
            "simulated_mixed_share_by_beam_width": [[_round(w), _round(s)] for w, s in result.width_curve],  # rad
            "simulated_outlier_rate_amid_straight_stretches_without_outliers": _round(result.outlier_baseline),
            "residual_tail_share": _est(c.tail_share),
            "residual_tail_sigma_m": _round(c.tail_sigma_m),
            "simulated_tail_share_by_noise_tail_prob": [[_round(e), _round(s)] for e, s in result.tail_curve],
            "residual_tail_clustering": _est(c.tail_clustering),
            "simulated_tail_clustering_by_noise_tail_patch_m": [[_round(e), _round(s)] for e, s in result.patch_curve],
            "nan_clustering": _est(c.nan_clustering),
            "simulated_nan_clustering_by_dropout_patch_m": [[_round(e), _round(s)] for e, s in result.dark_curve],
        }
    }


def format_calibration(result: CalibrationResult) -> list[str]:
    """Human-readable lines: each measurement with its standard error, and the fitted fields."""
    c, s = result.measured, result.sensor

    def pm(e, scale: float = 1.0, unit: str = "") -> str:
        if not np.isfinite(e.value):
            return "n/a (nothing to measure in this log)"
        std = f"{e.std * scale:.2g}" if np.isfinite(e.std) else "n/a"
        return f"{e.value * scale:.4g} +- {std}{unit}"

    lines = [
        f"scans {c.n_scans}, {c.n_beams} beams at {np.rad2deg(c.angle_increment):g} deg, quantum {c.quantum_m * 1000:g} mm ({c.units} mode)"
        + (f"; {c.repeated_scans} scans passed over as repeats of the scan before them" if c.repeated_scans else ""),
        f"noise sigma at 1-4 m   {c.noise.sigma_m * 1000:.3f} +- {c.noise.sigma_std_m * 1000:.3f} mm  ({c.noise.n_used} triples)",
        f"noise growth           {pm(c.noise_slope, 1000, ' mm/m')}",
        "noise by range         " + ", ".join(f"{b['r_lo']:g}-{b['r_hi']:g} m: {b['sigma'] * 1000:.1f} mm" for b in c.noise_bins),
        f"nan (invalid) rate     {pm(c.nan_rate, 100, ' %')}",
        f"+inf (no return) rate  {pm(c.inf_rate, 100, ' %')}",
        f"max-reading rate       {pm(c.max_reading_rate, 100, ' %')}" + (f"  (cap {c.max_reading:g} m)" if c.max_reading else ""),
        f"no return on surfaces  {pm(c.no_return_rate, 100, ' %')}",
        f"mixed pixels at steps  {pm(c.mixed_share, 100, ' %')}  -> beam_width {s.beam_width:.6g} rad ({math.degrees(s.beam_width):.4g} deg)",
        f"isolated outliers      {pm(c.outlier_rate, 100, ' %')}; amid straight stretches "
        f"{pm(c.outlier_straight_rate, 100, ' %')}  -> outlier_prob {s.outlier_prob:.4g} "
        f"(simulated world alone: {result.outlier_baseline * 100:.3g} %)",
        f"residual tail          {pm(c.tail_share, 100, ' %')} at {c.tail_sigma_m * 1000:.1f} mm  -> noise_tail_prob "
        f"{s.noise_tail_prob:.4g} at {s.noise_tail_sigma * 1000:.1f} mm",
        f"tail clustering        {pm(c.tail_clustering)}  -> noise_tail_patch_m {s.noise_tail_patch_m:g}",
        f"nan clustering         {pm(c.nan_clustering)}  -> dropout_patch_m {s.dropout_patch_m:g}",
    ]
    return lines


#: the first line of every sensor YAML calibrate writes (``calibrate --out`` replaces only such a file)
HEADER_START = "# lmsbench calibrate "


def write_sensor_yaml(result: CalibrationResult, path: Path, source: str) -> None:
    """The sensor config (top-level fields, read by SensorConfig.from_yaml) plus the measurements,
    written whole or not at all (``experiments.provenance.write_record``): written in place, a full
    disk or a stop while writing left ``calibrate --out S.yaml`` a cut YAML, the earlier calibration
    in S.yaml lost and the cut file not valid YAML for ``--sensor``."""
    from experiments.provenance import write_record

    header = (f"{HEADER_START[2:]}{source}\n"
              "sensor model fitted to the log; read with SensorConfig.from_yaml or --sensor FILE.yaml\n"
              "the calibration section holds every measurement with its standard error (bootstrap over scans)")
    extra = calibration_section(result, source)
    write_record(path, lambda p: result.sensor.to_yaml(p, header=header, extra=extra))


def sensor_from_option(path: str | Path | None, default: Any = None, **changes: Any) -> Any:
    """The SensorConfig of a ``--sensor FILE.yaml`` option (with ``changes``), or ``default``."""
    if path is None:
        return default
    from sim import SensorConfig

    sensor = SensorConfig.from_yaml(path)
    return sensor.replace(**changes) if changes else sensor

