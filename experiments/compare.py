"""Every extractor on identical scans: timing interleaved per scan in one process, scores against
ground truth where the source has it, and a summary per source and method.

Sources: simulated worlds (``sim.simulate_records`` with the truth of ``sim.visible_truth`` at each
record's true pose) or a real log (``lms200.read_log``; scored by ``explained_fraction`` only).
Timing wraps only the method's function (``time.perf_counter_ns``); on each scan the methods run
in an order rotated by one per scan, so no method always runs first (cold caches) or last.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

import numpy as np
import pandas as pd

from features.registry import available_methods, backend_of, get_method, make_config
from features.scoring import ScoreConfig, explained_fraction, prf, score_scan
from lms200 import LmsbenchError, Record, read_log

WORLD_NAMES = ("office", "corridor", "angles", "pillars", "random")


@dataclass
class Source:
    """Scans to compare on. ``truth_of(record)`` gives the visible truth, or is None (real logs)."""

    name: str
    kind: str  # "sim" or "log"
    seed: int | None
    records: Iterable[Record]
    truth_of: Callable[[Record], Any] | None = None
    total: int | None = None
    settings: dict[str, Any] = dataclasses.field(default_factory=dict)  # what produced the scans (saved beside results)

    @classmethod
    def from_records(cls, records: Sequence[Record], truths: Sequence[Any] | None = None, name: str = "sim",
                     seed: int | None = None) -> "Source":
        """Records already in memory (a simulated run, a log read once), with their visible truths
        (one per record, sensor frame) when known: scored against them, else like a log."""
        records = list(records)
        if truths is None:
            return cls(name, "log", seed, records, None, len(records))
        truths = list(truths)
        if len(truths) != len(records):
            raise LmsbenchError(f"{len(records)} records but {len(truths)} truths")
        by_index = {id(r): t for r, t in zip(records, truths)}
        return cls(name, "sim", seed, records, lambda rec: by_index[id(rec)], len(records))


def sim_source(world: str, seed: int = 0, duration: float = 30.0, rate_hz: float | None = 2.0,
               sensor: Any = None) -> Source:
    """Records of the simulated ``world`` (seeded) with their visible truth (sensor frame).

    The default sensor is the LMS200 model without interlaced timing: the truth is that of a single
    pose, so a scan whose beams come from poses up to 20 ms apart (1.2 deg of turn) would charge the
    robot's motion to the extractor. Pass ``sensor=sim.SensorConfig()`` for the moving-scan model.
    """
    import sim

    sensor = sensor if sensor is not None else sim.SensorConfig(interlaced=False)
    w = sim.make_world(world, seed=seed)
    records = sim.simulate_records(world=w, seed=seed, duration=duration, sensor=sensor, rate_hz=rate_hz)
    settings = dict(world=world, seed=seed, duration=duration, rate_hz=rate_hz, sensor=dataclasses.asdict(sensor))
    return Source(world, "sim", seed, records, _truth_in(w, sensor), len(records), settings)


def _truth_in(world: Any, sensor: Any) -> Callable[[Record], Any]:
    import sim

    def truth_of(rec: Record) -> Any:
        if rec.truth is None:
            raise LmsbenchError(f"simulated record at t={rec.scan.stamp} has no true pose")
        return sim.visible_truth(world, rec.truth, sensor)

    return truth_of


def is_simulation_folder(path: str | Path) -> bool:
    """A ``lmsbench simulate`` output folder (scans.clf and world.json)."""
    p = Path(path)
    return p.is_dir() and (p / "scans.clf").is_file() and (p / "world.json").is_file()


def folder_source(path: str | Path, stride: int = 1, max_scans: int | None = None) -> Source:
    """The scans of a ``lmsbench simulate`` folder, scored against the visible truth of its
    world.json at each scan's true pose (its TRUEPOS lines), for the sensor of its config.yaml.

    The truth is that of the pose at the scan's stamp: a folder simulated with the default
    interlaced sensor charges the robot's motion within a scan (up to 1.2 deg) to the extractor."""
    import yaml

    import sim

    p = Path(path)
    world = sim.World.from_json(p / "world.json")
    settings: dict[str, Any] = {"folder": str(p)}
    sensor = sim.SensorConfig()
    if (p / "config.yaml").is_file():
        cfg = yaml.safe_load((p / "config.yaml").read_text()) or {}
        if not isinstance(cfg, dict):
            raise LmsbenchError(f"{p / 'config.yaml'}: not a simulate config")
        sensor = sim.SensorConfig(**(cfg.get("sensor") or {}))
        settings.update({k: cfg.get(k) for k in ("world", "seed", "duration", "rate_hz")})
    settings["sensor"] = dataclasses.asdict(sensor)
    inner = log_source(p / "scans.clf", stride, max_scans)
    seed = settings.get("seed")
    return Source(p.name, "sim", int(seed) if seed is not None else None, inner.records, _truth_in(world, sensor),
                  max_scans, settings)


