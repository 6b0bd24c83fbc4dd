"""Every bad input to every command: exit status 2, exactly one line on stderr naming the problem,
no traceback, no hang, no output written. The cases of issue 16 and more of the same kinds.

Each case runs ``experiments.cli.main`` in this process under a 20 s alarm (a hang fails the
case instead of the suite); validation runs before any work, so a passing case takes
milliseconds. The Ctrl-C and Dask cases run in subprocesses.
"""

from __future__ import annotations

import gzip
import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from experiments.cli import main
from lms200 import Record, Scan, write_log

ROOT = Path(__file__).resolve().parents[1]


class Hang(Exception):
    pass


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Inputs of every kind, good and bad."""
    d = tmp_path_factory.mktemp("inputs")
    f = {"dir": d}
    (d / "binary.bin").write_bytes(bytes(range(256)) * 8)
    (d / "binary.clf").write_bytes(bytes(range(256)) * 8)
    (d / "binary.yaml").write_bytes(b"\x00\x01\x02" * 100)
    (d / "binary.json").write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(200))
    (d / "list.json").write_text("[1, 2]")
    (d / "nan_walls.json").write_text('{"walls": [[0, 0, NaN, 1]]}')
    (d / "bad_boxes.json").write_text('{"boxes": [[1, 2]]}')
    (d / "deep.json").write_text("[" * 100000 + "]" * 100000)  # json's RecursionError: an internal error
    (d / "far_walls.json").write_text('{"walls": [[0, 0, 1e308, 1e308]]}')  # overflow warnings, then an error
    # world.json files whose route or scan plane cannot work (the tour indexed them: IndexError)
    from sim import make_world

    office = make_world("office", 0).to_dict()
    for name, change in {"route_index": {"route_targets": [999]}, "route_nodes": {"route_nodes": []},
                         "scan_height": {"scan_height": float("nan")}, "route_apart": {"route_edges": [[1, 2]]},
                         "flat_box": {"boxes": [[0, 0, 0, 1, 0, 0, 1]]}}.items():
        (d / f"world_{name}.json").write_text(json.dumps({**office, **change}))
    # a simulate folder whose config.yaml is damaged (compare scores its scans with that sensor model)
    (d / "simbroken").mkdir()
    (d / "simbroken" / "world.json").write_text(json.dumps(office))
    (d / "simbroken" / "config.yaml").write_text("sensor: {noise_sigma: 0.005, bogus: 1}\n")
    (d / "plain.gz").write_text("FLASER 3 1.0 1.0 1.0 0 0 0 0 0 0 1.0 host 1.0\n")
    (d / "fake.bag").write_text("not a bag\n")
    (d / "empty.clf").write_text("")
    (d / "notalog.clf").write_text("hello\nworld\n")
    (d / "empty_dir").mkdir()
    (d / "notes_dir").mkdir()
    (d / "notes_dir" / "metrics.json").write_text("my notes\n")  # a user's, not a slam run's
    for name in ("pipe.clf", "pipe.yaml", "pipe.json"):  # named pipes with no writer: open() waited for ever
        os.mkfifo(d / name)
    (d / "bag_badmeta").mkdir()  # rosbags said "Could not load YAML ... "<unicode string>", line 1, ..."
    (d / "bag_badmeta" / "metadata.yaml").write_text("rosbag2_bagfile_information: [1\n")
    (d / "bag_listmeta").mkdir()
    (d / "bag_listmeta" / "metadata.yaml").write_text("- 1\n")
    (d / "a_file").write_text("x")
    (d / "pkg").mkdir()
    (d / "pkg" / "__init__.py").write_text("")
    ranges = np.full(361, 3.0)
    good = [Record(Scan.lms200(ranges, stamp=0.1 * k)) for k in range(5)]
    write_log(d / "good.clf", good)
    backwards = [Record(Scan.lms200(ranges, stamp=s)) for s in (0.0, 0.1, 0.2, 0.15, 0.3)]
    write_log(d / "backwards.clf", backwards)
    write_log(d / "no_returns.clf", [Record(Scan.lms200(np.full(361, np.inf), stamp=0.1 * k)) for k in range(5)])
    # one log of two geometries (181 beams at 1 deg between 361 at 0.5 deg): calibrate averaged them to 0.75 deg
    wide = [Record(Scan(np.full(181, 3.0), -np.pi / 2, np.pi / 180, 0.0, 8.183, 0.1 * k)) for k in range(5)]
    write_log(d / "mixed.clf", [r for pair in zip(good, wide) for r in pair])
    odo = [Record(Scan.lms200(ranges, stamp=0.1 * k), odom=(0.1 * k, 0.0, 0.0)) for k in range(5)]
    write_log(d / "odo.bag", odo, fmt="bag")  # topics /scan and /odom
    write_log(d / "range_min_2.clf", [Record(Scan(ranges, -np.pi / 2, np.pi / 360, 2.0, 8.183, 0.1 * k)) for k in range(3)])
    write_log(d / "far.clf", [Record(Scan.lms200(np.full(361, 6.0), stamp=0.1 * k)) for k in range(5)])
    (d / "zero_beams.clf").write_text("FLASER 0 0 0 0 0 0 0 0.0 host 0.0\n")  # was "needs 11 fields, got 11"
    with gzip.open(d / "blank.clf.gz", "wb") as fh:  # of 1 GB of them: read to its end twice (> 40 s) for no laser line
        fh.write(b"\n" * 100_001)
    with gzip.open(d / "good.clf.gz", "wt") as fh:
        fh.write((d / "good.clf").read_text())
    (d / "empty.yaml").write_text("# nothing set yet\n")
    (d / "cut_short.clf").write_text((d / "good.clf").read_text()[:-300])  # a recording stopped mid-line
    os.symlink(d / "moved_away.clf", d / "dangling.clf")  # the data moved: a link to nothing
    # a simulator-like folder: scans.clf and its truth
    (d / "simrun").mkdir()
    write_log(d / "simrun" / "scans.clf", good)
    write_log(d / "simbroken" / "scans.clf", good)
    # simulate folders whose truth was edited: a nan, a stamp going back (slam: "internal error: ValueError")
    from lms200 import write_tum

    for name, row in (("sim_nan_truth", "0.2 nan 0 0 0 0 0 1"), ("sim_back_truth", "0.05 0 0 0 0 0 0 1")):
        (d / name).mkdir()
        write_log(d / name / "scans.clf", good)
        write_tum(d / name / "groundtruth.tum", 0.1 * np.arange(5), np.zeros((5, 3)))
        lines = (d / name / "groundtruth.tum").read_text().splitlines()
        (d / name / "groundtruth.tum").write_text("\n".join(lines[:4] + [row] + lines[4:]) + "\n")
    # sweep files
    (d / "sweep.yaml").write_text(yaml.safe_dump({"name": "t", "kind": "extract", "fixed": {"duration": 0.5},
                                                  "grid": {"extractor.k": [3]}}))
    base = {"name": "t", "kind": "extract", "fixed": {"duration": 0.5}, "grid": {"extractor.k": [3]}}
    bad_sweeps = {"sweep_seed": {"seeds": [-1]}, "sweep_dup_seed": {"seeds": [0, 0]},
                  "sweep_bare_seeds": {"seeds": 3}, "sweep_bare_grid": {"grid": {"extractor.k": "3, 5, 10"}},
                  "sweep_k": {"grid": {"extractor.k": [-3]}}, "sweep_noise": {"grid": {"sensor.noise_sigma": [-0.01]}},
                  "sweep_plain": {"fixed": {"duration": 0.5, "bogus": 1}}, "sweep_name": {"name": "../../x"},
                  "sweep_world": {"fixed": {"duration": 0.5, "world": "offfice"}},
                  "sweep_duration": {"fixed": {"duration": -1.0}},
                  "sweep_slam": {"kind": "slam", "grid": {"slam.association.gate_probability": [1.5]}},
                  "sweep_samples": {"random": {"extractor.ad_tau": {"uniform": [1.0, 2.0]}}, "samples": "abc"},
                  "sweep_huge": {"random": {"extractor.ad_tau": {"uniform": [1.0, 2.0]}}, "samples": 10**9},
                  "sweep_sample_seed": {"random": {"extractor.ad_tau": {"uniform": [1.0, 2.0]}}, "samples": 2,
                                        "sample_seed": -1},
                  "sweep_text_bounds": {"random": {"extractor.ad_tau": {"uniform": ["a", "b"]}}, "samples": 2},
                  "sweep_int_bounds": {"random": {"extractor.min_points": {"int": [1.5, 3]}}, "samples": 2},
                  "sweep_int_huge": {"random": {"extractor.min_points": {"int": [3, 10**24]}}, "samples": 2},
                  "sweep_uniform_wide": {"random": {"extractor.ad_tau": {"uniform": [-1e308, 1e308]}}, "samples": 2},
                  "sweep_big_seed": {"seeds": [2**40]}, "sweep_name_number": {"name": 5},
                  "sweep_cells": {"grid": {"extractor.k": list(range(3, 503)), "extractor.ad_tau": list(range(1, 301))}},
                  "sweep_long": {"fixed": {"duration": 1e9}}, "sweep_short": {"fixed": {"duration": 0.001}}}
    for name, change in bad_sweeps.items():
        (d / f"{name}.yaml").write_text(yaml.safe_dump({**base, **change}))
    (d / "list.yaml").write_text("- 1\n- 2\n")
    (d / "huge.yaml").write_text("noise_sigma: 0.005\n# " + "x" * (1 << 20) + "\n")  # 1 MiB + 22 bytes: a sweep of it took 81 s
    (d / "sensor_text.yaml").write_text("mixed_gap: abc\n")
    (d / "sensor_flag.yaml").write_text("quantise: 3\n")
    (d / "sensor_dup.yaml").write_text("noise_sigma: 0.005\nmixed_gap: 0.1\nnoise_sigma: 0.5\n")
    (d / "sensor_mm.yaml").write_text("noise_sigma: 5\n")  # millimetres meant: 5 m of noise ran
    (d / "sensor_underflow.yaml").write_text("noise_sigma: 1e-400\n")  # read as 0: a noise-free run
    (d / "sensor_cm.yaml").write_text("n_beams: 361\nresolution: 0.008726646259971648\nunits: cm\nnoise_sigma: 0.44\n")  # cm meant
    (d / "sensor_slope_mm.yaml").write_text("noise_sigma: 0.005\nnoise_sigma_per_m: 0.5\n")  # mm per m meant
    (d / "sensor_gap_cm.yaml").write_text("noise_sigma: 0.005\nmixed_gap: 10\n")  # cm meant: no mixed pixel at all
    (d / "sensor_ok.yaml").write_text("noise_sigma: 0.005\n")
    (d / "sensor_cap.yaml").write_text("max_reading: 1.0e-320\n")  # every reading logged as 1e-320 m
    laughs = "[" + ", ".join(["&c0 [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]"] + [f"&c{i} [" + ", ".join([f"*c{i - 1}"] * 10) + "]"
                                                                    for i in range(1, 9)]) + "]"
    (d / "sensor_laughs.yaml").write_text(f"noise_sigma: {laughs}\n")  # 10^9 values: the message's repr hung
    (d / "slam_laughs.yaml").write_text(f"motion: {{sigma_accel: {laughs}}}\n")
    (d / "sensor_1deg.yaml").write_text("n_beams: 181\nresolution: 0.017453292519943295\n")  # good.clf: 361 at 0.5 deg
    (d / "short_run.yaml").write_text("world: office\nseed: 0\nduration: 0.001\n")  # a simulate config: no scan
    (d / "run_bool.yaml").write_text("world: office\nseed: 0\nduration: true\n")  # ran 1 s
    (d / "run_list.yaml").write_text("world: office\nseed: 0\nduration: [2]\n")
    (d / "run_robot.yaml").write_text("world: office\nseed: 0\nduration: 2\nrobot: 5\n")
    (d / "sensor_fine.yaml").write_text("n_beams: 100000000\nresolution: 1.0e-8\n")  # 10^8 beams: a hang
    (d / "badyaml.yaml").write_text("a: [1, 2\n")
    (d / "badcolon.yaml").write_text("noise_sigma: 0.1\n  x: : 3\n")
    (d / "badalias.yaml").write_text("noise_sigma: *nope\n")
    (d / "run_date.yaml").write_text("world: office\nseed: 2025-02-30\nduration: 2\n")  # an internal ValueError
    # YAML 1.1 numbers: seed 90 and seed 8 simulated, 181 beams, k 10 swept, silently
    (d / "run_sexagesimal.yaml").write_text("world: office\nseed: 1:30\nduration: 2\n")
    (d / "run_octal.yaml").write_text("world: office\nseed: 010\nduration: 2\n")
    (d / "sensor_underscore.yaml").write_text("n_beams: 18_1\nresolution: 0.017453292519943295\n")
    (d / "sweep_underscore.yaml").write_text("name: k\nkind: extract\ngrid:\n  extractor.k: [1_0]\n")
    (d / "simbadyaml").mkdir()
    (d / "simbadyaml" / "config.yaml").write_text("sensor: {noise_sigma: 0.005\n")
    write_log(d / "simbadyaml" / "scans.clf", good)
    (d / "simbadyaml" / "world.json").write_text((d / "simbroken" / "world.json").read_text())
    for name, text in {"simemptycfg": "", "simnosensor": "world: office\nseed: 0\n"}.items():
        (d / name).mkdir()  # an empty or cut config.yaml: compare scored the scans with the default sensor, exit 0
        (d / name / "config.yaml").write_text(text)
        write_log(d / name / "scans.clf", good)
        (d / name / "world.json").write_text((d / "simbroken" / "world.json").read_text())
    for name, spec in {"sweep_badspec": "a: [1\n", "sweep_listspec": "- 1\n"}.items():
        (d / name).mkdir()
        pd.DataFrame({"extractor.k": [3], "status": ["ok"], "error": [""], "cell": ["a"], "seed": [0],
                      "explained": [0.5]}).to_parquet(d / name / "results.parquet")
        (d / name / "sweep.yaml").write_text(spec)
    # SLAM configs: a method's options nested under extractor, unknown / invalid method params, wrong types
    (d / "slam_nested.yaml").write_text("extractor: {sensor: {band_tau: 3}}\n")
    (d / "slam_param.yaml").write_text("extractor_params: {bogus: 1}\n")
    (d / "slam_value.yaml").write_text("extractor: split_merge\nextractor_params: {split_threshold: -1}\n")
    (d / "slam_type.yaml").write_text("motion: {sigma_accel: fast}\n")
    (d / "slam_prob.yaml").write_text("slam: {prealign: {widen_probability: 1.5}}\n")
    (d / "slam_noise.yaml").write_text("motion: {odom_noise: [0.1]}\n")
    (d / "slam_beside.yaml").write_text("slam: {preset: paper}\nmotion: {sigma_accel: 9.0}\n")  # ran with 1.0
    (d / "slam_list.yaml").write_text("slam: [1, 2]\n")  # "unknown SLAM config field(s) [1, 2]"
    # values that reached the run: internal errors (voxel's grid size, a 0-beam chord, max_range**2
    # overflowing) or a hypothesis of 1e300 rad tried as a heading
    (d / "slam_voxel.yaml").write_text("slam: {keyframes: {voxel: 1.0e-12}}\n")
    (d / "slam_normal.yaml").write_text("slam: {alignment: {normal_step: 0}}\n")
    (d / "slam_range.yaml").write_text("slam: {alignment: {max_range: 1.0e300}}\n")
    (d / "slam_turn.yaml").write_text("slam: {alignment: {heading_hypotheses: [0.5, 1.0e300]}}\n")
    # a sweep folder whose every cell failed
    (d / "failed_sweep").mkdir()
    pd.DataFrame({"x": [1, 2], "status": ["error", "error"], "error": ["E", "E"], "cell": ["a", "b"]}).to_parquet(
        d / "failed_sweep" / "results.parquet")
    (d / "sweep_no_results").mkdir()
    # damaged tables: a truncated parquet file in a figures tables/ folder and in a sweep folder
    (d / "tables_broken").mkdir()
    (d / "tables_broken" / "study.yaml").write_text("world: office\n")
    (d / "tables_broken" / "summary.parquet").write_bytes(b"PAR1" + bytes(60))
    (d / "sweep_broken").mkdir()
    (d / "sweep_broken" / "results.parquet").write_bytes(b"PAR1" + bytes(60))
    for name in list(d.iterdir()):
        f[name.name] = str(name)
    return f


def run_main(argv: list[str], seconds: float = 20.0) -> int:
    def alarm(*_):
        raise Hang(f"lmsbench {' '.join(argv)} ran for more than {seconds} s")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


O = "{out}"  # placeholder: a fresh output folder of the case

CASES = [
    # simulate
    (["simulate", "--duration", "nan", "--out", O], "--duration"),
    (["simulate", "--duration", "inf", "--out", O], "--duration"),
    (["simulate", "--duration", "-5", "--out", O], "--duration"),
    (["simulate", "--duration", "1e9", "--out", O], "--duration"),
    (["simulate", "--seed", "-1", "--out", O], "--seed"),
    (["simulate", "--seed", "1.5", "--out", O], "--seed"),
    # a whole number of 400 digits was a traceback (OverflowError in the bound check) in every integer option
    (["simulate", "--seed", "9" * 400, "--out", O], "argument --seed: must be a whole number >= 0 and <= 4294967295, "
     "got '" + "9" * 40 + "...99999999' (400 characters)"),
    (["compare", "office:0", "--max-scans", "9" * 400, "--out", O], "argument --max-scans: must be a whole number >= 1 "
     "and at most 2^63 - 1, got '" + "9" * 40 + "...99999999' (400 characters)"),  # "(too large for a float)"
    # 5,000 digits (past int()'s 4,300) said "must be a whole number >= 1", which it is (review of probe 13)
    (["compare", "office:0", "--stride", "+" + "0" * 9 + "9" * 5000, "--out", O], "argument --stride: must be a whole "
     "number >= 1 and at most 2^63 - 1, got '+000000000" + "9" * 30 + "...99999999' (5010 characters)"),
    (["slam", "{good.clf}", "--every", "9" * 400, "--out", O], "argument --every/--stride: must be a whole number >= 1"),
    (["simulate", "--rate-hz", "-3", "--out", O], "--rate-hz"),
    (["simulate", "--rate-hz", "0", "--out", O], "--rate-hz"),
    (["simulate", "--rate-hz", "nan", "--out", O], "--rate-hz"),
    (["simulate", "--rate-hz", "40", "--out", O], "--rate-hz: 40 scans/s is more than the sensor gives (37.5"),
    (["simulate", "--world", "offfice", "--out", O], "offfice"),
    (["simulate", "--world", "{missing.json}", "--out", O], "missing.json"),
    (["simulate", "--world", "{binary.json}", "--out", O], "binary.json"),
    (["simulate", "--world", "{list.json}", "--out", O], "list.json"),
    (["simulate", "--world", "{nan_walls.json}", "--out", O], "finite"),
    (["simulate", "--world", "{bad_boxes.json}", "--out", O], "bad_boxes.json"),
    (["simulate", "--world", "{world_route_index.json}", "--out", O], "route_targets: node indices must be in [0, 20)"),
    (["simulate", "--world", "{world_route_nodes.json}", "--out", O], "route_edges: node indices"),
    (["simulate", "--world", "{world_scan_height.json}", "--out", O], "scan_height: must be a finite height"),
    (["simulate", "--world", "{world_route_apart.json}", "--out", O], "joins no two route targets"),
    (["simulate", "--world", "{world_flat_box.json}", "--out", O], "boxes: half sizes"),
    (["simulate", "--config", "{binary.yaml}", "--out", O], "binary.yaml"),
    (["simulate", "--config", "{list.yaml}", "--out", O], "list.yaml"),
    (["simulate", "--config", "{missing.yaml}", "--out", O], "missing.yaml"),
    (["simulate", "--config", "{slam_param.yaml}", "--out", O], "unknown key(s) ['extractor_params']"),
    (["simulate", "--config", "{sensor_text.yaml}", "--duration", "2", "--out", O], "--duration cannot be given"),
    (["simulate", "--config", "{sensor_text.yaml}", "--seed", "3", "--ideal", "--out", O], "--seed, --ideal cannot"),
    (["simulate", "--config", "{sensor_text.yaml}", "--seed", "0", "--clutter", "0", "--out", O], "--clutter, --seed cannot"),
    (["simulate", "--out", "{a_file}"], "not a folder"),
    (["simulate", "--resolution", "2", "--out", O], "--resolution"),
    (["simulate", "--clutter", "1e9", "--out", O], "--clutter"),
    # one interval for both ends: -1 said "must be a finite number >= 0", 1e9 "must be at most 10"
    (["simulate", "--clutter", "-1", "--out", O], "argument --clutter: must be a finite number >= 0 and <= 10 (10x a "
     "furnished office at most), got '-1'"),
    (["simulate", "--clutter", "10.5", "--out", O], "argument --clutter: must be a finite number >= 0 and <= 10 (10x a "
     "furnished office at most), got '10.5'"),
    (["simulate", "--sensor", "{sensor_text.yaml}", "--out", O], "mixed_gap: must be a number"),
    (["simulate", "--sensor", "{sensor_flag.yaml}", "--out", O], "quantise: must be true or false"),
    (["simulate", "--sensor", "{sensor_dup.yaml}", "--out", O], "key 'noise_sigma' given twice"),
    # flags that were ignored beside what overrides them: the file's geometry ran, the log had its own sensor
    (["simulate", "--sensor", "{sensor_ok.yaml}", "--resolution-deg", "1", "--out", O], "--resolution-deg cannot be given"),
    (["simulate", "--sensor", "{sensor_ok.yaml}", "--units", "cm", "--out", O], "--sensor holds the whole sensor model"),
    (["compare", "{good.clf}", "--sensor", "{sensor_ok.yaml}", "--out", O], "--sensor sets the sensor of the worlds"),
    (["simulate", "--config", "{short_run.yaml}", "--out", O], "duration: must be in [0.1, 3600] s (shorter holds no scan), got 0.001"),
    # values of the wrong type: `duration: true` ran 1 s; a list said "float() argument must be ..."
    (["simulate", "--config", "{run_bool.yaml}", "--out", O], "run_bool.yaml: not a simulate config (duration: must be a number, got True)"),
    (["simulate", "--config", "{run_list.yaml}", "--out", O], "(duration: must be a number, got [2])"),
    (["simulate", "--config", "{run_robot.yaml}", "--out", O], "(robot: must be a mapping of fields, got 5)"),
    (["simulate", "--sensor", "{sensor_mm.yaml}", "--out", O], "sensor_mm.yaml: noise_sigma: must be in [0, 0.1] m"),
    # a float written nonzero that float64 reads as 0 ran as 0: a noise-free run, an office with no clutter
    (["simulate", "--sensor", "{sensor_underflow.yaml}", "--out", O], "sensor_underflow.yaml: not valid YAML (line 1, "
     "column 14: key 'noise_sigma': 1e-400 rounds to 0 in float64 (its smallest nonzero number is 4.9e-324); "
     "write 0 for zero)"),
    (["simulate", "--clutter", "1e-400", "--out", O], "argument --clutter: must be a finite number >= 0 and <= 10 (10x a "
     "furnished office at most), got '1e-400': 1e-400 rounds to 0 in float64 (its smallest nonzero number is 4.9e-324)"),
    (["info", "{good.clf}", "--laser-angle-min-deg", "-1e-999"], "argument --laser-angle-min-deg: got '-1e-999': -1e-999 "
     "rounds to 0 in float64"),
    # a calibrated sensor with its noise in cm (MIT CSAIL's 4.4 mm as 0.44): sim2real compared the log
    # against 0.44 m of noise ("sensor: noise 440.00 mm", largest gap 0.514), exit 0
    (["sim2real", "{good.clf}", "--sensor", "{sensor_cm.yaml}", "--out", O], "sensor_cm.yaml: noise_sigma: must be in [0, "
     "0.1] m (a 1-sigma range error in metres; the datasheet's is 0.005: a value in mm or cm is refused), got 0.44"),
    (["sim2real", "{good.clf}", "--sensor", "{sensor_slope_mm.yaml}", "--out", O], "sensor_slope_mm.yaml: noise_sigma_per_m: "
     "must be within +-0.05 m per m of range (metres of noise per metre; real logs' are below 0.001), got 0.5"),
    (["sim2real", "{good.clf}", "--sensor", "{sensor_gap_cm.yaml}", "--out", O], "sensor_gap_cm.yaml: mixed_gap: must be in "
     "[0, 1] m (a depth step in metres; the default is 0.1), got 10"),
    (["compare", "office", "--sensor", "{sensor_fine.yaml}", "--out", O], "sensor_fine.yaml: resolution: must be in [0.004363, 0.017453] rad"),
    (["sim2real", "{good.clf}", "--sensor", "{sensor_dup.yaml}", "--out", O], "sensor_dup.yaml: not valid YAML (key 'noise_sigma' given twice"),
    # compare
    (["compare", "office:x", "--out", O], "office:x"),
    (["compare", "{simbroken}", "--out", O], "config.yaml: not a simulate config"),
    (["compare", "office:-1", "--out", O], "office:-1"),
    (["compare", "offfice", "--out", O], "offfice"),
    (["compare", "office", "--rate", "0", "--out", O], "--rate"),
    (["compare", "office", "--rate", "inf", "--out", O], "--rate"),
    (["compare", "office", "--seeds", "-1", "--out", O], "--seeds"),
    (["compare", "office", "--duration", "inf", "--out", O], "--duration"),
    (["compare", "office", "--seeds", "0", "0", "--out", O], "--seeds"),
    (["compare", "office", "--duration", "0", "--out", O], "--duration"),
    (["compare", "{good.clf}", "--stride", "-1", "--out", O], "--stride"),
    (["compare", "{good.clf}", "--stride", "0", "--out", O], "--stride"),
    (["compare", "{good.clf}", "--max-scans", "0", "--out", O], "--max-scans"),
    (["compare", "office", "--sigma", "-1", "--out", O], "--sigma"),
    (["compare", "office", "--sigma", "nan", "--out", O], "--sigma"),
    (["compare", "office", "--set", "extractor.k=abc", "--out", O], "k"),
    (["compare", "office", "--set", "extractor.hough.rho_step=0", "--out", O], "rho_step"),
    (["compare", "office", "--set", "extractor.kk=3", "--out", O], "kk"),
    # a method's fields for a method not run: as the library's compare(params=...) refuses them
    (["compare", "office", "--methods", "sensor", "--set", "extractor.iepf.split_threshold=0.05", "--out", O],
     "extractor.iepf.split_threshold: 'iepf' is not an extractor of this run; known: sensor"),
    (["compare", "office", "--set", "sensor.k=3", "--out", O], "extractor.sensor.k"),
    (["compare", "office", "--set", "novalue", "--out", O], "--set"),
    # Python's int() / float() take underscores and other scripts' digits: 1_0 (a typo of 1.0) ran 10 s,
    # Arabic-Indic ٣ and fullwidth ２ ran seed 3 and every 2nd scan, as the CARMEN reader refuses them
    (["compare", "office:1", "--duration", "1_0", "--out", O], "argument --duration: must be a finite number >= 0.1 "
                                                               "and <= 3600 s, got '1_0'"),
    (["compare", "office", "--seeds", "\u0663", "--out", O], "argument --seeds: must be a whole number >= 0"),
    (["compare", "office:\u0663", "--out", O], "the seed after the colon must be a whole number >= 0"),
    (["compare", "office:1", "--sigma", "1_0", "--out", O], "--sigma takes metres or 'auto', got '1_0'"),
    (["slam", "{simrun}", "--every", "\uff12", "--out", O], "argument --every/--stride: must be a whole number >= 1"),
    # the options with choices read their word with float() / int(): --fov-deg 1_80 recorded at 180 deg, --baud
    # with Arabic-Indic digits at 38400, simulate --resolution-deg with one ran at 1 deg (probe 13)
    (["simulate", "--resolution-deg", "\u0661", "--out", O],
     "argument --resolution-deg/--resolution: invalid float value: '\u0661'"),
    (["lms200", "record", "--port", "loop://", "--out", "{out}/x.clf", "--fov-deg", "1_80"],
     "argument --fov-deg/--fov: invalid int value: '1_80'"),
    (["lms200", "record", "--port", "loop://", "--out", "{out}/x.clf", "--baud", "\u0663\u0668\u0664\u0660\u0660"],
     "argument --baud: invalid int value"),
    # a count beyond int64's passed the options; compare compiled its kernels and read the log, then stopped on the
    # library's "stride: must be an integer in 1..2^63 - 1" (probe 13)
    (["compare", "{good.clf}", "--stride", "99999999999999999999999", "--out", O],
     "argument --stride: must be a whole number >= 1 and at most 2^63 - 1, got '99999999999999999999999'"),
    # the same field set twice ran the last value alone, exit 0 (an option given twice is refused)
    (["compare", "office:1", "--set", "extractor.sensor.k=2", "--set", "extractor.sensor.k=3", "--out", O],
     "--set extractor.sensor.k is given twice (extractor.sensor.k=2 and extractor.sensor.k=3); set each field once"),
    (["compare", "office", "--methods", "nosuch", "--out", O], "nosuch"),
    (["compare", "{binary.clf}", "--out", O], "binary"),
    (["compare", "{plain.gz}", "--out", O], "gzip"),
    (["compare", "{empty_dir}", "--out", O], "empty_dir"),
    (["compare", "{notalog.clf}", "--out", O], "not a CARMEN log"),
    (["compare", "office", "--format", "xls", "--out", O], "--format"),
    (["compare", "office", "--rate", "40", "--out", O], "--rate: 40 scans/s is more than the sensor gives (37.5"),
    # one source twice, or two of one name: the tables group by name (120 scans for a 60-scan log, two logs as one)
    (["compare", "{good.clf}", "{good.clf}", "--out", O], "good.clf is given twice ("),
    (["compare", "office", "office:1", "--out", O], "office:1 is given twice (office and office:1): each source once"),
    (["compare", "{simbroken}", "{simbroken}", "--out", O], "simbroken is given twice"),
    # slam
    (["slam", "{simrun}", "--max-scans", "0", "--out", O], "--max-scans"),
    (["slam", "{simrun}", "--every", "0", "--out", O], "--every"),
    (["slam", "{simrun}", "--rate-hz", "0", "--out", O], "--rate-hz"),
    (["slam", "{simrun}", "--rate-hz", "nan", "--out", O], "--rate-hz"),
    (["slam", "{simrun}", "--config", "{binary.yaml}", "--out", O], "binary.yaml"),
    (["slam", "{simrun}", "--config", "{badyaml.yaml}", "--out", O], "badyaml.yaml"),
    (["slam", "{simrun}", "--config", "{missing.yaml}", "--out", O], "missing.yaml"),
    (["slam", "{simrun}", "--extractor", "nosuch", "--out", O], "nosuch"),
    (["slam", "{simrun}", "--config", "{slam_nested.yaml}", "--out", O], "extractor: must be an extraction method's name"),
    (["slam", "{simrun}", "--config", "{slam_param.yaml}", "--out", O], "slam_param.yaml: extractor_params: unknown parameter(s) ['bogus']"),
    (["slam", "{simrun}", "--config", "{slam_value.yaml}", "--out", O], "slam_value.yaml: extractor_params.split_threshold: must be a width in [0.0001, 1] m, got -1"),
    (["slam", "{simrun}", "--config", "{slam_type.yaml}", "--out", O], "motion.sigma_accel: must be a number"),
    (["slam", "{simrun}", "--config", "{slam_prob.yaml}", "--out", O], "prealign.widen_probability: a probability"),
    (["slam", "{simrun}", "--config", "{slam_noise.yaml}", "--out", O], "odom_noise: must be 3 numbers"),
    (["slam", "{simrun}", "--config", "{slam_beside.yaml}", "--out", O],
     "slam_beside.yaml: key(s) ['motion'] beside the slam: section would be ignored; put them under slam:"),
    (["slam", "{simrun}", "--config", "{slam_list.yaml}", "--out", O],
     "slam_list.yaml: slam: must be a mapping of SLAM config fields, got [1, 2]"),
    (["slam", "{simrun}", "--config", "{slam_voxel.yaml}", "--out", O], "slam_voxel.yaml: keyframes.voxel: must be 0"),
    # an --out holding other things: the README's 'slam run --out slam' wrote into the slam package;
    # slam into the simulated run's own folder replaced its config.yaml (the sensor compare reads)
    (["slam", "{simrun}", "--out", "{simrun}"], "simrun is the input folder "),
    # a folder of the slam outputs' names only passed, and the run deleted the user's metrics.json
    (["slam", "{simrun}", "--out", "{notes_dir}"], "notes_dir: holds metrics.json, which this run would replace but "
                                                   "no earlier lmsbench slam run wrote"),
    (["simulate", "--duration", "1", "--out", "{pkg}"], "holds __init__.py, which this command does not write"),
    (["slam", "{simrun}", "--config", "{slam_normal.yaml}", "--out", O], "alignment.normal_step: must be in [1, 100] beams, got 0"),
    (["slam", "{simrun}", "--config", "{slam_range.yaml}", "--out", O], "alignment.max_range: must be in [0.1, 10000] m"),
    (["slam", "{simrun}", "--config", "{slam_turn.yaml}", "--out", O], "alignment.heading_hypotheses: offsets"),
    (["slam", "{backwards.clf}", "--out", O], "backwards"),
    # thinned to one scan of several: a "SLAM" of one pose, exit 0
    (["slam", "{good.clf}", "--rate-hz", "0.01", "--out", O], "good.clf: --rate-hz 0.01 keeps 1 of the 5 scans read "
                                                              "(stamps 0.000000 to 0.400000 s); SLAM needs two or more"),
    (["slam", "{good.clf}", "--every", "10", "--out", O], "good.clf: --every 10 keeps 1 of the 5 scans read"),
    (["slam", "{binary.clf}", "--out", O], "binary"),
    (["slam", "{no_returns.clf}", "--out", O], "no_returns.clf"),
    (["calibrate", "{no_returns.clf}"], "too few straight runs"),
    (["slam", "{missing.clf}", "--out", O], "missing.clf"),
    (["slam", "{empty_dir}", "--out", O], "empty_dir"),
    (["slam", "{simrun}", "--relations", "{missing.relations}", "--out", O], "missing.relations"),
    # sweep
    (["sweep", "{binary.yaml}", "--out", O], "binary.yaml"),
    (["sweep", "{missing.yaml}", "--out", O], "missing.yaml"),
    (["sweep", "{list.yaml}", "--out", O], "list.yaml"),
    (["sweep", "{badyaml.yaml}", "--out", O], "badyaml.yaml"),
    (["sweep", "{sweep.yaml}", "--scheduler", "foo", "--out", O], "foo"),
    # Dask's parse of these was an internal error (ValueError, exit 1), a port beyond 65535 a 10 s wait
    (["sweep", "{sweep.yaml}", "--scheduler", "tcp://", "--out", O],
     "scheduler: 'tcp://' is not a Dask scheduler address: give tcp://HOST:PORT, a host and a port 1-65535"),
    (["sweep", "{sweep.yaml}", "--scheduler", "tcp://127.0.0.1", "--out", O], "give tcp://HOST:PORT, a host and a port"),
    (["sweep", "{sweep.yaml}", "--scheduler", "tcp://[::1", "--out", O],
     "scheduler: 'tcp://[::1' is not a Dask scheduler address (tcp://HOST:PORT): invalid IPv6 URL"),
    (["sweep", "{sweep.yaml}", "--scheduler", "tcp://127.0.0.1:99999", "--out", O], "port out of range 0-65535"),
    (["sweep", "{sweep.yaml}", "--scheduler", "inproc://x", "--out", O], "not an in-process Dask address"),
    (["sweep", "{sweep.yaml}", "--workers", "0", "--out", O], "--workers"),
    (["sweep", "{sweep.yaml}", "--workers", "-1", "--out", O], "--workers"),
    (["sweep", "{sweep.yaml}", "--out", "{a_file}"], "not a folder"),
    (["sweep", "{sweep_seed.yaml}", "--out", O], "seeds"),
    (["sweep", "{sweep_dup_seed.yaml}", "--out", O], "seeds"),
    # `seeds: 3` ran the one seed 3 (three seeds meant); `k: 3, 5, 10` (no brackets) the string '3, 5, 10' in every cell
    (["sweep", "{sweep_bare_seeds.yaml}", "--out", O], "sweep_bare_seeds.yaml: `seeds: 3` is one number: write a list, "
                                                       "`seeds: [0, 1, 2]` for 3 seeds, `seeds: [3]` for the one seed 3"),
    (["sweep", "{sweep_bare_grid.yaml}", "--out", O], "sweep_bare_grid.yaml: grid.extractor.k: '3, 5, 10' is a single "
                                                      "value: write a list of the values to vary (`[3, 5, 10]`"),
    (["sweep", "{sweep_k.yaml}", "--out", O], "k: must be"),
    (["sweep", "{sweep_noise.yaml}", "--out", O], "noise_sigma"),
    (["sweep", "{sweep_plain.yaml}", "--out", O], "bogus"),
    (["sweep", "{sweep_name.yaml}", "--out", O], "plain folder name"),
    (["sweep", "{sweep_world.yaml}", "--out", O], "offfice"),
    (["sweep", "{sweep_duration.yaml}", "--out", O], "duration"),
    (["sweep", "{sweep_slam.yaml}", "--out", O], "gate_probability"),
    (["sweep", "{sweep_samples.yaml}", "--out", O], "`samples:` must be a whole number"),
    (["sweep", "{sweep_huge.yaml}", "--out", O], "`samples:` must be a whole number in [0, 100000]"),
    (["sweep", "{sweep_sample_seed.yaml}", "--out", O], "`sample_seed:`"),
    (["sweep", "{sweep_text_bounds.yaml}", "--out", O], "uniform needs [low, high]"),
    (["sweep", "{sweep_int_bounds.yaml}", "--out", O], "int needs whole-number bounds"),
    # bounds numpy cannot draw from: "internal error: ValueError: high is out of bounds for int64" / OverflowError
    (["sweep", "{sweep_int_huge.yaml}", "--out", O], "random.extractor.min_points: int's bounds must be within int64's range, [-2**63, 2**63 - 1], that a sweep's table holds, got a whole number of 25 digits"),
    (["sweep", "{sweep_uniform_wide.yaml}", "--out", O], "random.extractor.ad_tau: uniform needs high - low finite"),
    (["sweep", "{sweep_big_seed.yaml}", "--out", O], "`seeds:` must be distinct integers in [0, 4294967295]"),
    (["sweep", "{sweep_name_number.yaml}", "--out", O], "name: must be a string"),
    (["sweep", "{sweep_cells.yaml}", "--out", O], "150000 cells"),
    (["sweep", "{sweep_long.yaml}", "--out", O], "duration: must be a number of seconds in [0.1, 3600]"),
    (["sweep", "{sweep_short.yaml}", "--out", O], "duration: must be a number of seconds in [0.1, 3600], got 0.001"),
    # runs too short to hold a scan: simulate wrote an empty run, figures raised IndexError (exit 1),
    # compare and sim2real failed only after the work before (15 s of calibration)
    (["simulate", "--duration", "0.001", "--out", O], "--duration: must be a finite number >= 0.1 and <= 3600 s"),
    (["figures", "--duration", "0.001", "--no-slam", "--out", O], "--duration"),
    (["compare", "office", "--duration", "0.01", "--out", O], "--duration"),
    (["sim2real", "{good.clf}", "--duration", "0.001", "--out", O], "--duration"),
    (["sim2real", "{good.clf}", "--probe-duration", "0.05", "--out", O], "--probe-duration"),
    # the fit's runs: 1-600 s (a run of 0.2 s held 1 scan, too few to calibrate), and nothing to fit with --sensor
    (["calibrate", "{good.clf}", "--fit-duration", "0.5"], "argument --fit-duration: must be a finite number >= 1 and <= 600 s"),
    (["sim2real", "{good.clf}", "--fit-duration", "601", "--out", O], "--fit-duration"),
    (["sim2real", "{good.clf}", "--sensor", "{sensor_ok.yaml}", "--fit-duration", "2", "--out", O],
     "--fit-duration sets the calibration's fit; with --sensor the log is not calibrated"),
    (["demo", "--duration", "0.01", "--out", O], "--duration"),
    # a 'billion laughs' of aliases: the error message's repr of the value hung past the test's alarm
    (["simulate", "--sensor", "{sensor_laughs.yaml}", "--out", O], "sensor_laughs.yaml: not valid YAML (its aliases "
     "(*name) expand it to more than 1,000,000 values (a 'billion laughs'); write the values out)"),
    (["compare", "office:1", "--sensor", "{sensor_laughs.yaml}", "--out", O], "sensor_laughs.yaml: not valid YAML (its"),
    (["slam", "{simrun}", "--config", "{slam_laughs.yaml}", "--out", O], "slam_laughs.yaml: not valid YAML (its aliases"),
    # an empty word read as "not given" (the default extractor ran, a local cluster) or as every interface
    (["slam", "{simrun}", "--extractor", "", "--out", O], "argument --extractor: must not be empty, got ''; give an "
                                                          "extraction method's name"),
    (["sweep", "{sweep.yaml}", "--scheduler", "", "--out", O], "argument --scheduler: must not be empty, got ''"),
    (["lms200", "emulate", "--tcp", "0", "--host", ""], "argument --host: must not be empty, got ''"),  # 0.0.0.0
    (["lms200", "record", "--port", " ", "--out", "{out}/x.clf"], "argument --port: must not be empty, got ' '"),
    (["compare", "office:1", "--methods", "sensor", "", "--out", O], "argument --methods: must not be empty, got ''"),
    # a noise of 1e308 m overflowed in the summary (a RuntimeWarning on stderr, sigma_r_mm inf), exit 0
    (["compare", "office:1", "--sigma", "1e308", "--out", O], "--sigma must be a range noise std in [0.0001, 1000] m, "
                                                              "or 'auto', got '1e308'"),
    # a noise of 1e-300 m ran, exit 0: the sensor method found no line (F1 0), every 3-sigma explained
    # fraction was 0 and sigma_r_mm read 1e-297; below 0.1 mm no rangefinder's noise lies
    (["compare", "office:1", "--sigma", "1e-300", "--out", O], "argument --sigma: --sigma must be a range noise std in "
                                                               "[0.0001, 1000] m, or 'auto', got '1e-300'"),
    (["compare", "office:1", "--sigma", "5e-5", "--out", O], "--sigma must be a range noise std in [0.0001, 1000] m, "
                                                             "or 'auto', got '5e-5'"),
    # a world.json nested 100,000 deep, walls at 1e308 m (RuntimeWarnings on stderr before the error line)
    (["simulate", "--world", "{deep.json}", "--out", O], "deep.json: not a world.json (nested too deeply to parse)"),
    (["simulate", "--world", "{far_walls.json}", "--out", O], "far_walls.json: not a world.json (walls: must be finite "
                                                              "numbers within +-1e+06 m)"),
    # a compressed file where YAML is read: passed the check (its text is inside), then "internal error:
    # UnicodeDecodeError: 'utf-8' codec can't decode byte 0x8b"
    # (a compressed CARMEN log, said to be one: it was told to be decompressed, as if that would make it YAML)
    (["simulate", "--config", "{good.clf.gz}", "--out", O], "good.clf.gz: a gzip-compressed CARMEN log (its line 4 is "
                                                            "a PARAM message), not a simulate config.yaml"),
    (["sweep", "{good.clf.gz}", "--out", O], "good.clf.gz: a gzip-compressed CARMEN log (its line 4 is a PARAM message), "
                                             "not a sweep file"),
    (["slam", "{good.clf}", "--relations", "{good.clf.gz}", "--out", O], "good.clf.gz: a gzip-compressed CARMEN log (its "
                                                                       "line 4 is a PARAM message), not a relations file"),
    # options that apply to what the run does not do were ignored, exit 0
    # (with the default preset they set its paper-preset baselines: refused only when neither runs; review)
    (["slam", "{simrun}", "--association", "jcbb", "--no-paper-baseline", "--no-odometry-baseline", "--out", O],
     "--association set the paper preset's filter, which this run does not use"),
    (["slam", "{simrun}", "--corners", "--no-paper-baseline", "--no-odometry-baseline", "--out", O],
     "--corners set the paper preset's filter, which this run does not use"),
    (["lms200", "emulate", "--log", "{good.clf}", "--world", "corridor", "--seed", "5"],
     "--world, --seed set the simulated scans; --log replays the log's own"),
    (["lms200", "emulate", "--host", "0.0.0.0"], "--host needs --tcp PORT (without it the device is a pseudo-terminal)"),
    # the log options without --log were ignored: the simulator's scans served, exit 0
    (["lms200", "emulate", "--laser-fov-deg", "90", "--topic", "FLASER", "--duration", "0.1"],
     "error: --topic, --laser-fov-deg say how to read the --log to replay; without --log the device serves simulated "
     "scans (give --log LOG, or leave them out)"),
    (["lms200", "emulate", "--skip-bad-lines", "--duration", "0.1"], "error: --skip-bad-lines says how to read the --log"),
    (["sweep", "{sweep.yaml}", "--inprocess", "--workers", "3", "--out", O],
     "--workers sets the processes of the local cluster; --inprocess runs in this process"),
    (["demo", "--inprocess", "--no-sweep", "--out", O], "--inprocess runs the demo's sweep in this process; --no-sweep"),
    (["figures", "--tables", "{tables_broken}", "--duration", "5", "--no-slam", "--out", O],
     "--duration, --no-slam set the study that --tables replaces; redrawing from "),
    # log options with --tables: ignored, the figures redrawn from the tables as they were
    (["figures", "--tables", "{tables_broken}", "--topic", "FLASER", "--laser-range-max", "50", "--out", O],
     "--topic, --laser-range-max do not apply to --tables: they say how to read the study's log (Fig. 9's Intel log), "
     "and redrawing from "),
    (["figures", "--tables", "{tables_broken}", "--skip-bad-lines", "--out", O], "--skip-bad-lines does not apply to --tables"),
    # one scan kept: the whole comparison ran, then "internal error: ValueError: ate: fewer than 2 estimated poses"
    (["figures", "--duration", "0.5", "--rate-hz", "2", "--out", O], "--duration 0.5 at --rate-hz 2 keeps 1 scan(s) of "
     "the simulated run; the SLAM (Fig. 10) needs two or more (a longer run or a higher rate, or --no-slam)"),
    (["demo", "--duration", "1", "--rate-hz", "1", "--no-sweep", "--out", O], "--duration 1 at --rate-hz 1 keeps 1 scan(s)"),
    # figures
    (["figures", "--tables", "{tables_broken}", "--out", O], "summary.parquet: not a readable parquet table"),
    (["figures", "--tables", "{tables_broken}", "--sweep", "{sweep_broken}", "--out", O], "results.parquet: not a Parquet table"),
    (["figures", "--world", "offfice", "--out", O], "offfice"),
    (["figures", "--duration", "-5", "--out", O], "--duration"),
    (["figures", "--rate-hz", "0", "--out", O], "--rate-hz"),
    (["figures", "--seed", "-1", "--out", O], "--seed"),
    (["figures", "--methods", "nosuch", "--out", O], "nosuch"),
    (["figures", "--intel", "{missing.log}", "--out", O], "missing.log"),
    (["figures", "--intel", "{binary.clf}", "--out", O], "binary"),
    (["figures", "--tables", "{empty_dir}", "--out", O], "empty_dir"),
    (["figures", "--tables", "{missing_dir}", "--out", O], "missing_dir"),
    (["figures", "--sweep", "{failed_sweep}", "--out", O], "no successful cell"),
    (["figures", "--sweep", "{sweep_no_results}", "--out", O], "results.parquet"),
    # demo
    (["demo", "--world", "offfice", "--out", O], "offfice"),
    (["demo", "--duration", "-5", "--out", O], "--duration"),
    (["demo", "--rate-hz", "0", "--out", O], "--rate-hz"),
    (["demo", "--seed", "-1", "--out", O], "--seed"),
    (["demo", "--log", "{binary.clf}", "--out", O], "binary"),
    (["demo", "--log", "{missing.clf}", "--out", O], "missing.clf"),
    # lms200
    (["lms200", "emulate", "--world", "offfice"], "offfice"),
    (["lms200", "emulate", "--tcp", "70000"], "--tcp"),
    (["lms200", "emulate", "--tcp", "-1"], "--tcp"),
    (["lms200", "emulate", "--duration", "-5"], "--duration"),
    (["lms200", "emulate", "--time-scale", "0"], "--time-scale"),
    # ran as long as asked: a byte time of days, a reply awaited for 31 years
    (["lms200", "emulate", "--time-scale", "1e9"], "argument --time-scale: must be a finite number >= 1e-06 and <= 100, got '1e9'"),
    # 1e-310 was "internal error: OverflowError: cannot convert float infinity to integer" once a host asked for
    # scans; 1e-300 served what 1e-6 does (the emulator's own pace)
    (["lms200", "emulate", "--time-scale", "1e-310"], "argument --time-scale: must be a finite number >= 1e-06 and <= 100, got '1e-310'"),
    (["lms200", "emulate", "--time-scale", "1e-300"], "argument --time-scale: must be a finite number >= 1e-06 and <= 100, got '1e-300'"),
    (["lms200", "emulate", "--time-scale", "nan"], "argument --time-scale: must be a finite number >= 1e-06 and <= 100, got 'nan'"),
    (["lms200", "emulate", "--seed", "-1"], "--seed"),
    (["lms200", "emulate", "--log", "{binary.clf}"], "binary"),
    (["lms200", "emulate", "--log", "{missing.clf}"], "missing.clf"),
    (["lms200", "emulate", "--rfc2217"], "--tcp"),
    (["lms200", "record", "--port", "loop://", "--out", "{out}/x.clf", "--duration", "-5"], "--duration"),
    # shorter than any scan: the emulator stopped at once ("0 scans sent"), the recorder "recorded no scan", exit 0
    (["lms200", "emulate", "--duration", "1e-320"], "argument --duration: must be a finite number >= 0.1 s, got '1e-320'"),
    (["lms200", "record", "--port", "loop://", "--out", "{out}/x.clf", "--duration", "1e-300"],
     "argument --duration: must be a finite number >= 0.1 s, got '1e-300'"),
    (["lms200", "record", "--port", "loop://", "--out", "{out}/x.clf", "--max-scans", "0"], "--max-scans"),
    (["lms200", "record", "--port", "loop://", "--out", "{out}/x.clf", "--timeout", "0"], "--timeout"),
    (["lms200", "record", "--port", "loop://", "--out", "{out}/x.clf", "--mode-timeout", "0"], "--mode-timeout"),
    (["lms200", "record", "--port", "loop://", "--out", "{out}/x.clf", "--mode-timeout", "nan"], "--mode-timeout"),
    (["lms200", "record", "--port", "loop://", "--out", "{out}/x.clf", "--timeout", "1e9"],
     "argument --timeout: must be a finite number > 0 and <= 60 s, got '1e9'"),
    (["lms200", "record", "--port", "loop://", "--out", "{missing_dir}/x.clf"], "missing_dir"),
    (["lms200", "record", "--port", "loop://", "--out", "{out}/x.txt"], ".txt"),
    (["lms200", "record", "--port", "loop://", "--out", "{a_file}/x.clf"], "a_file"),
    # info
    (["info", "{plain.gz}"], "gzip"),
    (["info", "{binary.clf}"], "binary"),
    (["info", "{missing.clf}"], "missing.clf"),
    (["info", "{empty_dir}"], "empty_dir"),
    (["info", "{empty.clf}"], "empty"),
    (["info", "{fake.bag}"], "fake.bag"),
    (["info", "{notalog.clf}"], "not a CARMEN log"),
    # a topic that is not a LaserScan: "no topic '/odom'; topics: ['/odom (geometry_msgs/msg/PoseStamped)', ...]"
    (["info", "{odo.bag}", "--topic", "/odom"], "odo.bag: topic '/odom' holds geometry_msgs/msg/PoseStamped messages, "
                                                "not sensor_msgs/LaserScan; its LaserScan topics: /scan"),
    # a named pipe (or a device) where a file is expected: the check's open() hung (--out: the write, after the work)
    (["info", "{pipe.clf}"], "pipe.clf: a pipe (such as <(zcat LOG)), not a file: a log is read more than once"),
    (["compare", "{pipe.clf}", "--out", O], "pipe.clf: a pipe (such as <(zcat LOG)), not a file"),
    (["slam", "{pipe.clf}", "--out", O], "give the log file itself (gzip, bzip2 and xz logs are read as they are) or "
                                         "save the stream to a file first (zcat LOG > FILE)"),
    (["info", "{blank.clf.gz}"], "blank.clf.gz:1: more than 100,000 blank or comment lines in a row from here on: not a "
     "CARMEN log, or a damaged one"),
    (["compare", "{blank.clf.gz}", "--out", O], "blank.clf.gz:1: more than 100,000 blank or comment lines in a row"),
    # an impossible date: "internal error: ValueError: day is out of range for month"
    (["simulate", "--config", "{run_date.yaml}", "--out", O], "run_date.yaml: not valid YAML (line 2, column 7: "
     "'2025-02-30' is not a valid date or time (day is out of range for month))"),
    (["slam", "{good.clf}", "--config", "{run_date.yaml}", "--out", O], "run_date.yaml: not valid YAML (line 2, column 7: "),
    (["sweep", "{run_date.yaml}", "--out", O], "run_date.yaml: not valid YAML: line 2, column 7: '2025-02-30' is not"),
    (["simulate", "--config", "{run_sexagesimal.yaml}", "--out", O], "run_sexagesimal.yaml: not valid YAML (line 2, column 7: "
     "key 'seed': 1:30 is read as 90: YAML 1.1 reads digits between colons in base 60 (a time or an angle); write the "
     "number as a plain decimal, or quote it ('1:30') for text)"),
    (["simulate", "--config", "{run_octal.yaml}", "--out", O], "run_octal.yaml: not valid YAML (line 2, column 7: key 'seed': "
     "010 is read as 8: YAML 1.1 reads a whole number with a leading 0 in octal"),
    (["simulate", "--sensor", "{sensor_underscore.yaml}", "--world", "office", "--seed", "0", "--duration", "1", "--out", O],
     "sensor_underscore.yaml: not valid YAML (line 1, column 10: key 'n_beams': 18_1 is read as 181: YAML 1.1 drops a "
     "number's underscores"),
    (["sweep", "{sweep_underscore.yaml}", "--out", O], "sweep_underscore.yaml: not valid YAML: line 4, column 17: key "
     "'extractor.k', item 1: 1_0 is read as 10"),
    # configs and sweep files over 1 MiB: refused unread (a 1.5 MB sweep file took 81 s to be refused)
    (["sweep", "{huge.yaml}", "--out", O], "huge.yaml: 1,048,598 bytes, more than the 1,048,576 a sweep file "
     "may hold (refused unread; sweep files are a few KB: a sweep's grid lists the values of each parameter, not every cell)"),
    # each file named as what it is (all spoke of "a config or sweep file" and "a sweep's grid")
    (["slam", "{good.clf}", "--config", "{huge.yaml}", "--out", O], "huge.yaml: 1,048,598 bytes, more than the 1,048,576 "
     "a SLAM config.yaml may hold (refused unread; they are a few KB)"),
    (["simulate", "--sensor", "{huge.yaml}", "--out", O], "huge.yaml: 1,048,598 bytes, more than the 1,048,576 a sensor "
     "YAML may hold (refused unread; they are a few KB)"),
    # a config through a pipe: refused, "(a pipe, a device or a socket)", without why
    (["slam", "{good.clf}", "--config", "{pipe.yaml}", "--out", O], "pipe.yaml: not a regular file but a pipe (<(cat FILE), "
     "/dev/stdin fed by a pipe, a FIFO): a SLAM config.yaml must be a regular file, as it is checked before it is read"),
    (["simulate", "--world", "{pipe.json}", "--out", O], "pipe.json: not a regular file but a pipe (<(cat FILE), "
     "/dev/stdin fed by a pipe, a FIFO): a world.json must be a regular file"),
    (["sweep", "{pipe.yaml}", "--out", O], "a sweep file must be a regular file"),
    (["simulate", "--config", "{pipe.yaml}", "--out", O], "a simulate config.yaml must be a regular file"),
    (["sim2real", "{good.clf}", "--sensor", "{pipe.yaml}", "--out", O], "a sensor YAML must be a regular file"),
    (["simulate", "--sensor", "{pipe.yaml}", "--out", O], "pipe.yaml: not a regular file (a pipe, a device or a socket): "
     "a sensor YAML must be a regular file"),  # was "no such sensor file"
    (["compare", "office:1", "--sensor", "{pipe.yaml}", "--out", O], "a sensor YAML must be a regular file"),
    (["calibrate", "{good.clf}", "--out", "{pipe.yaml}"], "pipe.yaml: not a regular file (a pipe, a device or a socket); give a file name"),
    (["info", "/dev/zero"], "/dev/zero: not a regular file"),
    (["info", "{bag_badmeta}"], "bag_badmeta/metadata.yaml: not valid YAML (line 2, column 1: expected ',' or ']'"),
    (["slam", "{bag_listmeta}", "--out", O], "metadata.yaml: not a ROS 2 bag's metadata.yaml (no rosbag2_bagfile_information"),
    (["info", "{good.clf}", "--laser-fov-deg", "90", "--laser-resolution-deg", "0.5"], "own beam geometry"),
    # a laser kind the log lacks: "no laser messages found: not a CARMEN log" (info, compare), "got 0 scans"
    (["info", "{good.clf}", "--topic", "FLASER"], "good.clf has no FLASER lines; its laser lines: ROBOTLASER1 (5)"),
    (["calibrate", "{good.clf}", "--topic", "RLASER"], "good.clf has no RLASER lines; its laser lines: ROBOTLASER1"),
    (["slam", "{good.clf}", "--topic", "FLASER", "--out", O], "good.clf has no FLASER lines"),
    # not a laser kind at all: "good.clf:0: topic: ...", a line 0 the log does not have
    (["info", "{good.clf}", "--topic", "ODOM"], "topic: 'ODOM' is not a CARMEN laser message kind (FLASER, RLASER, "
                                                "ROBOTLASER1, ROBOTLASER2, RAWLASER1, RAWLASER2, RAWLASER3, RAWLASER4); "),
    (["slam", "{good.clf}", "--topic", "robotlaser1", "--out", O], "(did you mean ROBOTLASER1?); "),
    (["sim2real", "{good.clf}", "--topic", "/scan", "--out", O], "good.clf: its laser lines: ROBOTLASER1 (5)"),
    (["info", "{good.clf}", "--laser-angle-min-deg", "1000"], "--laser-angle-min-deg: a bearing must be within"),
    (["info", "{good.clf}", "--laser-angle-min-deg", "1e308"], "+-360 deg"),
    (["info", "{good.clf}", "--laser-range-max", "1e308"], "--laser-range-max: must be at most 10000 m"),
    # a subnormal (or a millimetre) max range: accepted, then every reading was invalid (info: 100 %)
    (["info", "{good.clf}", "--laser-range-max", "1e-320"], "--laser-range-max: must be at least 0.1 m"),
    (["simulate", "--sensor", "{sensor_cap.yaml}", "--duration", "1", "--out", O],
     "max_reading: must be in [0.1, range_max = 8.183] m, got 1e-320"),
    (["slam", "{good.clf}", "--laser-range-max", "0.001", "--out", O], "--laser-range-max: must be at least 0.1 m"),
    # not above the log's range_min (PARAM lmsbench_range_min 2.0): every laser line was malformed, one by one
    (["info", "{range_min_2.clf}", "--laser-range-max", "1.5", "--skip-bad-lines"],
     "range_min_2.clf:7: the range_max override (1.5 m, --laser-range-max) is not above this log's range_min (2 m"),
    (["info", "{good.clf}", "--laser-fov-deg", "-5"], "(-5 deg)"),
    (["compare", "{good.clf}", "--laser-resolution-deg", "1", "--out", O], "own beam geometry"),
    # calibrate
    (["calibrate", "{good.clf}", "--out", "{a_file/sensor.yaml}"], "/a_file is not a folder"),  # a file in the folder's place
    # --no-paper-baseline on a run of the paper preset itself set nothing, exit 0
    (["slam", "{good.clf}", "--preset", "paper", "--no-paper-baseline", "--out", O],
     "--no-paper-baseline: this run is the paper preset itself, so there is no separate paper baseline to leave out"),
    # --no-odometry-baseline on an input without odometry set nothing (the baseline runs only with it), exit 0
    (["slam", "{good.clf}", "--no-odometry-baseline", "--out", O],
     "good.clf has no odometry, so there is no odometry baseline to leave out (it runs only on an input with odometry "
     "on every scan)"),
    (["slam", "{simrun}", "--preset", "paper", "--no-odometry-baseline", "--out", O],
     "--no-odometry-baseline: "),
    # a log's reading options where no log is compared were ignored, exit 0
    (["compare", "office:0", "--topic", "FLASER", "--skip-bad-lines", "--out", O],
     "--topic, --skip-bad-lines say how to read a log; none of office:0 is one (the worlds are simulated)"),
    (["compare", "office", "--laser-fov-deg", "180", "--out", O], "--laser-fov-deg says how to read a log; none of office"),
    # a world's name in other case, and a simulate folder given as its world, were only "unknown world"
    (["simulate", "--world", "OFFICE", "--out", O], "--world: unknown world 'OFFICE' (did you mean office?); known worlds:"),
    (["demo", "--world", "Office", "--out", O], "unknown world 'Office' (did you mean office?); known worlds:"),
    (["simulate", "--world", "{simbroken}", "--out", O], "(a folder holding world.json: give "),
    # a file where a folder is read: "no such folder", and a sweep file for its folder "no results.parquet"
    (["figures", "--tables", "{good.clf}", "--out", O], "good.clf is a file, not a folder of tables"),
    (["figures", "--sweep", "{sweep.yaml}", "--no-slam", "--out", O], "sweep.yaml is a file, not a sweep folder"),
    # a folder that does not exist was said as a file is, "nodir is not a folder"
    (["calibrate", "{good.clf}", "--out", "{out}/nodir/sensor.yaml"], "/nodir/sensor.yaml: no folder "),
    (["lms200", "record", "--port", "loop://", "--out", "{out}/nodir/rec.clf"], "nodir; make it first (a file's folder is not made"),
    (["calibrate", "{good.clf}", "--out", "{empty_dir}"], "is a folder; give a file name"),
    (["calibrate", "{good.clf}", "--out", "/proc/sensor.yaml"], "not a writable folder"),
    (["compare", "{good.clf}", "--out", "/proc/lmsbench-out"], "not a writable folder"),
    (["calibrate", "{missing.clf}"], "missing.clf"),
    (["calibrate", "{binary.clf}"], "binary"),
    (["calibrate", "{plain.gz}"], "gzip"),
    (["calibrate", "{empty_dir}"], "empty_dir"),
    (["calibrate", "{good.clf}", "--stride", "0"], "--stride"),
    (["calibrate", "{good.clf}", "--max-scans", "-3"], "--max-scans"),
    (["calibrate", "{good.clf}", "--world", "offfice"], "offfice"),
    (["calibrate", "{good.clf}", "--out", "{empty_dir}"], "is a folder"),
    (["calibrate", "{good.clf}", "--out", "{good.clf}"], "calibrate writes a sensor YAML"),  # wrote over the log
    (["calibrate", "{good.clf}", "--out", "sensor.txt"], "sensor.txt: calibrate writes a sensor YAML; give a file name ending in .yaml"),
    (["calibrate", "{good.clf}", "--out", "{missing_dir}/s.yaml"], "missing_dir"),
    (["calibrate", "{good.clf}", "--laser-resolution-deg", "-1"], "--laser-resolution-deg"),
    (["calibrate", "{mixed.clf}"], "mixed.clf: scan 1 has 181 beams at 1 deg, scan 0 361 at 0.5 deg"),
    (["calibrate", "{far.clf}"], "far.clf: too few straight runs of beams at 1-4 m"),  # named no file
    (["calibrate", "{zero_beams.clf}"], "zero_beams.clf:1: malformed FLASER line: FLASER needs at least one beam"),
    # sim2real
    (["sim2real", "{missing.clf}", "--out", O], "missing.clf"),
    (["sim2real", "{binary.clf}", "--out", O], "binary"),
    (["sim2real", "{good.clf}", "--world", "offfice", "--out", O], "offfice"),
    (["sim2real", "{good.clf}", "--seeds", "-1", "--out", O], "--seeds"),
    (["sim2real", "{good.clf}", "--rate-hz", "1e9", "--out", O], "--rate-hz: 1e+09 scans/s is more than"),
    (["sim2real", "{good.clf}", "--world", "office", "--fit-rooms", "--out", O], "--fit-rooms"),
    (["sim2real", "{good.clf}", "--duration", "inf", "--out", O], "--duration"),
    (["sim2real", "{good.clf}", "--duration", "1e300", "--out", O], "--duration"),  # a tour that long never ends
    (["sim2real", "{good.clf}", "--probe-duration", "1e7", "--out", O], "--probe-duration"),
    (["sim2real", "{good.clf}", "--world", "office", "--probe-duration", "60", "--out", O], "--probe-duration"),
    (["sim2real", "{good.clf}", "--seeds", "1", "1", "--out", O], "--seeds"),
    (["sim2real", "{good.clf}", "--rate-hz", "0", "--out", O], "--rate-hz"),
    (["sim2real", "{good.clf}", "--stride", "0", "--out", O], "--stride"),
    (["sim2real", "{good.clf}", "--sensor", "{missing.yaml}", "--out", O], "missing.yaml"),
    (["sim2real", "{good.clf}", "--sensor", "{binary.yaml}", "--out", O], "binary.yaml"),
    (["sim2real", "{good.clf}", "--sensor", "{list.yaml}", "--out", O], "list.yaml"),
    (["sim2real", "{good.clf}", "--out", "{a_file}"], "a_file"),
    (["sim2real", "{good.clf}", "--seeds", "3", "4", "--probe-seeds", "4", "--out", O], "--probe-seeds: seed(s) 4 also in --seeds"),
    (["sim2real", "{good.clf}", "--probe-seeds", "100", "100", "--out", O], "--probe-seeds: seed(s) 100 given more than once"),
    (["sim2real", "{good.clf}", "--seeds", "100", "101", "--out", O], "--probe-seeds: seed(s) 100, 101 also in --seeds"),
    (["sim2real", "{good.clf}", "--probe-seeds", "-1", "--out", O], "--probe-seeds"),
    # its scans of 181 and 361 beams were compared with one simulated sensor (calibrated on every 2nd scan)
    (["sim2real", "{mixed.clf}", "--sensor", "{sensor_ok.yaml}", "--out", O], "mixed.clf: scan 5 has 181 beams"),
    (["sim2real", "{mixed.clf}", "--stride", "1", "--out", O], "mixed.clf: scan 1 has 181 beams at 1 deg"),
    (["sim2real", "{good.clf}", "--sensor", "{sensor_1deg.yaml}", "--out", O], "181 beams at 1 deg, but"),
    (["sim2real", "{good.clf}", "--world", "office", "--probe-seeds", "100", "--out", O], "--probe-seeds sets the mit"),
    # YAML errors named PyYAML's "<unicode string>" after the file, over several lines with a caret;
    # figures --sweep read its sweep.yaml only after the study: an internal error (Malformed / AttributeError)
    (["slam", "{simrun}", "--config", "{badyaml.yaml}", "--out", O], "badyaml.yaml: not valid YAML (line 2, column 1: "
     "expected ',' or ']', but got '<stream end>' (while parsing a flow sequence at line 1, column 4))"),
    (["sweep", "{badyaml.yaml}", "--out", O], "badyaml.yaml: not valid YAML: line 2, column 1: expected ',' or ']'"),
    (["simulate", "--config", "{badyaml.yaml}", "--out", O], "badyaml.yaml: not valid YAML (line 2, column 1: expected"),
    (["simulate", "--sensor", "{badcolon.yaml}", "--out", O],
     "badcolon.yaml: not valid YAML (line 2, column 4: mapping values are not allowed here)"),
    (["sim2real", "{good.clf}", "--sensor", "{badalias.yaml}", "--out", O],
     "badalias.yaml: not valid YAML (line 1, column 14: found undefined alias 'nope')"),
    (["compare", "{simbadyaml}", "--out", O], "config.yaml: not a simulate config (line 2, column 1: expected ',' or '}'"),
    (["compare", "{simemptycfg}", "--out", O], "config.yaml: not a simulate config (it has no sensor: mapping"),
    (["compare", "{simnosensor}", "--out", O], "config.yaml: not a simulate config (it has no sensor: mapping"),
    (["figures", "--sweep", "{sweep_badspec}", "--no-slam", "--out", O], "sweep.yaml: not valid YAML (line 2, column 1: "),
    (["figures", "--sweep", "{sweep_listspec}", "--no-slam", "--out", O], "sweep.yaml: not the sweep.yaml of `lmsbench sweep`"),
    # bench, the top level
    (["bench", "nosuch"], "nosuch"),
    (["bench", "lms200", "lms200"], "more than once"),
    (["bench", "lms200", "--out", "{a_file}"], "a_file"),
    (["nosuch"], "nosuch"),
    # an unknown option was said by the top-level parser ("lmsbench: error: ... see lmsbench --help")
    (["compare", "office", "--ideal", "--out", O], "lmsbench compare: error: unrecognized arguments: --ideal (--ideal is an option of: simulate; see lmsbench compare --help)"),
    (["lms200", "emulate", "--bogus", "1"], "lmsbench lms200 emulate: error: unrecognized arguments: --bogus 1"),
    (["simulate", "--world", "office", "--dur", "1", "--out", O], "lmsbench simulate: error: unrecognized arguments: --dur 1"),  # ran as --duration 1
    # an unknown option before the command was said by the command's parser (or as its missing SOURCES)
    (["--bogus", "compare", "office", "--out", O], "lmsbench: error: unrecognized arguments: --bogus (see lmsbench --help)"),
    (["--bogus", "compare"], "lmsbench: error: unrecognized arguments: --bogus (see lmsbench --help)"),
    (["--out=x", "info", "{good.clf}"], "lmsbench: error: unrecognized arguments: --out=x"),
    (["lms200", "--port", "loop://", "record", "--out", "{out}/x.clf"], "lmsbench lms200: error: unrecognized arguments: --port"),
    # an option given twice: argparse kept the last (seed 2 ran, the run went to the second --out)
    (["simulate", "--seed", "1", "--duration", "0.5", "--seed", "2", "--out", O],
     "lmsbench simulate: error: argument --seed: given 2 times; give it once"),
    (["simulate", "--duration", "0.5", "--out", "{out}/a", "--out={out}/b"], "argument --out: given 2 times; give it once"),
    (["compare", "{good.clf}", "--methods", "sensor", "--methods", "iepf", "--out", O], "argument --methods: given 2 times"),
    (["simulate", "--duration", "0.5", "--resolution-deg", "1", "--resolution", "0.5", "--out", O],
     "argument --resolution-deg/--resolution: given 2 times; give it once"),  # an option's two spellings both named
    (["info", "{good.clf}", "--laser-fov-deg", "180", "--laser-fov-deg", "100"], "argument --laser-fov-deg: given 2 times"),
    (["slam", "{sim_nan_truth}", "--out", O], "sim_nan_truth/groundtruth.tum:5: TUM row has a non-finite number: '0.2 nan"),
    (["slam", "{sim_back_truth}", "--out", O], "sim_back_truth/groundtruth.tum:5: TUM stamps go backwards (0.050000 s after 0.200000 s)"),
    # a real log for Fig. 9 without a valid beam: "internal error: ZeroDivisionError" after the whole study
    (["figures", "--intel", "{no_returns.clf}", "--no-slam", "--duration", "0.5", "--methods", "sensor", "--out", O],
     "no_returns.clf: none of its 5 scans has a valid beam (all +inf, nan or 0): no scan to draw for Fig. 9"),
    (["demo", "--log", "{no_returns.clf}", "--no-sweep", "--duration", "0.5", "--out", O], "no_returns.clf: none of its 5 scans"),
    # compare options that apply to none of the sources were ignored (office:1 --seeds 4 5 ran seed 1 alone)
    (["compare", "office:1", "--seeds", "4", "5", "--out", O], "--seeds sets the seeds of the worlds named without one "
                                                               "(office); none of office:1 is one"),
    (["compare", "{good.clf}", "--duration", "60", "--out", O], "--duration sets the worlds compare simulates"),
    (["compare", "{good.clf}", "--rate", "5", "--out", O], "--rate sets the worlds compare simulates"),
    (["compare", "office", "--stride", "2", "--out", O], "--stride thins logs and simulate folders; none of office is one"),
    (["compare", "office:1", "--poses", "corrected", "--out", O], "--poses says whether a log's poses are SLAM-corrected; "
                                                                 "none of office:1 is a log"),
    # an empty SLAM config ran the defaults silently (simulate --config and sweep refuse theirs)
    (["slam", "{good.clf}", "--config", "{empty.yaml}", "--out", O], "empty.yaml: no SLAM config field in it (empty, or "
                                                                     "comments only)"),
    # a log cut short names how to read on; a link to nothing says so ("no such log" named the link)
    (["info", "{cut_short.clf}"], "cut_short.clf:10: malformed ROBOTLASER1 line: ROBOTLASER1 announces 361 beams but has fewer fields"),
    (["info", "{cut_short.clf}"], "(--skip-bad-lines skips malformed lines, each reported)"),
    (["compare", "{dangling.clf}", "--out", O], "dangling.clf: a symbolic link to "),
    # a space around --set's name: its hint said "(write extractor. extractor.k)", or no field 'k ' was found
    (["compare", "office:0", "--set", " extractor.k=3", "--out", O],
     "argument --set: --set ' extractor.k=3': a space around the field's name; write extractor.k=3"),
    (["slam", "{good.clf}", "--set", "extractor.k =3", "--out", O], "a space around the field's name; write extractor.k=3"),
    (["compare", "office:0", "--set", "extractor.sensor.k=", "--out", O],  # it said "k must be ..., got None"
     "argument --set: --set extractor.sensor.k: no value after '='; give extractor.sensor.k=VALUE"),
    # a sensor YAML of comments only (`calibrate LOG > s.yaml` that failed) said "got NoneType", and a link to
    # nothing "no such sensor file", where every other input names the link
    (["simulate", "--sensor", "{empty.yaml}", "--duration", "0.5", "--out", O],
     "empty.yaml: empty (no sensor field, only comments or nothing); a sensor YAML holds the fields"),
    (["sim2real", "{good.clf}", "--sensor", "{empty.yaml}", "--out", O], "empty.yaml: empty (no sensor field"),
    (["compare", "office:0", "--sensor", "{dangling.clf}", "--out", O], "dangling.clf: a symbolic link to "),
    # lms200 record replaced an earlier CARMEN recording silently (bags were refused); a folder was "unknown kind"
    (["lms200", "record", "--port", "loop://", "--out", "{good.clf}"], "good.clf exists; a recording is not written over a file"),
    (["lms200", "record", "--port", "loop://", "--out", "{empty_dir}"], "empty_dir is a folder; give a file name"),
    # a link to nothing was said to exist ("dangling.clf exists; a recording is not written over a file")
    (["lms200", "record", "--port", "loop://", "--out", "{dangling.clf}"], "dangling.clf: a symbolic link to "),
    # an empty path is the current folder to pathlib (`--out "$OUT"` with OUT unset)
    (["slam", "", "--out", O], "lmsbench slam: error: argument input: empty path ''; give a file or folder name"),
    (["info", ""], "lmsbench info: error: empty path '' given as a log"),
    (["compare", "office:1", "--sensor", "", "--out", O], "argument --sensor: empty path ''"),
]


def _fill(argv: list[str], files: dict, out: Path) -> list[str]:
    def one(word: str) -> str:
        word = word.replace("{out}", str(out))
        if word.startswith("{") and word.endswith("}"):
            return files.get(word[1:-1], str(files["dir"] / word[1:-1]))
        return word
    return [one(w) for w in argv]


@pytest.mark.parametrize("argv, expected", CASES, ids=[" ".join(c[0]) for c in CASES])
def test_bad_input_is_one_line_exit_2_and_writes_nothing(argv, expected, files, tmp_path, capsys):
    out = tmp_path / "out"
    args = _fill(argv, files, out)
    before = sorted(p.name for p in files["dir"].iterdir())
    status = run_main(args)
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert status == 2, f"exit {status}, stderr: {err}"
    assert len(lines) == 1, f"expected one line on stderr, got: {err}"
    assert lines[0].startswith("lmsbench") and ": error: " in lines[0], lines[0]
    assert "Traceback" not in err and "internal error" not in err
    assert expected in lines[0], lines[0]
    assert not out.exists() or not any(out.iterdir()), f"wrote {list(out.iterdir())}"
    assert sorted(p.name for p in files["dir"].iterdir()) == before


@pytest.mark.parametrize("command", [["figures", "--no-slam"], ["figures"], ["demo", "--no-sweep"]])
def test_a_rate_above_the_sensors_is_refused_before_the_study_starts(command, tmp_path, capsys):
    """figures / demo --rate-hz 1e9 was refused only once the study's simulation began (after the
    Intel log's panels, narrated on stdout), and the demo left its --out folder behind, empty."""
    out = tmp_path / "out"
    assert run_main([*command, "--rate-hz", "1e9", "--duration", "0.5", "--out", str(out)]) == 2
    captured = capsys.readouterr()
    assert captured.err.strip().splitlines() == [
        f"lmsbench {command[0]}: error: --rate-hz: 1e+09 scans/s is more than the sensor gives (37.5 scans/s at 0.5 deg)"]
    assert captured.out == "" and not out.exists()


