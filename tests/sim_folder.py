"""A simulate-like folder for the slam tests: scans.clf, groundtruth.tum and, optionally,
world.json, laid out as `lmsbench simulate` writes them (without its map and config, which
``experiments.simulation.run_simulation`` adds at the cost of a slower run)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from lms200 import Record, write_log, write_tum


def write_sim_folder(folder: Path, records: list[Record], world_seed: int | None = None) -> Path:
    """Write ``records`` into ``folder`` (made if missing): their scans as scans.clf, their true
    poses as groundtruth.tum, and the office world of ``world_seed`` as world.json when given."""
    folder.mkdir(parents=True, exist_ok=True)
    write_log(folder / "scans.clf", records)
    truth = np.array([(r.scan.stamp, *r.truth) for r in records])
    write_tum(folder / "groundtruth.tum", truth[:, 0], truth[:, 1:])
    if world_seed is not None:
        from sim import make_world

        make_world("office", seed=world_seed).to_json(folder / "world.json")
    return folder