def log_source(path: str | Path, stride: int = 1, max_scans: int | None = None) -> Source:
    """Every ``stride``-th scan of a real log (CARMEN or bag); no ground truth."""
    if stride < 1:
        raise LmsbenchError(f"stride: must be >= 1, got {stride}")
    reader = read_log(path)

    def records() -> Iterable[Record]:
        for k, rec in enumerate(reader):
            if k % stride == 0:
                yield rec

    return Source(Path(path).name, "log", None, records(), None, max_scans, {"log": str(path), "stride": stride})


def parse_sources(specs: Sequence[str], seeds: Sequence[int] = (0,), duration: float = 30.0,
                  rate_hz: float | None = 2.0, stride: int = 1, max_scans: int | None = None,
                  sensor: Any = None) -> list[Source]:
    """Sources from command-line words: a world name (one source per seed), ``world:seed``, a
    ``lmsbench simulate`` folder, or the path of a log. ``sensor`` (a ``sim.SensorConfig``) is the
    simulated worlds' sensor model (a simulate folder has its own, in its config.yaml).

    Raises:
        LmsbenchError: a word that is none of these, a bad seed, or a log of the wrong kind.
    """
    out: list[Source] = []
    for spec in specs:
        name, colon, seed = spec.partition(":")
        if name in WORLD_NAMES:
            if colon and not (seed.isdigit() and int(seed) < 2**32):
                raise LmsbenchError(f"{spec}: the seed after the colon must be a whole number >= 0, got {seed!r}")
            for s in ([int(seed)] if colon else seeds):
                out.append(sim_source(name, s, duration, rate_hz, sensor))
        elif is_simulation_folder(spec):
            out.append(folder_source(spec, stride, max_scans))
        else:
            if not Path(spec).exists():
                raise LmsbenchError(f"{spec!r} is neither a world ({', '.join(WORLD_NAMES)}), a simulate folder "
                                    "nor an existing log")
            out.append(log_source(spec, stride, max_scans))
    return out


def check_sources(specs: Sequence[str]) -> None:
    """Check command-line source words before any work: world names and seeds, simulate folders
    (world.json loads), logs (their kind, and at least one laser scan)."""
    from experiments.options import check_log

    for spec in specs:
        name, colon, seed = spec.partition(":")
        if name in WORLD_NAMES:
            if colon and not (seed.isdigit() and int(seed) < 2**32):
                raise LmsbenchError(f"{spec}: the seed after the colon must be a whole number >= 0, got {seed!r}")
            continue
        if is_simulation_folder(spec):
            import sim

            try:
                sim.World.from_json(Path(spec) / "world.json")
            except LmsbenchError:
                raise
            except (ValueError, KeyError, TypeError) as exc:
                raise LmsbenchError(f"{spec}/world.json: not a world ({type(exc).__name__}: {exc})") from None
            spec = str(Path(spec) / "scans.clf")
        elif not Path(spec).exists():
            close = [w for w in WORLD_NAMES if _close(w, name)]
            hint = f" (did you mean {close[0]}?)" if close else ""
            raise LmsbenchError(f"{spec!r} is neither a world ({', '.join(WORLD_NAMES)}){hint}, a simulate folder "
                                "nor an existing log")
        check_log(spec)
        if next(iter(read_log(spec)), None) is None:
            raise LmsbenchError(f"{spec}: no laser messages found (not a CARMEN log with FLASER / ROBOTLASER1 "
                                "lines, nor a bag with LaserScan messages)")