@pytest.mark.parametrize("argv", [["simulate", "--duration", "5"], ["compare", "office:0", "--duration", "5"],
                                  ["sim2real", "{good.clf}"], ["figures", "--no-slam"], ["demo", "--no-sweep"]],
                         ids=lambda a: a[0])
@pytest.mark.parametrize("rate", ["1e-308", "5e-324", "0.0001"])
def test_a_rate_below_one_scan_an_hour_is_refused_before_any_work(argv, rate, files, tmp_path, capsys):
    """`simulate --rate-hz 1e-308` (and compare --rate, sim2real / figures / demo / slam --rate-hz) ran
    and kept the first scan alone, exit 0 (slam refused it only after reading the whole input): no run
    of at most an hour keeps a second scan below 1/3600 scans/s."""
    out = tmp_path / "out"
    flag = "--rate" if argv[0] == "compare" else "--rate-hz"
    status = run_main([*_fill(argv, files, out), flag, rate, "--out", str(out)])
    captured = capsys.readouterr()
    assert status == 2
    assert captured.err.strip().splitlines() == [
        f"lmsbench {argv[0]}: error: argument {'--rate/--rate-hz' if argv[0] == 'compare' else '--rate-hz'}: must be at "
        "least 1/3600 scans/s (one scan an hour, the longest simulated run: a lower rate keeps the first scan alone), "
        f"got '{rate}' (see lmsbench {argv[0]} --help)"]
    assert captured.out == "" and not out.exists()


