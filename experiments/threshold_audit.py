"""Ground-truth audit of split_merge's and iepf's thresholds (issue #13 item 4): line F1, explained
fraction and ray RMSE against the simulator's exact lines, with the LMS200's fixed thresholds and
with thresholds that follow the noise, over range noise, beam step and an interlaced sweeps'
offset. ``python -m experiments.threshold_audit [WORLD] [OUT.csv]``; the tables are in
docs/realdata.md ("Audit of the baselines' thresholds").

Scans: the simulator's noiseless ranges (cm codes, not interlaced, so each scan has the truth of
one pose) plus seeded Gaussian noise and, for "0.5deg+zz13", the two 1 deg sweeps offset by
13 mm (even beams +6.5 mm, odd -6.5 mm: MIT CSAIL's 12 mm neighbour scatter over 5 mm within a
sweep), rounded to 1 cm. Every extractor gets the scans' neighbour scatter as ``sigma`` (what
``compare`` gives a log); the variants differ in ``sigma_fit`` and the thresholds' multipliers.
"""

from __future__ import annotations

import dataclasses
import math
import sys
from typing import Any

import numpy as np
import pandas as pd

SEEDS = (0, 1, 2)
DURATION_S, RATE_HZ = 150.0, 0.4
GEOMETRIES = {"0.5deg": (361, 0.5, 0.0), "1deg": (181, 1.0, 0.0), "0.5deg+zz13": (361, 0.5, 0.013)}
NOISES_M = (0.005, 0.010, 0.015, 0.025)
METHODS = ("split_merge", "iepf")


def noisy(records: list[Any], sigma: float, zigzag: float, rng: np.random.Generator) -> list[Any]:
    """``records`` with Gaussian range noise ``sigma`` (m), the sweeps offset by ``zigzag`` (m) and
    ranges rounded to 1 cm (cm codes)."""
    out = []
    for rec in records:
        s = rec.scan
        r = s.ranges.copy()
        fin = np.isfinite(r)
        offset = np.where(np.arange(r.size) % 2 == 0, 0.5, -0.5) * zigzag
        r[fin] = np.round(r[fin] + rng.normal(0.0, sigma, int(fin.sum())) + offset[fin], 2)
        out.append(dataclasses.replace(rec, scan=s.replace(ranges=r)))  # odom, truth, corrected kept
    return out


def variants(neighbour: float, fit: float) -> dict[str, dict[str, dict[str, Any]]]:
    """Per variant, the split_merge / iepf overrides: "fixed" the LMS200's 3 / 4 cm split and 1 cm
    merge (the defaults before the audit), "fit" the defaults (thresholds following ``fit_sigma``),
    "neighbour" the same rule on the neighbour scatter."""
    fixed = dict(split_sigmas=0.0, merge_sigmas=0.0)
    return {"fixed": {m: dict(fixed) for m in METHODS},
            "fit": {m: dict(sigma_fit=fit) for m in METHODS},
            "neighbour": {m: dict(sigma_fit=neighbour) for m in METHODS}}


def run(world: str = "office") -> pd.DataFrame:
    """One row per geometry, noise, seed, variant and method (the sensor method once, as reference)."""
    import sim
    from experiments.compare import Source, compare
    from features.noise_estimate import fit_sigma, neighbour_sigma

    rows = []
    for geometry, (n_beams, step_deg, zigzag) in GEOMETRIES.items():
        for seed in SEEDS:
            sensor = sim.SensorConfig(n_beams=n_beams, resolution=math.radians(step_deg), units="cm", noise_sigma=0.0,
                                      quantise=False, interlaced=False)
            w = sim.make_world(world, seed=seed)
            clean = sim.simulate_records(world=w, seed=seed, duration=DURATION_S, sensor=sensor, rate_hz=RATE_HZ)
            truths = [sim.visible_truth(w, rec.truth, sensor) for rec in clean]
            for sigma in NOISES_M:
                recs = noisy(clean, sigma, zigzag, np.random.default_rng([seed, round(sigma * 1e4), round(zigzag * 1e4)]))
                neighbour, fit = neighbour_sigma(recs), fit_sigma(recs)
                for variant, params in variants(neighbour, fit).items():
                    src = Source.from_records(recs, truths, name=world, seed=seed)
                    src.sigma_r, src.extractor_sigma = sigma, neighbour
                    methods = list(METHODS) + (["sensor"] if variant == "fixed" else [])
                    table = compare([src], methods, params=params)
                    for method, g in table.groupby("method"):
                        rows.append(dict(geometry=geometry, noise_mm=1e3 * sigma, seed=seed, variant=variant,
                                         method=method, neighbour_mm=1e3 * neighbour, fit_mm=1e3 * fit,
                                         tp=int(g.tp.sum()), fp=int(g.fp.sum()), fn=int(g.fn.sum()),
                                         explained_3cm=float(g.explained_3cm.mean()),
                                         ray_ss=float((g.ray_rmse**2 * g.n_explained_3cm).sum()),
                                         n_explained=float(g.n_explained_3cm.sum()),
                                         truth_explained_3cm=float(g.truth_explained_3cm.mean()),
                                         lines_per_scan=float(g.n_lines.mean())))
    return pd.DataFrame(rows)


def summary(rows: pd.DataFrame) -> pd.DataFrame:
    """Pooled over seeds: line F1 (and its range over seeds), explained fraction, ray RMSE (mm)."""
    rows = rows.assign(f1=2 * rows.tp / (2 * rows.tp + rows.fp + rows.fn))
    g = rows.groupby(["geometry", "noise_mm", "method", "variant"], sort=False)
    out = g.agg(tp=("tp", "sum"), fp=("fp", "sum"), fn=("fn", "sum"), f1_min=("f1", "min"), f1_max=("f1", "max"),
                explained_3cm=("explained_3cm", "mean"), truth_explained_3cm=("truth_explained_3cm", "mean"),
                ray_ss=("ray_ss", "sum"), n_explained=("n_explained", "sum"), lines_per_scan=("lines_per_scan", "mean"),
                fit_mm=("fit_mm", "mean"), neighbour_mm=("neighbour_mm", "mean"))
    out["f1"] = 2 * out.tp / (2 * out.tp + out.fp + out.fn)
    out["ray_rmse_mm"] = 1e3 * np.sqrt(out.ray_ss / out.n_explained)
    return out.drop(columns=["ray_ss", "n_explained"]).reset_index()


USAGE = "usage: python -m experiments.threshold_audit [WORLD] [OUT.csv]"
SEE_HELP = "(see python -m experiments.threshold_audit --help)"  # an error is one line, as lmsbench's


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if any(a in ("-h", "--help") for a in args):  # was taken for a world: a traceback, "unknown world '--help'"
        print(f"{USAGE}\n\n{__doc__}")
        return 0
    if len(args) > 2 or any(a.startswith("-") for a in args):
        print(f"threshold_audit: error: unrecognized arguments: {' '.join(args)} {SEE_HELP}", file=sys.stderr)
        return 2
    import sim

    if args and args[0] not in sim.WORLD_NAMES:  # before the first simulation, in one line
        print(f"threshold_audit: error: unknown world {args[0]!r}; known worlds: {', '.join(sim.WORLD_NAMES)} {SEE_HELP}",
              file=sys.stderr)
        return 2
    rows = run(args[0] if args else "office")
    if len(args) > 1:
        rows.to_csv(args[1], index=False)
    with pd.option_context("display.width", 200, "display.max_rows", 500):
        print(summary(rows).round(3).to_string(index=False))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