def _check_types(method: str, overrides: dict[str, Any]) -> None:
    """An override has the kind of its field's default: a number for a number, true/false for a
    flag, text for text (configs check ranges, not types)."""
    default = dataclasses.asdict(make_config(method))
    for name, value in overrides.items():
        if name not in default:
            continue  # make_config names unknown fields
        d = default[name]
        number = isinstance(value, (int, float)) and not isinstance(value, bool)
        if isinstance(d, bool):
            ok = isinstance(value, bool)
            kind = "true or false"
        elif isinstance(d, (int, float)):
            ok = number and (isinstance(d, float) or float(value).is_integer())
            kind = "a whole number" if isinstance(d, int) else "a number"
        elif isinstance(d, str):
            ok = isinstance(value, str)
            kind = "text"
        else:
            continue
        if not ok:
            raise LmsbenchError(f"{method}: {name} must be {kind} (default {d!r}), got {value!r}")


def _close(a: str, b: str) -> bool:
    import difflib

    return difflib.SequenceMatcher(None, a, b).ratio() >= 0.75


def _errors(values: np.ndarray) -> tuple[float, float]:
    if values.size == 0:
        return float("nan"), float("nan")
    return float(np.mean(values)), float(np.sqrt(np.mean(values**2)))


def compare(
    sources: Sequence[Source | str],
    methods: Sequence[str] | None = None,
    *,
    params: dict[str, dict[str, Any]] | None = None,
    score_config: ScoreConfig | None = None,
    sigma: float = 0.005,
    max_scans: int | None = None,
    progress: bool = False,
    matches: list[dict[str, Any]] | None = None,
) -> pd.DataFrame:
    """Run ``methods`` (default: every available one) on every scan of ``sources``.

    Args:
        sources: Source objects, or strings as for :func:`parse_sources` (seed 0).
        methods: extractor names; the order does not matter (it is rotated per scan).
        params: per-method overrides of config fields, ``{"hough": {"rho_step": 0.01}}``.
        score_config: line / corner matching tolerances.
        sigma: range noise (m) for the explained fraction (3 sigma band).
        max_scans: at most this many scans per source.
        progress: show a tqdm progress bar.
        matches: if a list, one dict per matched line is appended to it (method, source, seed,
            scan, face, rho_err, alpha_err): see :func:`common_errors`.

    Returns:
        A tidy table, one row per method x scan: method, backend ("numba" or "numpy", see
        ``features.registry.backend_of``: speed ratios are fair only between equal backends), source, kind, seed, scan, stamp, n_valid,
        n_lines, n_corners, microseconds (wall, ``perf_counter_ns``), time_ms (the same in ms), cpu_microseconds (this
        thread's CPU time, ``thread_time_ns``: what a pre-empted call really used), explained,
        range_rms (m) and, for simulated sources,
        n_truth, tp, fp, fn, precision, recall, f1, rho_err_mean / rho_err_rms (m),
        alpha_err_mean / alpha_err_rms (rad), endpoint_err_mean (m), n_truth_corners, corner_tp,
        corner_fp, corner_fn, corner_err_mean (m).
    """
    methods = list(methods) if methods else available_methods()
    params = params or {}
    runs = [(m, get_method(m).run, make_config(m, **params.get(m, {}))) for m in methods]
    backends = {name: backend_of(name, cfg) for name, _, cfg in runs}
    srcs = [s for spec in sources for s in ([spec] if isinstance(spec, Source) else parse_sources([spec]))]
    total = sum(min(s.total or 0, max_scans or s.total or 0) for s in srcs) or None
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=total, unit="scan", desc="compare")
    rows: list[dict[str, Any]] = []
    warmed = False
    for src in srcs:
        for k, rec in enumerate(src.records):
            if max_scans is not None and k >= max_scans:
                break
            scan = rec.scan
            truth = src.truth_of(rec) if src.truth_of else None
            n_valid = int(np.count_nonzero(scan.valid))
            shift = k % len(runs)
            if not warmed:  # first calls load compiled kernels and fill caches: not timed
                for _, fn, cfg in runs:
                    fn(scan, cfg)
                warmed = True
            for name, fn, cfg in runs[shift:] + runs[:shift]:
                t0, c0 = time.perf_counter_ns(), time.thread_time_ns()
                fs = fn(scan, cfg)
                c1, t1 = time.thread_time_ns(), time.perf_counter_ns()
                elapsed, cpu = t1 - t0, c1 - c0
                explained, range_rms = explained_fraction(fs, scan, sigma)
                row = dict(method=name, backend=backends[name], source=src.name, kind=src.kind, seed=src.seed, scan=k,
                           stamp=scan.stamp, n_valid=n_valid, n_lines=len(fs.lines),
                           n_corners=len(fs.corners), microseconds=elapsed / 1e3, cpu_microseconds=cpu / 1e3,
                           explained=explained, range_rms=range_rms)
                if truth is not None:
                    score = score_scan(fs, truth, score_config)
                    row.update(_score_row(score))
                    if matches is not None:
                        for face, dr, da in zip(score.matches[:, 1].tolist(), score.rho_errors.tolist(),
                                                score.alpha_errors.tolist()):
                            matches.append(dict(method=name, source=src.name, seed=src.seed, scan=k,
                                                face=face, rho_err=dr, alpha_err=da))
                rows.append(row)
            if bar is not None:
                bar.update(1)
    if bar is not None:
        bar.close()
    table = pd.DataFrame(rows)
    if not table.empty:
        table.insert(table.columns.get_loc("microseconds") + 1, "time_ms", table["microseconds"] / 1e3)
    return table