def test_slam_rate_hz_has_no_floor_on_a_log_longer_than_an_hour(tmp_path, capsys):
    """slam reads real logs, which may last a day: --rate-hz 0.0002 (one scan per 5000 s) of a 24 h log
    keeps 13 of its 25 hourly scans, and was refused as "below 1/3600 scans/s (... a lower rate keeps the
    first scan alone)", false there. A rate that keeps one scan alone is refused after the read, with the count."""
    from experiments.slamrun import load_input

    log = tmp_path / "day.clf"
    write_log(log, [Record(Scan.lms200(np.full(361, 2.0 + 0.01 * k), stamp=3600.0 * k)) for k in range(25)])
    data = load_input(log, rate_hz=0.0002)
    assert data.numbers == list(range(0, 25, 2)) and [r.scan.stamp for r in data.records][-1] == 86400.0
    for rate in ("1e-308", "5e-324"):
        assert main(["slam", str(log), "--rate-hz", rate, "--out", str(tmp_path / "o")]) == 2
        assert capsys.readouterr().err.strip().splitlines() == [
            f"lmsbench slam: error: {log}: --rate-hz {float(rate):g} keeps 1 of the 25 scans read (stamps 0.000000 to "
            "86400.000000 s); SLAM needs two or more"]
    assert main(["slam", str(log), "--rate-hz", "0", "--out", str(tmp_path / "o")]) == 2
    assert "argument --rate-hz: must be a finite number > 0 scans/s, got '0'" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_the_issue_cases_are_all_here():
    """The issue's list, by command, is covered (and more of each kind)."""
    by_command = {}
    for argv, _ in CASES:
        by_command[argv[0]] = by_command.get(argv[0], 0) + 1
    assert all(by_command[c] >= 4 for c in ("simulate", "compare", "slam", "sweep", "figures", "demo", "lms200", "info",
                                                 "calibrate", "sim2real"))
    assert len(CASES) >= 100