def _score_row(s) -> dict[str, Any]:
    rho_mean, rho_rms = _errors(s.rho_errors)
    alpha_mean, alpha_rms = _errors(s.alpha_errors)
    return dict(
        n_truth=s.n_truth, tp=s.tp, fp=s.fp, fn=s.fn, precision=s.precision, recall=s.recall, f1=s.f1,
        rho_err_mean=rho_mean, rho_err_rms=rho_rms, alpha_err_mean=alpha_mean, alpha_err_rms=alpha_rms,
        endpoint_err_mean=float(np.mean(s.endpoint_errors)) if s.tp else float("nan"),
        n_truth_corners=s.corner_tp + s.corner_fn, corner_tp=s.corner_tp, corner_fp=s.corner_fp,
        corner_fn=s.corner_fn,
        corner_err_mean=float(np.mean(s.corner_errors)) if s.corner_tp else float("nan"),
    )


def _weighted(values: pd.Series, weights: pd.Series) -> float:
    ok = values.notna() & (weights > 0)
    return float((values[ok] * weights[ok]).sum() / weights[ok].sum()) if ok.any() else float("nan")


def summarise(table: pd.DataFrame, reference: str = "sensor") -> pd.DataFrame:
    """One row per source x method: counts pooled over scans and seeds (micro-averaged precision,
    recall, F1), error bias and RMS pooled over matched lines (rho in mm, alpha in deg), corner
    scores, mean explained fraction, time per scan (mean and median, microseconds), scans per
    second and ``speed_vs_sensor`` = the reference method's time / this method's (above 1 =
    faster than the reference; nan when the reference did not run). Both rates use the median
    time: on a shared machine a pre-empted call can take 100 times the usual, which swamps a mean.
    ``cpu_us_median`` and ``cpu_speed_vs_sensor`` are the same from CPU time: under load a call
    longer than the scheduler's slice is pre-empted more often, which wall time penalises.
    ``time_ms_p05`` / ``_p25`` / ``_median`` / ``_p75`` / ``_p95``: quantiles of the wall time per
    scan in ms (the figures' error bars)."""
    out = []
    for (source, method), g in table.groupby(["source", "method"], sort=False):
        row: dict[str, Any] = dict(source=source, method=method, kind=g["kind"].iloc[0], scans=len(g),
                                   backend=g["backend"].iloc[0] if "backend" in g else "numpy",
                                   seeds=g["seed"].nunique(), lines_per_scan=g["n_lines"].mean())
        if "tp" in g and g["tp"].notna().any():
            tp, fp, fn = (int(g[c].sum()) for c in ("tp", "fp", "fn"))
            p, r, f = prf(tp, fp, fn)
            ctp, cfp, cfn = (int(g[c].sum()) for c in ("corner_tp", "corner_fp", "corner_fn"))
            cp, cr, cf = prf(ctp, cfp, cfn)
            w = g["tp"]
            row.update(
                tp=tp, fp=fp, fn=fn, precision=p, recall=r, f1=f,
                rho_bias_mm=1e3 * _weighted(g["rho_err_mean"], w),
                rho_rms_mm=1e3 * np.sqrt(_weighted(g["rho_err_rms"] ** 2, w)),
                alpha_bias_deg=np.rad2deg(_weighted(g["alpha_err_mean"], w)),
                alpha_rms_deg=np.rad2deg(np.sqrt(_weighted(g["alpha_err_rms"] ** 2, w))),
                endpoint_err_mm=1e3 * _weighted(g["endpoint_err_mean"], w),
                corner_precision=cp, corner_recall=cr, corner_f1=cf,
                corner_err_mm=1e3 * _weighted(g["corner_err_mean"], g["corner_tp"]),
            )
        row.update(explained=g["explained"].mean(), range_rms_mm=1e3 * g["range_rms"].mean(),
                   us_mean=g["microseconds"].mean(), us_median=g["microseconds"].median())
        if "cpu_microseconds" in g:
            row["cpu_us_median"] = g["cpu_microseconds"].median()
        row["scans_per_s"] = 1e6 / row["us_median"]
        ms = g["microseconds"] / 1e3
        for q, label in ((0.05, "p05"), (0.25, "p25"), (0.5, "median"), (0.75, "p75"), (0.95, "p95")):
            row[f"time_ms_{label}"] = float(ms.quantile(q))
        out.append(row)
    summary = pd.DataFrame(out)
    if summary.empty:
        return summary
    ref = summary[summary["method"] == reference].set_index("source")["us_median"]
    summary["speed_vs_sensor"] = summary["source"].map(ref) / summary["us_median"]
    if "cpu_us_median" in summary:
        ref = summary[summary["method"] == reference].set_index("source")["cpu_us_median"]
        summary["cpu_speed_vs_sensor"] = summary["source"].map(ref) / summary["cpu_us_median"]
    return summary