def test_an_error_found_mid_run_is_still_stderr_s_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A log whose line 31 is cut short is found out after 30 scans were compared: the progress
    bar's carriage-return frames before it made stderr several lines for anything that splits on
    them (Python's splitlines, a text-mode pipe); off a terminal there is no bar now."""
    scans = [Scan.lms200(np.full(361, 2.0 + 0.01 * k), stamp=0.2 * k) for k in range(40)]
    write_log(tmp_path / "log.clf", [Record(s) for s in scans])
    lines = (tmp_path / "log.clf").read_text().splitlines(keepends=True)
    laser = [i for i, line in enumerate(lines) if line.startswith("ROBOTLASER1")]
    lines[laser[30]] = " ".join(lines[laser[30]].split()[:100]) + "\n"
    (tmp_path / "cut.clf").write_text("".join(lines))
    assert main(["compare", str(tmp_path / "cut.clf"), "--methods", "hough", "--sigma", "0.01",
                 "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.strip().splitlines() == [err.strip()] and "ROBOTLASER1" in err
    assert f":{laser[30] + 1}:" in err


@pytest.mark.parametrize("command", [["info"], ["compare"], ["calibrate"], ["sim2real"], ["slam", "--out", "o"]])
def test_a_log_through_process_substitution_is_refused_saying_why(files, tmp_path, capsys, command):
    """`lmsbench info <(zcat LOG.gz)`: the pipe was refused, "not a regular file (a pipe, a device or
    a socket); give the file itself", without why; a log is read more than once (the reader's first
    lines to choose the laser, then every line; compare and sim2real again, for the
    noise), so it needs a file. A pipe with a writer, as bash's <(...) gives, is refused unread."""
    r, w = os.pipe()
    os.write(w, Path(files["good.clf"]).read_bytes()[:4096])  # a live writer's first bytes (within the pipe's buffer)
    try:
        argv = [command[0], f"/dev/fd/{r}", *[str(tmp_path / a) if a == "o" else a for a in command[1:]]]
        assert run_main(argv) == 2
        assert len(os.read(r, 8192)) == 4096  # refused unread
    finally:
        os.close(w)
        os.close(r)
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith(f"lmsbench {command[0]}: error: /dev/fd/{r}: a pipe "
                                                         "(such as <(zcat LOG)), not a file: a log is read more than once")
    assert err.endswith("or save the stream to a file first (zcat LOG > FILE)")


@pytest.mark.parametrize("command, what", [(["slam", "{good.clf}", "--config"], "a SLAM config.yaml"),
                                           (["simulate", "--config"], "a simulate config.yaml"),
                                           (["sweep"], "a sweep file")])
def test_a_config_through_process_substitution_is_refused_saying_why(files, tmp_path, capsys, command, what):
    """`lmsbench slam LOG --config <(cat x.yaml)` (or `--config /dev/stdin` fed by a pipe) said "not a
    regular file (a pipe, a device or a socket); give the file itself": now that a config must be a
    regular file and why. Refused unread: the writer's bytes are still in the pipe."""
    r, w = os.pipe()
    os.write(w, b"slam: {preset: paper}\n")
    try:
        argv = [files.get(a[1:-1], a) if a.startswith("{") else a for a in command] + [f"/dev/fd/{r}", "--out", str(tmp_path / "o")]
        assert run_main(argv) == 2
        assert os.read(r, 8192) == b"slam: {preset: paper}\n"
    finally:
        os.close(w)
        os.close(r)
    err = capsys.readouterr().err.strip()
    assert err.splitlines() == [f"lmsbench {command[0]}: error: /dev/fd/{r}: not a regular file but a pipe (<(cat FILE), "
                                f"/dev/stdin fed by a pipe, a FIFO): {what} must be a regular file, as it is checked "
                                "before it is read and a pipe's bytes are gone once read; give the file itself (or save "
                                "the stream to a file first)"]
    assert not (tmp_path / "o").exists()


def test_two_logs_of_one_name_are_refused_before_any_work(files, tmp_path, capsys):
    """compare names a log by its file name: two runs' good.clf were summed into one row."""
    twin = tmp_path / "twin"
    twin.mkdir()
    (twin / "good.clf").write_text(Path(files["good.clf"]).read_text())
    assert run_main(["compare", files["good.clf"], str(twin / "good.clf"), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"lmsbench compare: error: {files['good.clf']} and {twin / 'good.clf'} would both be reported as "
                   "'good.clf' (compare names a source by its world, folder or file name): give one of them another "
                   "name, e.g. a link"]
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("first, second", [("a b.clf", "a_b.clf"), ("\u00e4.clf", "\u00f6.clf")])
def test_two_logs_of_one_figure_name_are_refused_before_any_work(files, tmp_path, capsys, first, second):
    """A log's figure is named by its file name kept to letters, digits, _ and -: "a b.clf" and
    "a_b.clf" (or "ä.clf" and "ö.clf") both wrote realdata_a_b_clf.* (realdata__clf.*), the second
    over the first, exit 0 ('wrote ..., realdata_a_b_clf.png, realdata_a_b_clf.png')."""
    text = Path(files["good.clf"]).read_text()
    for name in (first, second):
        (tmp_path / name).write_text(text)
    stem = "realdata_a_b_clf" if first.startswith("a") else "realdata__clf"
    assert run_main(["compare", str(tmp_path / first), str(tmp_path / second), "--out", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench compare: error: {tmp_path / first} and {tmp_path / second} would both write their figure as "
        f"{stem}.png (a figure's name keeps only letters, digits, _ and - of the file name): give one of them another "
        "name, e.g. a link"]
    assert not (tmp_path / "o").exists()


def _sweep_folder(folder: Path, f1: float, spec: str) -> Path:
    folder.mkdir(parents=True)
    seeds = [0, 1] if "seeds: [0, 1]" in spec else [0, 0]  # each row one cell of the spec (figures checks it)
    pd.DataFrame({"x": [1, 2], "status": ["ok", "ok"], "error": ["", ""], "cell": ["a", "b"], "seed": seeds,
                  "f1": [f1, f1]}).to_parquet(folder / "results.parquet")
    (folder / "sweep.yaml").write_text(spec)
    return folder


@pytest.mark.parametrize("spec", ["name: k_vs_noise\nkind: extract\ngrid:\n  x: [1, 2]\n",  # one sweep file, two --out
                                  "kind: extract\ngrid:\n  x: [1, 2]\n"])  # no name: both folders named "sweep"
def test_two_sweeps_of_one_plot_name_are_refused_before_any_work(tmp_path, capsys, spec):
    """`figures --sweep a/sweep --sweep b/sweep` of two sweeps of one name (one sweep file run into
    two folders, or two folders of one name without a name:) drew b's sweep_NAME_f1 plot over a's,
    exit 0 ('sweep_sweep_f1 ... wrote 31 files', a's f1 of 0.5 nowhere): refused before any work,
    one line, naming both folders and the plot, as compare refuses two logs of one figure name."""
    a = _sweep_folder(tmp_path / "a" / "sweep", 0.5, spec)
    b = _sweep_folder(tmp_path / "b" / "sweep", 0.9, spec)
    stem = "sweep_k_vs_noise_f1" if spec.startswith("name") else "sweep_sweep_f1"
    assert run_main(["figures", "--sweep", str(a), "--sweep", str(b), "--out", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench figures: error: --sweep {a} and --sweep {b} would both write their plot {stem}.png (a sweep's plots "
        "are named by the name: of its sweep.yaml, else by its folder's name): draw them with two runs of figures "
        "(another --out), or give one of them another name: in its sweep.yaml"]
    assert not (tmp_path / "o").exists()
    assert run_main(["figures", "--sweep", str(a), "--sweep", str(a) + "/", "--out", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench figures: error: --sweep {a} is given twice ({a} and {a}): each sweep folder once"]
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("f1, spec, why", [
    (float("nan"), "name: nan\nkind: extract\ngrid:\n  x: [1, 2]\n",
     "no metric has a value in its results.parquet (0 of its 2 cells failed, the others gave no finite number for any "
     "metric (nan, inf, text or a bool)"),
    (0.5, "name: flat\nkind: extract\nfixed:\n  x: 1\nseeds: [0, 1]\n",  # two cells, as its table's
     "no grid parameter takes two values and none is sampled, so there is nothing to plot the metrics against")])
def test_a_sweep_with_nothing_to_plot_is_refused_before_any_work(tmp_path, capsys, f1, spec, why):
    """`figures --sweep S` of a sweep whose cells all gave nan (or that varies nothing) drew no plot
    of it and said nothing, exit 0 ("wrote 31 files", none of the sweep): refused before any work."""
    folder = _sweep_folder(tmp_path / "s", f1, spec)
    assert run_main(["figures", "--sweep", str(folder), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"lmsbench figures: error: --sweep {folder}: {why}"), err
    assert not (tmp_path / "o").exists()


def test_sweeps_of_other_names_are_drawn_side_by_side(tmp_path):
    """The check leaves two sweeps of other names alone: each one's plots are drawn."""
    from experiments.commands.figures import _check_sweeps_apart
    from experiments.figures.make import sweep_stems
    from experiments.options import read_sweep_results

    a = _sweep_folder(tmp_path / "a" / "sweep", 0.5, "name: one\nkind: extract\ngrid:\n  x: [1, 2]\n")
    b = _sweep_folder(tmp_path / "b" / "sweep", 0.9, "name: two\nkind: extract\ngrid:\n  x: [1, 2]\n")
    assert sweep_stems(a) == ["sweep_one_f1"] and sweep_stems(b) == ["sweep_two_f1"]
    _check_sweeps_apart([read_sweep_results(a), read_sweep_results(b)])  # each folder with its table and sweep.yaml


def test_out_may_not_write_over_what_the_run_reads(files, tmp_path, capsys):
    """`compare SIMFOLDER --out SIMFOLDER` replaced the folder's config.yaml (the simulate config
    whose sensor model compare reads for it) with compare's own, exit 0; sim2real's sensor.yaml
    likewise over its --sensor. Now refused before any work, the input untouched."""
    from experiments.cli import main as cli_main

    sim = tmp_path / "sim"
    assert cli_main(["simulate", "--duration", "2", "--out", str(sim)]) == 0
    before = {p.name: p.read_bytes() for p in sim.iterdir()}
    assert run_main(["compare", str(sim), "--methods", "hough", "--out", str(sim)]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench compare: error: --out {sim}: the run would write config.yaml over {sim / 'config.yaml'}, which it "
        "reads; give another folder"]
    (sim / "sensor.yaml").write_text(Path(files["sensor_ok.yaml"]).read_text())
    before["sensor.yaml"] = (sim / "sensor.yaml").read_bytes()
    assert run_main(["sim2real", files["good.clf"], "--sensor", str(sim / "sensor.yaml"), "--out", str(sim)]) == 2
    assert "the run would write sensor.yaml over" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in sim.iterdir()} == before


def test_a_latin1_comment_near_the_top_is_read_as_further_down(files, tmp_path, capsys):
    """A log whose first 4 KB held one byte that is not UTF-8 (a latin-1 comment) was refused as
    "not text (byte 517 is not UTF-8)", while the same comment further down was read (the reader
    reads ASCII, other bytes replaced). Now both read alike; a head of mostly such bytes is binary."""
    lines = Path(files["good.clf"]).read_bytes().split(b"\n")
    for name, at in (("early.clf", 1), ("late.clf", len(lines) - 2)):
        (tmp_path / name).write_bytes(b"\n".join(lines[:at] + [b"# commentaire \xe9t\xe9"] + lines[at:]))
    assert run_main(["info", str(tmp_path / "late.clf"), "--json"]) == 0
    late = json.loads(capsys.readouterr().out)
    assert run_main(["info", str(tmp_path / "early.clf"), "--json"]) == 0
    early = json.loads(capsys.readouterr().out)
    assert early["scans"] == late["scans"] == 5
    (tmp_path / "latin.clf").write_bytes(bytes([0xE9]) * 300 + b"FLASER 1 1.0 0 0 0 0 0 0 1.0 h 1.0\n" * 20)
    assert run_main(["info", str(tmp_path / "latin.clf")]) == 2
    assert "a binary file (300 of its first 1000 bytes are not ASCII text)" in capsys.readouterr().err


@pytest.mark.parametrize("argv, prog", [([], "lmsbench"), (["lms200"], "lmsbench lms200")])
def test_no_command_is_a_usage_error(argv: list[str], prog: str, capsys: pytest.CaptureFixture[str]) -> None:
    """``lmsbench`` alone printed the whole help to stdout and exited 1 (the status of an internal
    error); a missing command is a usage error: one line on stderr that lists the commands, exit 2."""
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1
    assert err.startswith(f"{prog}: error: ")
    if not argv:
        assert "a command is required: bench, calibrate, compare" in err
    else:  # was "the following arguments are required: ACTION", naming neither action
        assert err.startswith("lmsbench lms200: error: a command is required: emulate, record (see lmsbench lms200 --help)")


def test_compare_out_holds_only_compares_own_outputs(files, tmp_path, capsys):
    """`compare LOG --out FOLDER` replaced any file of FOLDER with one of its output names (a
    user's config.yaml or summary.csv) silently; a folder holding files compare does not write is
    now refused, one line, nothing touched. A folder of compare's own earlier outputs (its fixed
    files and each log's realdata_* figure) is replaced, as before."""
    out = tmp_path / "o"
    assert run_main(["compare", files["good.clf"], "--methods", "split_merge", "--out", str(out)]) == 0
    written = sorted(p.name for p in out.iterdir())
    assert "config.yaml" in written and any(n.startswith("realdata_") for n in written)
    assert run_main(["compare", files["good.clf"], "--methods", "split_merge", "--out", str(out)]) == 0  # a rerun
    capsys.readouterr()
    (out / "notes.txt").write_text("mine")
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert run_main(["compare", files["good.clf"], "--methods", "split_merge", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"lmsbench compare: error: --out {out}: holds notes.txt, which this command does not write; give a "
                   "new or empty folder (a folder of this command's own earlier outputs is replaced)"]
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


@pytest.mark.parametrize("command, theirs", [(["bench", "features", "--quick"], "bench.csv"), (["sim2real"], "config.yaml")])
def test_bench_and_sim2real_out_hold_only_their_own_outputs(command, theirs, files, tmp_path, capsys):
    """`bench --out DIR` and `sim2real LOG --out DIR` replaced a user's files of their outputs'
    names (bench.csv, config.yaml, sensor.yaml, ...) in DIR silently; a folder holding files the
    command does not write is refused before any work, one line, nothing touched."""
    out = tmp_path / "o"
    out.mkdir()
    (out / theirs).write_text("mine: 1\n")
    (out / "notes.txt").write_text("mine")
    argv = command + ([files["good.clf"]] if command == ["sim2real"] else []) + ["--out", str(out)]
    assert run_main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"lmsbench {command[0]}: error: --out {out}: holds notes.txt, which this command does not write; "
                   "give a new or empty folder (a folder of this command's own earlier outputs is replaced)"]
    assert sorted(p.name for p in out.iterdir()) == sorted([theirs, "notes.txt"])
    assert (out / theirs).read_text() == "mine: 1\n"


@pytest.mark.parametrize("value", ["all", "0", "-2", "1.5", "99999"])
def test_a_bad_thread_count_in_the_environment_is_refused_before_any_work(value, tmp_path, capsys, monkeypatch):
    """``$LMSBENCH_THREADS`` (the threads of ``features.extract_many``) is checked by every
    command before it starts (slam's extraction took the error for a batch of mixed geometry and
    fell back to one call a scan)."""
    scans = [Scan.lms200(np.full(361, 2.0 + 0.01 * k), stamp=0.2 * k) for k in range(40)]
    write_log(tmp_path / "log.clf", [Record(s) for s in scans])
    monkeypatch.setenv("LMSBENCH_THREADS", value)
    for argv in (["slam", str(tmp_path / "log.clf"), "--out", str(tmp_path / "o"), "--quiet"],
                 ["info", str(tmp_path / "log.clf")]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.strip().splitlines() == [
            f"lmsbench {argv[0]}: error: LMSBENCH_THREADS: must be a whole number from 1 to 1024, got {value!r}"]
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("command, theirs, others", [
    (["figures", "--no-slam", "--duration", "1", "--rate-hz", "2", "--methods", "sensor"], "fig3_scan.png",
     "notes.txt, tables/mine.csv"),
    (["demo", "--no-sweep", "--duration", "1", "--rate-hz", "2"], "report.md",
     "notes.txt, sweeps/demo_k_vs_noise/mine.csv, tables/mine.csv"),
])
def test_figures_and_demo_out_hold_only_their_own_outputs(command, theirs, others, tmp_path, capsys):
    """`figures --out DIR` and `demo --out DIR` replaced a user's files of their outputs' names
    (fig3_scan.png, report.md, tables/*.parquet) in DIR silently, and the demo deleted a
    sweeps/demo_k_vs_noise folder of DIR whole; a folder holding files the command does not write
    (also in the sub-folders it writes into) is refused before any work, one line, nothing touched."""
    out = tmp_path / "o"
    (out / "tables").mkdir(parents=True)
    (out / "tables" / "mine.csv").write_text("a\n1\n")
    (out / theirs).write_text("mine")
    (out / "notes.txt").write_text("mine")
    if command[0] == "demo":
        (out / "sweeps" / "demo_k_vs_noise").mkdir(parents=True)
        (out / "sweeps" / "demo_k_vs_noise" / "mine.csv").write_text("a\n1\n")
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert run_main(command + ["--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"lmsbench {command[0]}: error: --out {out}: holds {others}, which this command does not write; "
                   "give a new or empty folder (a folder of this command's own earlier outputs is replaced)"]
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before


def test_out_given_as_an_empty_string_is_refused_not_the_current_folder(tmp_path, monkeypatch, capsys):
    """`simulate --out ""` (a shell variable left unset) wrote the run into the current folder:
    Path("") is "."; it is refused, the folder left empty."""
    monkeypatch.chdir(tmp_path)
    assert run_main(["simulate", "--duration", "0.5", "--out", ""]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        "lmsbench simulate: error: argument --out: empty path ''; give a file or folder name (see lmsbench simulate --help)"]
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("argv", [["simulate", "--duration", "0.5", "--out", "-"], ["calibrate", "x.clf", "--out", "-"],
                                  ["slam", "-", "--out", "o"]])
def test_a_dash_is_no_path(argv, tmp_path, monkeypatch, capsys):
    """`simulate --out -` made a folder named '-' (and `calibrate --out -` a file), where '-' reads as
    the standard output."""
    monkeypatch.chdir(tmp_path)
    assert run_main(argv) == 2
    flag = "input" if argv[1] == "-" else "--out"
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench {argv[0]}: error: argument {flag}: '-' is no stream here: give a file or folder name (calibrate "
        f"without --out prints its YAML) (see lmsbench {argv[0]} --help)"]
    assert list(tmp_path.iterdir()) == []


def test_repeatable_options_and_flags_may_still_be_given_twice():
    """Only options that take one value are refused twice: --set and --sweep collect, a flag
    given twice means the same."""
    from experiments.cli import build_parser

    args = build_parser().parse_args(["compare", "office:1", "--set", "extractor.k=3", "--set", "extractor.ad_tau=2"])
    assert [p[0] for p in args.params] == ["extractor.k", "extractor.ad_tau"]
    args = build_parser().parse_args(["figures", "--sweep", "a", "--sweep", "b", "--no-slam", "--no-slam"])
    assert [str(p) for p in args.sweep] == ["a", "b"] and args.no_slam


@pytest.mark.parametrize("word", ["-9e1", "-90.", "-9.0E+1"])
def test_a_negative_number_with_an_exponent_or_a_trailing_point_is_an_options_value(word):
    """argparse 3.11 takes -90 and -.5 for numbers, any other word with a leading '-' for an
    option: `info LOG --laser-angle-min-deg -9e1` (a valid bearing) said "argument
    --laser-angle-min-deg: expected one argument"."""
    from experiments.cli import build_parser

    args = build_parser().parse_args(["info", "x.clf", "--laser-angle-min-deg", word])
    assert args.laser_angle_min_deg == -90.0


@pytest.mark.parametrize("option, word, says", [
    ("--seed", "-1e3", "argument --seed: must be a whole number >= 0 and <= 4294967295, got '-1e3'"),
    ("--duration", "-inf", "argument --duration: must be a finite number >= 0.1 and <= 3600 s, got '-inf'"),
    ("--duration", "-NaN", "argument --duration: must be a finite number >= 0.1 and <= 3600 s, got '-NaN'")])
def test_a_negative_number_out_of_range_says_its_range_not_expected_one_argument(option, word, says, tmp_path, capsys):
    assert run_main(["simulate", "--out", str(tmp_path / "o"), option, word]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench simulate: error: {says} (see lmsbench simulate --help)"]
    assert not (tmp_path / "o").exists()


def test_sweep_out_holds_only_sweep_outputs_and_not_the_sweep_file(files, tmp_path, capsys):
    """`sweep DIR/sweep.yaml --out DIR` wrote the resolved spec over the user's file (its comments
    lost), and `sweep --out DIR` replaced a user's results.csv in DIR; both are refused before any
    cell runs, nothing touched. Resuming into the sweep's own folder still works."""
    mine = tmp_path / "mine"
    mine.mkdir()
    text = "# k against nothing: my notes\n" + Path(files["sweep.yaml"]).read_text()
    (mine / "sweep.yaml").write_text(text)
    assert run_main(["sweep", str(mine / "sweep.yaml"), "--inprocess", "--no-progress", "--out", str(mine)]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench sweep: error: --out {mine}: the run would write sweep.yaml over {mine / 'sweep.yaml'}, which it "
        "reads; give another folder"]
    assert [p.name for p in mine.iterdir()] == ["sweep.yaml"] and (mine / "sweep.yaml").read_text() == text
    out = tmp_path / "out"
    argv = ["sweep", str(files["sweep.yaml"]), "--inprocess", "--no-progress", "--out", str(out)]
    assert run_main(argv, seconds=120) == 0 and run_main(argv, seconds=120) == 0  # a run, then a resume
    assert "1 cells, 0 computed, 1 already done" in capsys.readouterr().out
    record = (out / "sweep.yaml").read_text()  # the sweep as run, in its folder: run again from it (--out implied)
    assert run_main(["sweep", str(out / "sweep.yaml"), "--inprocess", "--no-progress", "--out", str(out)], seconds=120) == 0
    assert "1 cells, 0 computed, 1 already done" in capsys.readouterr().out and (out / "sweep.yaml").read_text() == record
    (out / "notes.md").write_text("mine")
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert run_main(argv) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench sweep: error: --out {out}: holds notes.md, which this command does not write; give a new or "
        "empty folder (a folder of this command's own earlier outputs is replaced)"]
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before


def test_a_system_error_names_its_file_without_errno_clutter():
    """An OSError with a file name (a file in a folder root may not read: set up as another user)
    read "[Errno 13] Permission denied: '/data/run/scans.clf'"; now FILE: reason."""
    from experiments.cli import _one_line

    assert _one_line(PermissionError(13, "Permission denied", "/data/run/scans.clf")) == \
        "/data/run/scans.clf: permission denied"
    assert _one_line(OSError(18, "Invalid cross-device link", "/a", None, "/b")) == "/a: invalid cross-device link (/b)"
    assert _one_line(TimeoutError("timed out")) == "timed out"


@pytest.mark.parametrize("argv, where", [(["simulate", "--duration", "0.5", "--out", "{out}"], "--out {out}"),
                                         (["calibrate", "{sim}", "--fit-duration", "1", "--out", "{out}.yaml"], "--out {out}.yaml")])
def test_a_full_disk_says_where_the_command_writes(argv, where, tmp_path, capsys, monkeypatch):
    """A full disk (a file's write or close raises ENOSPC without the file's name) was said as
    "error: [Errno 28] No space left on device", naming nothing; it now names the command's --out
    and the temporary folder, whichever disk filled."""
    import errno
    import tempfile

    sim = tmp_path / "sim"
    if argv[0] == "calibrate":
        assert run_main(["simulate", "--duration", "0.5", "--quiet", "--out", str(sim)]) == 0
    capsys.readouterr()

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr("experiments.provenance.write_synced", full)  # simulate's first write (its marker)
    monkeypatch.setattr("experiments.provenance.write_record", full)  # calibrate's YAML, every record
    out = tmp_path / "o"
    assert run_main([a.format(out=out, sim=sim) for a in argv]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench {argv[0]}: error: cannot write: no space left on device (on the disk of {where.format(out=out)} "
        f"or of the temporary folder {tempfile.gettempdir()})"]


@pytest.mark.parametrize("argv, base", [
    (["compare", "office:0", "--duration", "0.5", "--methods", "sensor"], "compare"),
    (["bench", "sim", "--quick"], "bench"),
    (["figures", "--no-slam", "--duration", "0.5", "--methods", "sensor"], "figures"),
    (["sim2real", "{good.clf}", "--sensor", "{sensor_ok.yaml}"], "sim2real"),
    (["demo", "--no-sweep", "--duration", "0.5"], "demo")])
def test_a_run_folder_that_cannot_be_made_is_refused_before_any_work(argv, base, files, tmp_path, capsys, monkeypatch):
    """Without --out a command makes results/CMD/DATE_TIME, which was not checked: where results is
    a file (or the folder read-only), bench ran every benchmark and figures its whole study, then
    failed with "results: not a directory" (their rows and tables lost). It is refused first."""
    import experiments.benchmarks.sim
    import experiments.demo
    import experiments.figures.study

    def no_work(*args, **kwargs):
        raise AssertionError("the work started")

    monkeypatch.setattr(experiments.benchmarks.sim, "run", no_work)
    monkeypatch.setattr(experiments.figures.study, "run_study", no_work)
    monkeypatch.setattr(experiments.demo, "run_study", no_work)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "results").write_text("mine")
    assert run_main(_fill(argv, files, tmp_path / "unused")) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench {argv[0]}: error: results is not a folder, so a run without --out cannot be made in "
        f"results/{base}; give --out"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results"]


def test_a_removed_current_folder_is_said_as_such(files, tmp_path):
    """`slam RUN --out rel` from a folder removed after the shell entered it said "error: [Errno 2] No
    such file or directory" (os.getcwd's error, naming no file)."""
    gone = tmp_path / "gone"
    gone.mkdir()
    script = ("import os, sys; from experiments.cli import main; os.chdir(sys.argv[1]); os.rmdir(sys.argv[1]); "
              "sys.exit(main(['slam', sys.argv[2], '--out', 'rel', '--quiet']))")
    run = subprocess.run([sys.executable, "-c", script, str(gone), str(files["good.clf"])], capture_output=True,
                         text=True, timeout=60, cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert run.returncode == 2, run.stderr
    assert run.stderr.strip().splitlines() == [
        "lmsbench slam: error: the current folder no longer exists (it was removed after the shell entered it); "
        "cd to one that does"]
    # without --out (the run folder in results/compare): it said ". is not a writable folder, so a run without
    # --out cannot be made in results/compare; give --out" (review)
    script = ("import os, sys; from experiments.cli import main; os.chdir(sys.argv[1]); os.rmdir(sys.argv[1]); "
              "sys.exit(main(['compare', 'office:0', '--duration', '0.5', '--methods', 'sensor', '--no-progress']))")
    gone.mkdir()
    run = subprocess.run([sys.executable, "-c", script, str(gone)], capture_output=True,
                         text=True, timeout=60, cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert run.returncode == 2, run.stderr
    assert run.stderr.strip().splitlines() == [
        "lmsbench compare: error: the current folder no longer exists (it was removed after the shell entered it); "
        "cd to one that does"]


def test_a_full_disk_under_pyarrow_is_said_once_as_the_systems_reason():
    """pyarrow's OSError of a full disk (a sweep's cell files) has its own text around the errno:
    the line read "cannot write: error writing bytes to file. Detail: [errno 28] No space left on device"."""
    import errno
    import tempfile

    from experiments.cli import _full_disk

    exc = OSError(errno.ENOSPC, "error writing bytes to file. Detail: [errno 28] No space left on device")
    assert _full_disk(exc, Path("sw")) == ("cannot write: no space left on device (on the disk of --out sw or of the "
                                           f"temporary folder {tempfile.gettempdir()})")
    assert _full_disk(OSError(errno.ENOSPC, "No space left on device", "a.clf"), None) == ""  # named: as every OSError
    assert _full_disk(OSError(errno.ENOENT, "No such file or directory"), None) == ""


def test_info_on_a_log_of_two_scan_sizes_says_whose_geometry_it_shows(files, capsys):
    """`info` on a log mixing 361 beams at 0.5 deg and 181 at 1 deg printed the first scan's field
    of view and resolution as the log's; it now says they are the first scan's."""
    assert run_main(["info", files["mixed.clf"]]) == 0
    out = capsys.readouterr().out
    assert "beams per scan  181-361" in out
    assert "resolution      0.500 deg, the first scan's" in out and "180.00 deg (from -90.00 deg), the first scan's" in out
    assert run_main(["info", files["good.clf"]]) == 0
    assert "resolution      0.500 deg\n" in capsys.readouterr().out


@pytest.mark.parametrize("argv", [["figures", "--intel", ""], ["demo", "--log", ""]])
def test_an_empty_log_path_is_refused_not_taken_for_the_default_log(argv, tmp_path, capsys):
    """`figures --intel ""` and `demo --log ""` (a shell variable left unset) ran on the default
    Intel log: the empty string read as "not given"."""
    assert run_main(argv + ["--out", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench {argv[0]}: error: argument {'--intel/--log' if argv[1] == '--intel' else argv[1]}: empty path ''; "
        "give a file or folder name "
        f"(see lmsbench {argv[0]} --help)"]
    assert not (tmp_path / "o").exists()


def test_compare_tells_worlds_from_files_by_name_for_sensor_as_for_seeds(tmp_path, monkeypatch, capsys):
    """A folder named like a world in the current folder: `compare office --sensor S` was refused
    ("none of office is one": --sensor told worlds by the path not existing) while --seeds and the
    run take `office` by its name, as a world."""
    import sim

    monkeypatch.chdir(tmp_path)
    (tmp_path / "office").mkdir()
    sim.SensorConfig().to_yaml(tmp_path / "s.yaml")
    assert run_main(["compare", "office", "--seeds", "1", "--duration", "0.5", "--methods", "split_merge",
                     "--sensor", "s.yaml", "--no-progress", "--out", "o"], seconds=120) == 0
    assert (tmp_path / "o" / "summary.csv").exists()


@pytest.mark.parametrize("section, expected", [
    ("robot: {v_max: 1.0e300}", "(robot.v_max: must be a finite number in [0.01, 10] m/s, got 1e+300)"),  # planned for ever
    ("robot: {v_max: -1}", "(robot.v_max: must be a finite number in [0.01, 10] m/s, got -1)"),  # ran, silently
    ("robot: {a_max: 0}", "(robot.a_max: must be a finite number in [0.01, 100] m/s^2, got 0)"),  # a tour of nan, warnings
    # positive but absurd: a robot that never left its first pose, exit 0
    ("robot: {a_max: 1.0e-300}", "(robot.a_max: must be a finite number in [0.01, 100] m/s^2, got 1e-300)"),
    ("robot: {v_max: 0.001}", "(robot.v_max: must be a finite number in [0.01, 10] m/s, got 0.001)"),
    ("robot: {w_max: 1.0e-9}", "(robot.w_max: must be a finite number in [0.01, 20] rad/s, got 1e-09)"),
    ("robot: {alpha_max: 0.005}", "(robot.alpha_max: must be a finite number in [0.01, 200] rad/s^2, got 0.005)"),
    ("robot: {v_max: [1, 2]}", "(robot.v_max: must be a finite number in [0.01, 10] m/s, got [1, 2])"),  # internal error
    ("robot: {pause_s: [5, 1]}", "(robot.pause_s: the shortest pause must not exceed the longest, got [5, 1])"),
    ("robot: {pause_s: [1, 2, 3]}", "(robot.pause_s: must be two numbers of seconds [shortest, longest], got (1, 2, 3))"),
    ("odometry: {alpha1: x}", "(odometry.alpha1: must be a finite number in [0, 10], got 'x')"),  # internal error (numpy)
    ("odometry: {alpha2: 1.0e300}", "(odometry.alpha2: must be a finite number in [0, 10], got 1e+300)"),  # ran, silently
    # a misplaced or unknown key: "'int' object is not iterable", "RobotLimits.__init__() got an unexpected keyword
    # argument 'bogus'"; at the top, the allowed keys but not where the key belongs
    ("robot: {pause_s: 5}", "(robot.pause_s: must be two numbers of seconds [shortest, longest], got 5)"),
    ("robot: {bogus: 1}", "(robot: unknown field(s) ['bogus']; robot: has v_max, a_max, w_max, alpha_max, radius, pause_s)"),
    ("odometry: {alpha5: 1}", "(odometry: unknown field(s) ['alpha5']; odometry: has alpha1, alpha2, alpha3, alpha4)"),
    ("sensor: {noise: 1}", "(sensor: unknown field(s) ['noise']; sensor: has n_beams, resolution, units, noise_sigma, "),
    ("pause_s: 5", "(unknown key(s) ['pause_s']; a simulate config has ['clutter', 'duration', 'odometry', 'rate_hz', "
                   "'robot', 'seed', 'sensor', 'world']; pause_s belongs under robot: (robot: {pause_s: ...}))"),
])
def test_simulate_config_robot_and_odometry_values_are_checked(section, expected, tmp_path, capsys):
    """`simulate --config` checked the run's and the sensor's values but not the robot's limits nor
    the odometry's noise: v_max 1e300 planned a tour for ever, -1 or a_max 0 ran a tour of no or nan
    motion, a list, a reversed pause range or text were internal errors. Now refused, one line."""
    (tmp_path / "run.yaml").write_text(f"world: office\nseed: 0\nduration: 1\n{section}\n")
    assert run_main(["simulate", "--config", str(tmp_path / "run.yaml"), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"lmsbench simulate: error: {tmp_path / 'run.yaml'}: not a simulate config {expected}")
    assert err[0].endswith(")")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("line, said", [
    ("duration: 5000", "duration: must be in [0.1, 3600] s, got 5000"),
    ("duration: 0.01", "duration: must be in [0.1, 3600] s (shorter holds no scan), got 0.01"),
    ("duration: .nan", "duration: must be in [0.1, 3600] s, got nan"),
    ("rate_hz: -1", "rate_hz: must be a finite number of scans/s > 0 (or None: every scan), got -1.0"),
])
def test_simulate_config_duration_and_rate_name_the_value_given(tmp_path, capsys, line, said):
    """`simulate --config` with `duration: 5000` said "duration must be in [0.1, 3600] s (shorter holds
    no scan) and rate_hz > 0": not the value given, and a rate that was fine. Now the field and its value."""
    (tmp_path / "run.yaml").write_text(f"world: office\n{line}\n")
    assert run_main(["simulate", "--config", str(tmp_path / "run.yaml"), "--out", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err == f"lmsbench simulate: error: {tmp_path / 'run.yaml'}: {said}\n"
    assert not (tmp_path / "o").exists()


def test_a_yaml_1_1_boolean_word_in_a_config_is_refused_naming_the_file_line_and_key(tmp_path, capsys):
    """`simulate --config` with `sensor: {interlaced: no}` ran a non-interlaced sensor, exit 0: PyYAML
    (YAML 1.1) reads no as False, where YAML 1.2 reads text. Refused before any work, one line."""
    (tmp_path / "run.yaml").write_text("world: office\nduration: 1\nsensor: {interlaced: no}\n")
    assert run_main(["simulate", "--config", str(tmp_path / "run.yaml"), "--out", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err == (
        f"lmsbench simulate: error: {tmp_path / 'run.yaml'}: not valid YAML (line 3, column 22: key 'interlaced': no is "
        "read as false (YAML 1.1), but as text by YAML 1.2; write true or false, or quote it ('no') for text)\n")
    assert not (tmp_path / "o").exists()


def test_simulate_checks_a_configs_world_against_out_as_it_does_world(tmp_path, capsys, monkeypatch):
    """`simulate` checked its inputs against --out twice: --world before the folder's own check, a
    --config's world.json after it, once the config was read. So `--config C.yaml --out W` (C.yaml:
    world: W/world.json) with a stray file in W said "holds notes.txt, which this command does not
    write", where `--world W/world.json --out W` said the run would write world.json over its input.
    One check now, after the config is read and before any output: the same message both ways."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "W").mkdir()
    (tmp_path / "W" / "world.json").write_text("{}")
    (tmp_path / "W" / "notes.txt").write_text("mine\n")
    (tmp_path / "c.yaml").write_text("world: W/world.json\nduration: 1\n")
    said = ("lmsbench simulate: error: --out W: the run would write world.json over W/world.json, which it reads; "
            "give another folder\n")
    assert run_main(["simulate", "--config", "c.yaml", "--out", "W"]) == 2
    assert capsys.readouterr().err == said
    assert run_main(["simulate", "--world", "W/world.json", "--duration", "1", "--out", "W"]) == 2
    assert capsys.readouterr().err == said
    assert sorted(p.name for p in (tmp_path / "W").iterdir()) == ["notes.txt", "world.json"]


def test_a_sweep_is_not_written_into_another_sweeps_folder(files, tmp_path, capsys):
    """`sweep B.yaml --out FOLDER_OF_A` replaced A's sweep.yaml, results.parquet and results.csv
    with B's, exit 0: A's table and record were gone (its cells stayed). Refused before any cell,
    nothing touched; A itself still resumes there."""
    out = tmp_path / "a"
    argv = ["sweep", files["sweep.yaml"], "--inprocess", "--no-progress", "--out", str(out)]
    assert run_main(argv, seconds=120) == 0
    other = tmp_path / "other.yaml"
    other.write_text(Path(files["sweep.yaml"]).read_text().replace("name: t", "name: other"))
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    capsys.readouterr()
    assert run_main(["sweep", str(other), "--inprocess", "--no-progress", "--out", str(out)]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench sweep: error: --out {out}: holds the sweep 't' (its sweep.yaml), not 'other': its results would be "
        "replaced; give another folder (a sweep resumes in a folder of its own name)"]
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    assert run_main(argv, seconds=120) == 0 and "1 cells, 0 computed, 1 already done" in capsys.readouterr().out


@pytest.mark.parametrize("argv, expected", [
    (["simulate", "--seed", "9" * 5000], "lmsbench simulate: error: argument --seed: must be a whole number >= 0 and <= "
     f"4294967295, got '{'9' * 40}...99999999' (5000 characters) (see lmsbench simulate --help)"),
    (["simulate", "--world", "w" * 5000, "--duration", "1"], f"lmsbench simulate: error: --world: unknown world "
     f"'{'w' * 40}...wwwwwwww' (5000 characters); known worlds: office, corridor, angles, pillars, random, cluttered, "
     "mit or a world.json"),
])
def test_a_long_value_is_shortened_in_the_error_line(argv, expected, tmp_path, capsys):
    """A 5000-digit --seed was echoed whole: an error line of 5 KB, the option's range printed as
    4.29497e+09 (2**32 - 1 rounded), the --world hint cut off by the 600-character clip."""
    assert run_main(argv + ["--out", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [expected]


def test_an_apostrophe_is_not_taken_for_the_quote_of_a_long_value():
    """shorten_quoted's pattern ran from the apostrophe of "don't" to the opening quote of the value:
    it cut the words between them ("a long explana...re, got ' (112 characters)") and left the
    100-digit value whole."""
    from experiments.options import shorten_quoted

    words = "don't give " + "a long explanation " * 5 + "here, the log's value: "
    assert shorten_quoted(f"--x: {words}'{'9' * 100}'; it isn't one") == (
        f"--x: {words}'{'9' * 40}...99999999' (100 characters); it isn't one")
    assert shorten_quoted(f"--x: '{'w' * 100}' (the log's)") == f"--x: '{'w' * 40}...wwwwwwww' (100 characters) (the log's)"
    assert shorten_quoted(words * 3) == words * 3  # apostrophes alone: nothing quoted, nothing cut


@pytest.mark.parametrize("command", [["compare", "{good.clf}"], ["sweep", "{sweep.yaml}"], ["simulate", "--duration", "1"],
                                     ["slam", "{simrun}"], ["figures", "--tables", "{tables_broken}"]])
@pytest.mark.parametrize("link", ["loop", "dangling", "loop/sub", "dangling/sub"])
def test_out_a_link_to_nothing_or_a_loop_is_refused_before_the_work(command, link, files, tmp_path, capsys):
    """`--out LINK` where LINK is a loop of links: compare, sweep and figures said "internal error:
    RuntimeError: Symlink loop" (Path.resolve); simulate and slam ran the whole work and then failed
    making the folder ("LINK: file exists"), as with a link to nothing; LINK/sub likewise (review)."""
    name = link.split("/")[0]
    bad = tmp_path / name
    bad.symlink_to(bad if name == "loop" else tmp_path / "nowhere")
    target = str(bad) if name == "loop" else str(tmp_path / "nowhere")
    out = tmp_path / link
    argv = [files.get(w[1:-1], w) if w.startswith("{") else w for w in command]
    assert run_main(argv + ["--out", str(out)]) == 2
    said = f"--out {out}: {bad}" if out != bad else f"--out {bad}"
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench {command[0]}: error: {said}: a symbolic link to {target}, which does not exist (or a loop of links)"]


@pytest.mark.parametrize("command", [["compare", "LOOP"], ["compare", "LOOP", "--out", "{out}"],
                                     ["simulate", "--config", "LOOP", "--out", "{out}"],
                                     ["calibrate", "LOOP", "--out", "{out}.yaml"], ["sweep", "LOOP", "--out", "{out}"]])
def test_an_input_that_is_a_loop_of_links_is_one_line_and_status_2(command, tmp_path, capsys):
    """`compare LOOP` and `simulate --config LOOP --out DIR` said "internal error: RuntimeError:
    Symlink loop from ..." (Path.resolve, in the checks of a source's path and of what --out would
    replace), exit 1."""
    loop = tmp_path / "loop"
    loop.symlink_to(tmp_path / "loop2")
    (tmp_path / "loop2").symlink_to(loop)
    argv = [str(loop) if w == "LOOP" else w.replace("{out}", str(tmp_path / "out")) for w in command]
    assert run_main(argv) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench {command[0]}: error: {loop}: a symbolic link to {tmp_path / 'loop2'}, which does not exist (or a loop of links)"]


@pytest.mark.slow
def test_a_sweeps_own_big_sweep_yaml_is_read_for_its_plots(tmp_path):
    """The 1 MiB bound is for files a user writes: the sweep.yaml a sweep of many cells writes,
    one grid value a line, is larger (1.1 MB here: 50,000 values of 17 digits; the most cells,
    MAX_CELLS, write more) and `figures --sweep DIR` still reads it. (Half the lines of 100,000
    short values, for the same size: the YAML parser's time goes by the line, 14 s for those.)"""
    from experiments.options import read_sweep_results
    from experiments.sweep.runner import spec_record
    from experiments.sweep.spec import SweepSpec
    from lms200.yamlio import MAX_YAML_BYTES

    spec = SweepSpec.from_dict({"name": "t", "kind": "extract", "grid": {"extractor.ad_tau": [1.0 + i * 1.2345678901234e-6
                                                                                             for i in range(50_000)]}})
    (tmp_path / "sweep.yaml").write_text(spec_record(spec))
    assert (tmp_path / "sweep.yaml").stat().st_size > MAX_YAML_BYTES
    n = len(spec.cells())  # a finished sweep's table: one row a cell (fewer is a sweep that did not finish)
    pd.DataFrame({"extractor.ad_tau": spec.grid["extractor.ad_tau"], "status": ["ok"] * n, "error": [""] * n,
                  "cell": [str(i) for i in range(n)], "seed": [0] * n}).to_parquet(tmp_path / "results.parquet")
    assert read_sweep_results(tmp_path)[0] == tmp_path


@pytest.mark.parametrize("with_out", [True, False])
@pytest.mark.parametrize("log, said", [
    ("groundtruth.tum", "groundtruth.tum: not a CARMEN log"),
    # the wrong-input hunt: a log of only +inf readings passed the first-scan check, and the study's
    # refusal left the run folder (or --out) behind, empty
    ("no_returns.clf", "no_returns.clf: none of its 5 scans has a valid beam (all +inf, nan or 0): no scan to draw"),
])
def test_demo_refuses_a_log_that_does_not_read_before_it_makes_its_folder(with_out, log, said, tmp_path, monkeypatch,
                                                                         capsys):
    """`demo --log run/groundtruth.tum` (a file, not a log) made results/demo/DATE_TIME and moved
    results/demo/latest to it, empty, before the study refused the file (or left --out X behind,
    empty): the earlier good report was no longer "latest". The log is read first, up to a scan
    with a valid beam."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "groundtruth.tum").write_text("0.0 0 0 0 0 0 0 1\n0.1 0.1 0 0 0 0 0 1\n")
    write_log(tmp_path / "no_returns.clf", [Record(Scan.lms200(np.full(361, np.inf), stamp=0.1 * k)) for k in range(5)])
    out = ["--out", str(tmp_path / "x")] if with_out else []
    assert run_main(["demo", "--log", log, "--no-sweep", "--duration", "1", *out]) == 2
    captured = capsys.readouterr()
    (line,) = captured.err.strip().splitlines()
    assert said in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["groundtruth.tum", "no_returns.clf"]  # no results/, no x/


def test_a_geometry_the_flags_give_that_fits_no_line_does_not_offer_to_skip_every_line(tmp_path, capsys):
    """--laser-fov-deg 90 --laser-resolution-deg 1 on 361-beam FLASER lines misfits every line:
    the error said so, then offered --skip-bad-lines, which would skip the whole log. The offer
    stays for a geometry the log itself declares (a line of another count is skippable)."""
    log = tmp_path / "flaser.clf"
    line = "FLASER 361 " + " ".join(["2.00"] * 361) + " 0 0 0 0 0 0 {t} host {t}\n"
    log.write_text("".join(line.format(t=1.0 + k) for k in range(3)))
    assert run_main(["info", str(log), "--laser-fov-deg", "90", "--laser-resolution-deg", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "361 beams do not fit a field of view of 90.000 deg at 1.0000 deg" in err
    assert "--skip-bad-lines" not in err
    assert run_main(["info", str(log)]) == 0  # the convention's 180 deg at 0.5 deg
    capsys.readouterr()


def test_yaml_files_not_utf8_past_the_head_are_one_line(tmp_path, capsys):
    """Fuzzing of 2026-12-06: the UTF-8 check read a YAML file's first 4 KB, and took a bad byte in
    the last 4 bytes of a shorter file for a character cut at the end of that block: `simulate
    --config`, `slam --config` and `figures --sweep` then failed in read_text, "internal error:
    UnicodeDecodeError", exit 1 (a sweep file and a bag's metadata.yaml the same past 4 KB)."""
    late = b"# " + b"x" * 5000 + b"\n# \xff\n"  # byte 5005
    (tmp_path / "short.yaml").write_bytes(b"world: office # \xff\n")  # byte 16 of 18
    (tmp_path / "late.yaml").write_bytes(b"world: office\n" + late)
    (tmp_path / "sweep.yaml").write_bytes(b"name: t\nkind: extract\ngrid: {extractor.k: [3, 5]}\n" + late)
    swept = tmp_path / "swept"
    swept.mkdir()
    (swept / "sweep.yaml").write_bytes(b"name: t\nkind: extract\ngrid: {extractor.k: [3]}\n" + late)
    pd.DataFrame({"extractor.k": [3], "seed": [0], "f1": [1.0], "status": ["ok"], "cell": ["a"]}).to_parquet(
        swept / "results.parquet")
    bag = tmp_path / "bag"
    bag.mkdir()
    (bag / "metadata.yaml").write_bytes(b"rosbag2_bagfile_information: {}\n" + late)
    out = str(tmp_path / "out")
    cases = [(["simulate", "--config", str(tmp_path / "short.yaml"), "--out", out], "short.yaml", 16, "a simulate config.yaml"),
             (["simulate", "--config", str(tmp_path / "late.yaml"), "--out", out], "late.yaml", 5019, "a simulate config.yaml"),
             (["sweep", str(tmp_path / "sweep.yaml"), "--inprocess", "--out", out], "sweep.yaml", 5055, "a sweep file"),
             (["figures", "--sweep", str(swept), "--out", out], "swept/sweep.yaml", 5052,
              "the sweep.yaml `lmsbench sweep` writes beside its results"),
             (["info", str(bag)], "bag/metadata.yaml", 5037, "a ROS 2 bag's metadata.yaml")]
    for argv, name, byte, what in cases:
        assert main(argv) == 2, argv
        assert capsys.readouterr().err == (f"lmsbench {argv[0]}: error: {tmp_path / name}: not text (byte {byte} is not "
                                           f"UTF-8), not {what}\n"), argv
    assert not Path(out).exists()


def test_the_clutter_options_bound_is_the_simulators():
    """simulate --clutter's argparse bound is sim.worlds.MAX_CLUTTER (kept apart: sim loads pybullet)."""
    from experiments.commands.simulate import CLUTTER_MAX
    from sim.worlds import MAX_CLUTTER

    assert CLUTTER_MAX == MAX_CLUTTER


def test_huge_whole_number_beyond_a_stated_range_says_the_range_once():
    """``simulate --seed <400 nines>`` said the range and then "(too large for a float)": the range
    already says why. An option with no upper bound of its own (``--max-scans``) says int64's, the
    library's: it said "(too large for a float)" of a count."""
    import argparse

    from experiments.options import count, number

    seed = number(0, 2**32 - 1, integer=True)
    with pytest.raises(argparse.ArgumentTypeError) as info:
        seed("9" * 400)
    assert str(info.value) == f"must be a whole number >= 0 and <= 4294967295, got '{'9' * 400}'"  # shortened by the CLI
    with pytest.raises(argparse.ArgumentTypeError) as info:
        count(1)("9" * 400)
    assert str(info.value) == f"must be a whole number >= 1 and at most 2^63 - 1, got '{'9' * 400}'"


def test_a_log_whose_name_is_not_utf8_is_named_by_its_escapes(files, tmp_path, capsys):
    """A log named b<0xff>.clf (os.fsdecode: a lone surrogate): compare's table (pyarrow) and slam's
    figure title (matplotlib) cannot hold its name, and both ended in an internal error after the
    work; sim2real's report.md too. The name is written with its escapes, as stderr shows it."""
    from experiments.demo import demo_command
    from experiments.figures.study import StudyConfig
    from experiments.provenance import read_parquet, write_record

    log = tmp_path / os.fsdecode(b"b\xff.clf")
    shutil.copyfile(files["good.clf"], log)
    out = tmp_path / os.fsdecode(b"c\xfe")  # its Parquet table through a handle; its path on stdout
    assert run_main(["compare", str(log), "--methods", "split_merge", "--max-scans", "20", "--out", str(out)]) == 0
    assert set(read_parquet(out / "compare.parquet")["source"]) == {"b\\udcff.clf"}
    assert run_main(["info", str(log)]) == 0  # the name on stdout, which capsys keeps strict (as en_US.UTF-8)
    said = capsys.readouterr()
    assert "b\\udcff.clf" in said.out and "internal error" not in said.err
    # the demo report's Reproduce line names the file again in the shell's ANSI-C quotes
    assert demo_command(StudyConfig(intel_log=str(log)), "") == f"lmsbench demo --log $'{tmp_path}/b\\xff.clf' --no-sweep"
    assert run_main(["slam", str(log), "--max-scans", "5", "--no-paper-baseline", "--out", str(tmp_path / "s")]) == 0
    assert "internal error" not in capsys.readouterr().err
    write_record(tmp_path / "r.md", f"# sim2real: {log.name}\n")
    assert (tmp_path / "r.md").read_text(encoding="utf-8") == "# sim2real: b\\udcff.clf\n"