def common_errors(matches: pd.DataFrame) -> pd.DataFrame:
    """Errors on the faces every method matched (per source): the like-for-like accuracy, since a
    method that finds more (harder: far, short, grazing) faces pools larger errors. One row per
    source x method: n_common, rho_rms_common_mm, alpha_rms_common_deg."""
    cols = ["source", "method", "n_common", "rho_rms_common_mm", "alpha_rms_common_deg"]
    if matches.empty:
        return pd.DataFrame(columns=cols)
    out = []
    key = ["seed", "scan", "face"]
    for source, g in matches.groupby("source", sort=False):
        n_methods = g["method"].nunique()
        seen = g.groupby(key)["method"].nunique()
        common = seen[seen == n_methods].index
        c = g.set_index(key).loc[lambda d: d.index.isin(common)]
        for method, h in c.groupby("method", sort=False):
            out.append(dict(source=source, method=method, n_common=len(h),
                            rho_rms_common_mm=1e3 * float(np.sqrt(np.mean(h["rho_err"] ** 2))),
                            alpha_rms_common_deg=float(np.rad2deg(np.sqrt(np.mean(h["alpha_err"] ** 2))))))
    return pd.DataFrame(out, columns=cols)


def format_summary(summary: pd.DataFrame) -> str:
    """The summary as a fixed-width text table (the columns that exist)."""
    cols = ["source", "method", "backend", "scans", "f1", "precision", "recall", "rho_bias_mm", "rho_rms_mm",
            "alpha_bias_deg", "alpha_rms_deg", "rho_rms_common_mm", "alpha_rms_common_deg", "corner_precision", "corner_recall", "corner_err_mm",
            "explained", "range_rms_mm", "us_median", "scans_per_s", "speed_vs_sensor", "cpu_us_median",
            "cpu_speed_vs_sensor"]
    cols = [c for c in cols if c in summary]
    text = summary[cols].to_string(index=False, float_format=lambda v: f"{v:.3g}", na_rep="-")
    if "backend" in summary and summary["backend"].nunique() > 1:
        mixed = ", ".join(f"{m}={b}" for m, b in summary.drop_duplicates("method")[["method", "backend"]].values)
        text += (f"\nnote: the methods ran on different backends ({mixed}; numba = compiled kernels, numpy = "
                 "vectorised numpy): speed ratios between different backends are not like for like")
    return text


def resolved_configs(methods: Sequence[str], params: dict[str, dict[str, Any]] | None = None) -> dict[str, Any]:
    """Each method's full config as plain data (saved beside the results).

    Raises:
        LmsbenchError: an override of a value that cannot work (``rho_step=0``, ``k="abc"``)."""
    params = params or {}
    out = {}
    for m in methods:
        _check_types(m, params.get(m, {}))
        try:
            out[m] = dataclasses.asdict(make_config(m, **params.get(m, {})))
        except LmsbenchError:
            raise
        except (ValueError, TypeError) as exc:
            raise LmsbenchError(f"{m}: {' '.join(str(exc).split())}") from None
    return out
