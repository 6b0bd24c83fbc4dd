"""`lmsbench slam` end to end on a short simulated run, and SLAM on the simulator's scans."""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from lms200 import InputError, LmsbenchError, read_tum, write_log, write_tum
from sim_folder import write_sim_folder



@pytest.fixture(scope="module")
def sim_folder(tmp_path_factory) -> Path:
    """A 6 s office run written the way `lmsbench simulate` lays out its folder."""
    from sim import simulate_records

    return write_sim_folder(tmp_path_factory.mktemp("sim"), simulate_records("office", seed=1, duration=6.0), 1)


def test_slam_command_writes_every_output(sim_folder, tmp_path, capsys):
    # in process: a subprocess would compile every numba kernel again on a fresh clone (about two
    # minutes); the command line itself (entry point, exit codes) is covered by test_cli_bad_input
    from experiments.cli import main

    out = tmp_path / "run"
    assert main(["slam", str(sim_folder), "--out", str(out), "--quiet"]) == 0
    captured = capsys.readouterr()
    stdout = captured.out
    assert "warning" not in captured.err  # healthy (asserted below): no warning
    for name in ("trajectory.tum", "keyframes.tum", "map.json", "metrics.json", "config.yaml", "slam.png"):
        assert (out / name).is_file(), name
    assert "loop closures over" in stdout and "default preset" in stdout
    stamps, poses = read_tum(out / "trajectory.tum")
    # the scores of this run and its baseline are printed, as in metrics.json (only the published
    # relations errors of MIT CSAIL were, and none of the run's own)
    rows = json.loads((out / "metrics.json").read_text())["table"]
    assert (f"  ATE RMS (m): this run {rows[0]['ate_rmse']:.3g}, paper preset {rows[1]['ate_rmse']:.3g}"
            in stdout.splitlines())
    true_stamps, _ = read_tum(sim_folder / "groundtruth.tum")
    np.testing.assert_allclose(stamps, true_stamps, atol=1e-6)  # one pose per scan, the input's stamps
    m = json.loads((out / "metrics.json").read_text())
    assert m["n_scans"] == stamps.size and m["preset"] == "default"
    assert m["loop_closures"]["n_keyframes"] >= 2 and m["loop_closures"]["n"] == len(m["loop_closures"]["closed"])
    assert [row["source"] for row in m["table"]][:2] == ["slam", "paper preset"]
    assert m["ate"]["rmse"] < 0.1  # a short run in the simulated office stays on track
    assert not m["consistency"]["diverged"] and m["consistency"]["healthy"]
    lines = json.loads((out / "map.json").read_text())["lines"]
    assert len(lines) == m["landmarks"]["lines"] > 3
    assert m["map"]["distance_mean"] < 0.1
    # the same folder again with the paper preset, which writes no keyframes: the folder is that run's alone
    assert main(["slam", str(sim_folder), "--out", str(out), "--quiet", "--preset", "paper"]) == 0
    assert json.loads((out / "metrics.json").read_text())["preset"] == "paper"
    assert not (out / "keyframes.tum").exists()


def test_slam_skips_the_fewest_scans_out_of_time_order(sim_folder, tmp_path, capsys):
    """A log whose stamps go backwards (Intel's corrected log: 4 of 910 scans, by 0.05-0.86 s) is
    refused in one line that names the way out; with --skip-bad-lines the fewest scans that leave
    the rest in time order are skipped, each named: a stamp that jumps 1000 s ahead costs that one
    scan, not every scan after it, and the run stays on track."""
    import dataclasses
    import shutil

    from experiments.cli import main
    from experiments.commands.slam import in_time_order
    from lms200 import read_log

    records = list(read_log(sim_folder / "scans.clf"))
    jump = 10
    records[jump] = dataclasses.replace(records[jump], scan=records[jump].scan.replace(stamp=records[jump].scan.stamp + 1000.0))
    folder = tmp_path / "jumpy"
    folder.mkdir()
    write_log(folder / "scans.clf", records)
    for name in ("groundtruth.tum", "world.json"):
        shutil.copy(sim_folder / name, folder / name)
    assert main(["slam", str(folder), "--out", str(tmp_path / "refused"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"time goes backwards at scan {jump + 1}" in err[0] and "--skip-bad-lines" in err[0]
    out = tmp_path / "run"
    assert main(["slam", str(folder), "--out", str(out), "--quiet", "--skip-bad-lines"]) == 0
    err = capsys.readouterr().err
    assert f"skipped scan {jump} " in err and err.count("skipped scan") == 1
    stamps, _ = read_tum(out / "trajectory.tum")
    assert stamps.size == len(records) - 1
    assert json.loads((out / "metrics.json").read_text())["ate"]["rmse"] < 0.1
    # the same log read alone: its truth is its TRUEPOS lines, a pose per scan, skipped with the scan
    assert main(["slam", str(folder / "scans.clf"), "--out", str(tmp_path / "alone"), "--quiet", "--skip-bad-lines"]) == 0
    assert json.loads((tmp_path / "alone" / "metrics.json").read_text())["ate"]["rmse"] < 0.1
    capsys.readouterr()
    assert in_time_order([938.408, 940.654, 940.54, 954.436]) in ([0, 1, 3], [0, 2, 3])  # Intel's scans 293-296
    assert in_time_order([3.0, 2.0, 1.0]) == [2] and in_time_order([]) == []


def test_slam_refuses_scans_kept_of_one_stamp_before_any_work(sim_folder, tmp_path, capsys, monkeypatch):
    """A review: `slam ev.clf --every 2` on 10 scans stamped [0]*9 + [1] kept 5 of one stamp, ran the
    SLAM, then failed with "records: all 5 scans read have the same stamp" (run_slam's parameter, and 5
    read where 10 were). Now refused before any SLAM work, naming the log and the option."""
    import dataclasses

    import slam.run
    from experiments.cli import main
    from lms200 import read_log

    records = list(read_log(sim_folder / "scans.clf"))[:10]
    stamped = [dataclasses.replace(r, scan=r.scan.replace(stamp=0.0 if k < 9 else 1.0)) for k, r in enumerate(records)]
    write_log(tmp_path / "ev.clf", stamped)
    ran: list[object] = []
    monkeypatch.setattr(slam.run, "_run_steps", lambda *args: ran.append(args))  # the paper preset's SLAM work
    monkeypatch.setattr("slam.scanslam.run_scan_slam", lambda *args: ran.append(args))
    odd = [dataclasses.replace(r, scan=r.scan.replace(stamp=1.0 if k == 1 else 0.0)) for k, r in enumerate(records)]
    write_log(tmp_path / "odd.clf", odd)  # read to its 7th scan: scan 1 stamped 1 s, the 4 kept (0, 2, 4, 6) 0 s
    for name, extra, said in (("ev.clf", ["--every", "2"], "--every 2 keeps 5 of the 10"),
                              ("odd.clf", ["--every", "2", "--max-scans", "4"], "--every 2 and --max-scans 4 keeps 4 of the 7")):
        assert main(["slam", str(tmp_path / name), "--out", str(tmp_path / "o"), "--quiet", *extra]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert err == [f"lmsbench slam: error: {tmp_path / name}: {said} scans read, all stamped 0.000000 s; SLAM's "
                       "motion model needs the time between scans"]
        assert ran == []


def test_slam_refuses_a_log_of_one_stamp_and_warns_of_steps_without_time(sim_folder, tmp_path, capsys):
    """A log whose stamps are all equal ran (exit 0): every step predicted no motion and searched no
    turn. Now refused in one line naming the file, with --rate-hz too (which kept one scan of it).
    A log where only some steps take no time (a coarse clock: pairs of scans per stamp) still runs,
    and says how many steps on stderr."""
    import dataclasses

    from experiments.cli import main
    from lms200 import read_log

    records = list(read_log(sim_folder / "scans.clf"))[:20]
    flat = [dataclasses.replace(r, scan=r.scan.replace(stamp=7.0)) for r in records]
    write_log(tmp_path / "flat.clf", flat)
    for extra in ([], ["--rate-hz", "5"]):
        assert main(["slam", str(tmp_path / "flat.clf"), "--out", str(tmp_path / "o"), "--quiet", *extra]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert err == [f"lmsbench slam: error: {tmp_path / 'flat.clf'}: all 20 scans read have the same stamp "
                       "(7.000000 s); SLAM's motion model needs the time between scans (a log written without a clock?)"]
        assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())
    paired = [dataclasses.replace(r, scan=r.scan.replace(stamp=records[k - k % 2].scan.stamp))
              for k, r in enumerate(records)]
    write_log(tmp_path / "paired.clf", paired)
    assert main(["slam", str(tmp_path / "paired.clf"), "--out", str(tmp_path / "p"), "--quiet"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert [line for line in err if "take no time" in line] == [
        f"lmsbench slam: warning: {tmp_path / 'paired.clf'}: 10 of 19 steps take no time (scan 1 has the stamp of the "
        f"scan kept before it, scan 0's {records[0].scan.stamp:.6f} s): the motion model predicts no motion and the search no turn "
        "over them"]
    assert read_tum(tmp_path / "p" / "trajectory.tum")[0].size == 20


@pytest.mark.parametrize("damage, message", [
    # no log holds such a stamp now (0 .. 2^32 s, lms200.records.MAX_STAMP_S: write_log refuses it, and the reader,
    # tests/test_log_plausible_values.py); run_slam still refuses it its own way
    ("gap", "records: item 10: stamp 1e+200 s is outside 0 .. 2^32 s (4294967296 s, 2106-02-07), the stamps every log "
            "reader and writer takes: a clock's UNIX time, or seconds since the run's start; the CARMEN reader refuses it "
            "(the log could not be read back)"),
    # nor such a pose: the CARMEN reader refuses it, as the TUM reader does (lms200.carmen.MAX_COORD_M), and so does
    # write_log (tests/test_carmen_pose_bounds.py, with the reader's refusal on the command line)
    ("odom", "records: item 10: odom pose (1e+300, -3) m lies beyond +-1e+09 m (damaged, or not metres?), which the CARMEN reader refuses "
             "(the log could not be read back)"),
])
def test_slam_refuses_stamps_and_poses_its_models_overflow_on(sim_folder, tmp_path, damage, message):
    """A log whose stamps jump by 1e200 s (or whose odometry reads 1e300 m: the default run's odometry
    baseline) was 'internal error: OverflowError: (34, 'Numerical result out of range')', exit 1, after
    the run had started; a 1e9 s gap still runs. No log holds either now (write_log and the reader refuse
    both); run_slam refuses such records its own way."""
    import dataclasses

    from lms200 import read_log
    from slam import SlamConfig, run_slam
    from slam.run import SlamInputError

    records = list(read_log(sim_folder / "scans.clf"))[:20]
    if damage == "gap":  # Scan refuses such a stamp now: set in place past its check, as a Scan changed after it was made
        bad = [dataclasses.replace(r, scan=r.scan.replace()) for r in records]
        for r in bad[10:]:
            object.__setattr__(r.scan, "stamp", r.scan.stamp + 1e200)
    else:
        bad = [dataclasses.replace(r, odom=(1e300, -3.0, 0.0)) if k >= 10 else dataclasses.replace(r, odom=(0.0, 0.0, 0.0))
               for k, r in enumerate(records)]
    with pytest.raises(InputError) as err:
        write_log(tmp_path / "bad.clf", bad)
    assert str(err.value) == message
    with pytest.raises(SlamInputError, match=r"^records\[10\]: "):
        run_slam(bad, SlamConfig(preset="paper", motion=dataclasses.replace(SlamConfig().motion, use_odometry=True)))
    gap = [dataclasses.replace(r, scan=r.scan.replace(stamp=r.scan.stamp + (1e9 if k >= 10 else 0.0)))
           for k, r in enumerate(records)]
    assert run_slam(gap).trajectory.shape == (20, 4)


@pytest.mark.parametrize("wall", ["[0, 0, NaN, 1]", "[0, 0, 1e308, 1e308]"])
def test_slam_refuses_a_world_json_wall_simulate_and_compare_refuse_before_the_run(sim_folder, tmp_path, capsys, wall):
    """A simulate folder's world.json with a NaN wall was map_error's error after the whole run (its
    config.yaml, trajectory, keyframes and map written, no metrics.json), and a wall at 1e308 m ran,
    exit 0, with matplotlib's overflow RuntimeWarning on stderr and a nonsense map error; simulate and
    compare refuse both (World.from_json). Refused before any output, one line."""
    import shutil

    from experiments.cli import main

    run = tmp_path / "run"
    shutil.copytree(sim_folder, run)
    (run / "world.json").write_text('{"walls": [' + wall + '], "circles": [], "corners": []}')
    assert main(["slam", str(run), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench slam: error: {run / 'world.json'}: not a world.json (walls: must be finite numbers within +-1e+06 m)"]
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("name, content, message", [
    ("groundtruth.tum", None, "{f} is a folder, not a TUM file"),
    ("world.json", None, "{f} is a folder, not a world.json"),
    ("world.json", "[1, 2]", "{f}: not a world.json (the top level is a list, not a mapping of walls, boxes, ...)"),
    ("world.json", "null", "{f}: not a world.json (the top level is a NoneType, not a mapping of walls, boxes, ...)"),
    # a key given twice or misspelt (found by fuzzing): the walls left out of the map's score, silently
    ("world.json", '{"walls": [[0, 0, 1, 0]], "walls": []}',
     "{f}: not a world.json (key 'walls' given twice (the last would be taken, silently))"),
    ("world.json", '{"walls": [[0, 0, 1, 0]], "circle": []}',
     "{f}: not a world.json (unknown key(s) ['circle'] ('circle' for 'circles'?): a world.json has name, seed, "
     "scan_height, walls, circles, corners, boxes, cylinders, route_nodes, route_edges, route_targets, glass)"),
    ("world.json", '{"walls": {"a": 1}}', "{f}: not a world.json (walls: must be a list of walls (a wall must be a "
     "list of 4 numbers x1, y1, x2, y2 (m)), got {{'a': 1}})"),
])
def test_a_simulate_folder_whose_truth_or_world_is_a_folder_or_no_mapping_is_refused(sim_folder, tmp_path, capsys,
                                                                                    name, content, message):
    """The wrong-input hunt: a groundtruth.tum or world.json that is a folder was passed over (is_file()),
    so slam ran without the truth's or the map's scores, exit 0, and said nothing; a world.json
    holding a JSON list, null or a mapping of walls was 'internal error: TypeError', exit 1."""
    import shutil

    from experiments.cli import main

    run = tmp_path / "run"
    shutil.copytree(sim_folder, run)
    (run / name).unlink()
    if content is None:
        (run / name).mkdir()
    else:
        (run / name).write_text(content)
    assert main(["slam", str(run), "--out", str(tmp_path / "o"), "--quiet", "--max-scans", "5"]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [f"lmsbench slam: error: {message.format(f=run / name)}"]
    assert not (tmp_path / "o").exists()


def test_a_ground_truth_beside_none_of_the_scans_is_refused_before_the_run(sim_folder, tmp_path, capsys):
    """The wrong-input hunt: a simulate folder whose groundtruth.tum was another run's, or shifted by
    100 s, ran the whole SLAM, wrote config.yaml, the trajectory, keyframes and map, then failed with
    "ate: fewer than 2 estimated poses fall inside the ground truth's time span" (no file named, no
    metrics.json). Now refused before any output, naming the file and both time spans."""
    import shutil

    from experiments.cli import main

    run = tmp_path / "run"
    shutil.copytree(sim_folder, run)
    stamps, poses = read_tum(sim_folder / "groundtruth.tum")
    write_tum(run / "groundtruth.tum", stamps + 100.0, poses)
    assert main(["slam", str(run), "--out", str(tmp_path / "o"), "--quiet", "--max-scans", "5"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and re.fullmatch(
        rf"lmsbench slam: error: {re.escape(str(run / 'groundtruth.tum'))}: its stamps \(100\.000000 to 10[0-9.]+ s\) "
        r"cover 0 of the 5 scans to run on \(0\.000000 to [0-9.]+ s\); scoring against it needs two or more "
        r"\(the ground truth of another run, or stamps of another clock\?\)", err[0]), err
    assert not (tmp_path / "o").exists()


def test_relations_beside_none_of_the_scans_are_refused_before_the_run(sim_folder, tmp_path, capsys):
    """Another log's relations (MIT CSAIL's given with the Intel log) ran the whole SLAM, warned "the
    relations error covers 0 of the file's 1172 relations" and wrote metrics.json with no relations
    score, exit 0. Refused before any output, naming the file and both time spans; relations over part
    of the scans, or past a --max-scans cut, still run (the run's own warning says how many it scored)."""
    from experiments.cli import main
    from experiments.slamrun import load_input

    def relations(name: str, *pairs: tuple[float, float]) -> Path:
        path = tmp_path / name
        path.write_text("".join(f"{a} {b} 0.1 0 0 0 0 0.01\n" for a, b in pairs))
        return path

    other = relations("other.relations", (100.0, 100.5), (101.0, 102.0))
    assert main(["slam", str(sim_folder), "--relations", str(other), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and re.fullmatch(
        rf"lmsbench slam: error: {re.escape(str(other))}: none of its 2 relations lies within the scans' time span: "
        r"the relations span 100\.000000 to 102\.000000 s, the log's 22[0-9] scans to run on 0\.000000 to 5\.9[0-9]+ s; "
        r"the relations error would score nothing \(the relations of another log, or stamps of another clock\?\)", err[0]), err
    assert not (tmp_path / "o").exists()
    # one pair inside, or past the cut of --max-scans: read (the run's warning says what it scores)
    assert load_input(sim_folder, relations("part.relations", (1.0, 1.5), (100.0, 101.0))).relations.shape == (2, 5)
    assert load_input(sim_folder, relations("later.relations", (4.0, 4.5)), max_scans=5).relations.shape == (1, 5)
    # past the cut and past the whole log's end (its last stamp, found from the log's tail): refused as without the
    # cut (they passed, the whole SLAM run on the cut, exit 0, when they lay after it)
    with pytest.raises(LmsbenchError, match=r"relations span 100\.000000 to 102\.000000 s, the whole log's scans "
                                            r"0\.000000 to 5\.9[0-9]+ s \(5 of them read, --max-scans\)"):
        load_input(sim_folder, other, max_scans=5)
    from lms200 import Record, Scan

    log = tmp_path / "late.clf"  # scans from 10 s on
    write_log(log, [Record(Scan.lms200(np.full(361, 2.0 + 0.01 * k), stamp=10.0 + 0.1 * k)) for k in range(8)])
    with pytest.raises(LmsbenchError, match=r"relations span 1\.000000 to 2\.000000 s, the 5 scans read \(at most 5, "
                                            r"--max-scans\) 10\.000000 to 10\.400000 s"):  # before the scans: not the log's
        load_input(log, relations("before.relations", (1.0, 2.0)), max_scans=5)
    packed = tmp_path / "late.clf.gz"  # the same log gzipped: its end from one decompressing pass
    write_log(packed, [Record(Scan.lms200(np.full(361, 2.0 + 0.01 * k), stamp=10.0 + 0.1 * k)) for k in range(8)])
    assert load_input(packed, relations("tail.relations", (10.5, 10.7)), max_scans=5).relations.shape == (1, 5)
    with pytest.raises(LmsbenchError, match=r"the whole log's scans 10\.000000 to 10\.700000 s \(5 of them read"):
        load_input(packed, relations("after.relations", (10.75, 11.0)), max_scans=5)
    # found beside the log, not given: a stale file is left out with a note (no option could leave it out)
    relations("late.relations", (1.0, 2.0))
    found = load_input(log)
    assert found.relations is None and "relations" not in found.sources
    assert any("late.relations: none of its 1 relations" in n and "found beside the log, not given" in n
               for n in found.notes), found.notes


@pytest.mark.parametrize("content, held", [("", "an empty file (0 bytes)"),
                                           ("# timestamp x y z qx qy qz qw\n\n", "holds only blank or comment lines (2)")])
def test_a_ground_truth_of_no_poses_is_refused_before_the_run(sim_folder, tmp_path, capsys, content, held):
    """An emptied or cut groundtruth.tum (no row) was "internal error: IndexError: index 0 is out of
    bounds for axis 0 with size 0", exit 1 (the span check read its first row); read_tum refuses it."""
    import shutil

    from experiments.cli import main

    run = tmp_path / "run"
    shutil.copytree(sim_folder, run)
    (run / "groundtruth.tum").write_text(content)
    assert main(["slam", str(run), "--out", str(tmp_path / "o"), "--quiet", "--max-scans", "5"]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench slam: error: {run / 'groundtruth.tum'}: no poses: {held}; a TUM file holds a row t x y z qx qy qz qw "
        "per pose (a cut or emptied file?)"]
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("content", ["{}", '{"walls": []}', '{"walls": [], "circles": []}', '{"boxes": []}'])
@pytest.mark.parametrize("command", ["slam", "compare", "simulate"])
def test_a_world_json_of_nothing_is_refused(sim_folder, tmp_path, capsys, content, command):
    """A world.json with no wall, circle or box: compare scored every extractor against no face (F1 0,
    exit 0), slam scored its map against no wall (wall_coverage 0, exit 0)."""
    import shutil

    from experiments.cli import main

    run = tmp_path / "run"
    shutil.copytree(sim_folder, run)
    world = run / "world.json"
    world.write_text(content)
    argv = {"slam": ["slam", str(run), "--max-scans", "5"], "compare": ["compare", str(run), "--max-scans", "2",
                                                                         "--methods", "sensor"],
            "simulate": ["simulate", "--world", str(world), "--duration", "0.2"]}[command]
    assert main([*argv, "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"lmsbench {command}: error: {world}: not a world.json: it holds no walls, circles or boxes, "
                   "nothing to scan or score against"], err
    assert not (tmp_path / "o").exists()


def test_slam_command_errors_are_one_line(tmp_path, capsys):
    from experiments.cli import main  # in process: the subprocess test above covers the real command line

    assert main(["slam", str(tmp_path / "nothing"), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "no such input" in err and len(err.strip().splitlines()) == 1
    (tmp_path / "empty").mkdir()
    assert main(["slam", str(tmp_path / "empty"), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "scans.clf" in err and len(err.strip().splitlines()) == 1


def test_slam_config_files_name_a_bad_extractor_and_take_a_users_own(sim_folder, tmp_path, capsys, monkeypatch):
    """SlamConfig now checks its extractor when built: a config file's `extractor: nope` and
    `extractor_params` that --extractor's method lacks are one line naming the file; a file's
    MODULE:FUNCTION extractor is registered before the config is built, so it still runs."""
    from experiments.cli import main
    from features.registry import _REGISTRY

    (tmp_path / "nope.yaml").write_text("extractor: nope\n")
    (tmp_path / "sigma.yaml").write_text("extractor_params: {sigma_r: 0.02}\n")
    out = str(tmp_path / "o")
    assert main(["slam", str(sim_folder), "--config", str(tmp_path / "nope.yaml"), "--out", out]) == 2
    err = capsys.readouterr().err.strip()
    assert err.endswith("nope.yaml: extractor: unknown extraction method 'nope'; registered methods "
                        "(features.registry): sensor, split_merge, iepf, hough, ransac") and len(err.splitlines()) == 1
    assert main(["slam", str(sim_folder), "--config", str(tmp_path / "sigma.yaml"), "--extractor", "hough", "--out", out]) == 2
    err = capsys.readouterr().err.strip()
    assert "sigma.yaml: extractor_params: unknown parameter(s) ['sigma_r'] for method 'hough'" in err and len(err.splitlines()) == 1
    (tmp_path / "slam_user_ext.py").write_text("from features import extract\n\n\ndef lines(scan):\n"
                                               "    return extract(scan, 'split_merge')\n")
    (tmp_path / "user.yaml").write_text("extractor: slam_user_ext:lines\n")
    monkeypatch.chdir(tmp_path)
    try:
        assert main(["slam", str(sim_folder), "--config", "user.yaml", "--out", out, "--quiet", "--no-paper-baseline",
                     "--max-scans", "10"]) == 0
    finally:
        _REGISTRY.pop("slam_user_ext:lines", None)
    assert "extractor: slam_user_ext:lines" in (tmp_path / "o" / "config.yaml").read_text()


def test_odometry_on_an_input_without_any_is_refused(sim_folder, tmp_path, capsys):
    """--odometry drives either preset now; an input without odometry is refused before any work,
    in one line, and leaves no folder behind."""
    from experiments.cli import main

    for preset in ("default", "paper"):
        assert main(["slam", str(sim_folder), "--out", str(tmp_path / "o"), "--odometry", "--preset", preset,
                     "--quiet"]) == 2
        err = capsys.readouterr().err.strip()
        assert err.endswith("--odometry needs odometry on every scan, and this input has none") and len(err.splitlines()) == 1
        assert not (tmp_path / "o").exists()


def test_odometry_options_that_would_set_nothing_are_refused(tmp_path, capsys):
    """With --odometry there is no separate odometry baseline: --no-odometry-baseline set nothing,
    and --association / --corners with --no-paper-baseline set a filter nothing ran (exit 0, rows
    without it). A log with odometry on some scans only was told it had none; a config's
    use_odometry was called --odometry. Each is one line, exit 2, before any work."""
    from dataclasses import replace

    from experiments.cli import main
    from sim import simulate_records
    from sim.records import OdometryConfig

    records = simulate_records("office", seed=1, duration=4.0, rate_hz=3.0, odometry=OdometryConfig())
    write_log(tmp_path / "odo.clf", records)
    write_log(tmp_path / "partial.clf", [r if k % 3 else replace(r, odom=None) for k, r in enumerate(records)])
    (tmp_path / "odo.yaml").write_text("motion: {use_odometry: true}\n")
    out = str(tmp_path / "o")
    cases = [
        (["--odometry", "--no-odometry-baseline"], "--no-odometry-baseline: this run uses the odometry itself"),
        (["--odometry", "--no-paper-baseline", "--association", "jcbb"],
         "--association set the paper preset's filter, which this run does not use (the default pipeline, with "
         "--no-paper-baseline and --odometry, which has no separate odometry baseline)"),
    ]
    for extra, message in cases:
        assert main(["slam", str(tmp_path / "odo.clf"), "--out", out, "--quiet", *extra]) == 2
        err = capsys.readouterr().err.strip()
        assert message in err and len(err.splitlines()) == 1, err
    n, missing = len(records), sum(1 for k in range(len(records)) if k % 3 == 0)
    assert main(["slam", str(tmp_path / "partial.clf"), "--out", out, "--quiet", "--odometry"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.endswith(f"--odometry needs odometry on every scan, and {missing} of the {n} scans have none"), err
    assert main(["slam", str(tmp_path / "partial.clf"), "--out", out, "--quiet", "--config", str(tmp_path / "odo.yaml")]) == 2
    err = capsys.readouterr().err.strip()
    assert f"motion.use_odometry (in {tmp_path / 'odo.yaml'}) needs odometry on every scan" in err, err
    assert not (tmp_path / "o").exists()


def test_config_sections_no_run_of_the_command_reads_are_refused(sim_folder, tmp_path, capsys):
    """Round 7: `slam RUN --config C --preset paper` with C's `loop_closure: {every: 5}` (the default pipeline's)
    ran, exit 0, and wrote the unread setting into config.yaml as if it had run; so did the paper preset's
    sections where no paper preset ran. Refused before any work; an earlier run's config.yaml (every section at
    its defaults but what was set) is taken, and a section a baseline reads is taken."""
    from experiments.cli import main

    (tmp_path / "lc.yaml").write_text("loop_closure: {every: 5}\nkeyframes: {distance: 0.4}\n")
    (tmp_path / "pa.yaml").write_text("prealign: {radius: 5}\n")
    out = tmp_path / "o"
    for argv, said in [
        (["--config", str(tmp_path / "lc.yaml"), "--preset", "paper"],
         f"{tmp_path / 'lc.yaml'}: keyframes.distance, loop_closure.every set the default pipeline, which --preset paper "
         "does not run (its baselines are the paper preset's too): drop them, or run the default preset"),
        (["--config", str(tmp_path / "pa.yaml"), "--no-paper-baseline", "--no-odometry-baseline"],
         f"{tmp_path / 'pa.yaml'}: prealign.radius sets the paper preset's filter, which this run does not use"),
        # the review: an input without odometry runs no odometry baseline either (ran, exit 0)
        (["--config", str(tmp_path / "pa.yaml"), "--no-paper-baseline"],
         f"{tmp_path / 'pa.yaml'}: prealign.radius sets the paper preset's filter, which this run does not use (the "
         f"default pipeline, with --no-paper-baseline, on {sim_folder}, which has no odometry for an odometry baseline)"),
        (["--corners", "--no-paper-baseline"], "--corners set the paper preset's filter, which this run does not use"),
    ]:
        assert main(["slam", str(sim_folder), "--out", str(out), "--quiet", *argv]) == 2
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 1 and said in err[0], err
        assert not out.exists()
    from experiments.commands.slam import _config
    from experiments.cli import build_parser

    for argv in (["--config", str(tmp_path / "pa.yaml")], ["--config", str(tmp_path / "lc.yaml")]):  # read by a run
        args = build_parser().parse_args(["slam", str(sim_folder), "--out", str(out), *argv])
        assert _config(args).preset == "default"


def test_odometry_drives_the_default_pipeline_and_names_its_rows(tmp_path, capsys):
    """``lmsbench slam --odometry`` with the default preset: config.yaml says so, the summary
    table's rows are "slam (odometry)" and the paper preset with the same motion input, and the
    run is scored (a sparse simulated run with wheel odometry, 2 s between scans)."""

    import yaml

    from experiments.cli import main
    from sim import simulate_records
    from sim.records import OdometryConfig

    records = simulate_records("office", seed=1, duration=40.0, rate_hz=0.5, odometry=OdometryConfig())
    folder = write_sim_folder(tmp_path / "sim", records, 1)
    out = tmp_path / "o"
    assert main(["slam", str(folder), "--out", str(out), "--odometry", "--quiet"]) == 0
    assert yaml.safe_load((out / "config.yaml").read_text())["slam"]["motion"]["use_odometry"] is True
    metrics = json.loads((out / "metrics.json").read_text())
    assert [row["source"] for row in metrics["table"]] == ["slam (odometry)", "paper preset (odometry)", "raw odometry"]
    rows = {row["source"]: row for row in metrics["table"]}
    assert rows["slam (odometry)"]["ate_rmse"] < 0.5 * rows["raw odometry"]["ate_rmse"]


def test_odometry_without_a_reference_leaves_no_empty_row(tmp_path):
    """On a log with odometry and no reference (csail-robotlaser1.log.gz) metrics.json's table had
    a row ``{"source": "raw odometry"}`` of nothing: raw odometry has no score without a reference."""
    from lms200 import Record
    from sim import simulate_records
    from sim.records import OdometryConfig
    from slam import SlamConfig

    from experiments.slamrun import load_input, run

    records = simulate_records("office", seed=1, duration=3.0, odometry=OdometryConfig())
    log = tmp_path / "run.clf"
    write_log(log, [Record(r.scan, odom=r.odom) for r in records])  # no truth
    data = load_input(log, every=4)
    assert data.odometry is not None and data.truth is None
    result = run(data, SlamConfig(), progress=False, paper_baseline=False)
    table = result.metrics["table"]
    assert [row["source"] for row in table] == ["slam", "paper preset (odometry)"]
    assert all(set(row) == {"source", "cpu_scans_per_s", "seconds"} - ({"cpu_scans_per_s"} if "odometry" in row["source"]
                                                                       else set()) for row in table), table


def test_decimated_input_and_odometry_rows(sim_folder):
    from slam import SlamConfig

    from experiments.slamrun import load_input, run

    data = load_input(sim_folder, every=3)
    assert len(data.records) == 75 and data.odometry is None
    result = run(data, SlamConfig(), progress=False)
    assert [row["source"] for row in result.metrics["table"]] == ["slam", "paper preset"]
    assert result.metrics["ate"]["rmse"] < 0.15
    five = load_input(sim_folder, rate_hz=5.0)
    stamps = np.array([r.scan.stamp for r in five.records])
    assert np.all(np.diff(stamps) >= 0.2 - 1e-9) and np.all(np.diff(stamps) < 0.23)


@pytest.mark.shared_data
def test_mit_relations_of_raw_odometry_match_the_published_anchor(shared_data):
    from slam.metrics import relations_error

    from experiments.slamrun import load_input

    data = load_input(shared_data / "mit-csail.clf.gz")
    assert data.relations is not None and data.relations.shape == (1172, 5)
    r = relations_error(data.odometry, data.relations)
    assert r.n == 1172 and r.n_skipped == 0
    assert r.trans_mean == pytest.approx(1.70, abs=0.05)  # Kummerle et al.'s raw odometry on this log


def test_a_simulator_folder_without_interlacing_turns_deskew_off(tmp_path):
    """De-skew moves beams by the LMS200's beam times; a folder simulated with interlaced=False
    (every beam from one pose, e.g. --ideal) must not be de-skewed (it would add that motion)."""
    from experiments.slamrun import deskew_for_sensor, simulated_interlaced
    from slam import SlamConfig

    (tmp_path / "scans.clf").write_text("")
    assert simulated_interlaced(tmp_path) is None  # no config.yaml: nothing known
    for flag in (False, True):
        (tmp_path / "config.yaml").write_text(f"world: office\nsensor:\n  n_beams: 361\n  interlaced: {str(flag).lower()}\n")
        assert simulated_interlaced(tmp_path) is flag
    assert simulated_interlaced(tmp_path / "scans.clf") is None  # a log file, not a folder
    # read as compare reads it (YAML 1.1's words): the strict loader refused `name: n`, which compare read (a review)
    (tmp_path / "config.yaml").write_text("world: office\nname: n\nsensor:\n  interlaced: no\n")
    assert simulated_interlaced(tmp_path) is False
    cfg = SlamConfig()
    assert cfg.alignment.deskew
    assert deskew_for_sensor(cfg, interlaced=True) is cfg
    off = deskew_for_sensor(cfg, interlaced=False)
    assert not off.alignment.deskew and off.alignment.normal_agreement == cfg.alignment.normal_agreement


@pytest.fixture(scope="module")
def sparse_log(tmp_path_factory) -> Path:
    """Office seed 1, 16 s at 0.5 scans/s (the search runs on every step), with scan 3 repeated
    (a zero interval: the prediction's std is its floor alone)."""
    from sim import simulate_records

    records = simulate_records("office", seed=1, duration=16.0, rate_hz=0.5)
    path = tmp_path_factory.mktemp("sparse") / "scans.clf"
    write_log(path, records[:4] + [records[3]] + records[4:])
    return path


@pytest.mark.parametrize("config, expected", [
    ("alignment: {search_sigmas: 0}", "alignment.search_sigmas: must be in [1, 10]"),  # was a ZeroDivisionError mid-run
    ("alignment: {search_sigmas: 1e300}", "alignment.search_sigmas: must be in [1, 10]"),  # the prior's std underflowed
    ("alignment: {search_step_theta: 1e-9}", "alignment.search_step_theta: must be in [0.001, pi] rad (finer "
                                             "needs more memory"),  # was a MemoryError
    ("alignment: {search_step_theta: 4}", "alignment.search_step_theta: must be in [0.001, pi] rad (at most "
                                          "half a turn)"),  # said "finer needs more memory"
    ("alignment: {search_resolution: 1e-6}", "alignment.search_resolution: must be in [0.01, 1] m (finer"),  # MemoryError
    ("alignment: {search_resolution: 2}", "alignment.search_resolution: must be in [0.01, 1] m (coarser cells"),
    ("alignment: {search_xy: 1e9}", "alignment.search_xy: must be in [0.2, 10] m"),
    ("alignment: {search_xy: 1.0e-300}", "alignment.search_xy: must be in [0.2, 10] m"),  # a divide-by-zero warning
    ("alignment: {search_sigma: 1e6}", "alignment.search_sigma: must be in [0.0001, 1] m"),
    ("alignment: {search_sigma: 5.0e-324}", "alignment.search_sigma: must be in [0.0001, 1] m"),  # numpy overflow warnings
    ("alignment: {fit_sigma: 1.0e-320}", "alignment.fit_sigma: must be in [0.0001, 1] m"),
    ("alignment: {search_step: 1.0e-160}", "alignment.search_step: must be in [0.1, 10] m"),  # OverflowError: step**-2
    ("alignment: {ambiguity_sigmas: 1.0e300}", "alignment.ambiguity_sigmas: must be in [0, 100] std"),  # OverflowError
    ("alignment: {ambiguity_sigmas: 1.0e300, fit_margin: 1.0e300}", "alignment.fit_margin: must be in [0, 1]"),
    ("alignment: {max_turn_rate: 0}", "alignment.max_turn_rate: must be in [0.01, 10000] rad/s"),
    ("motion: {sigma_floor_xy: 0}", "motion.sigma_floor_xy: must be in [1e-06, 1000] m"),  # a repeated stamp divided by a zero std
    ("motion: {sigma_floor_xy: 1.0e160}", "motion.sigma_floor_xy: must be in [1e-06, 1000] m"),  # OverflowError: sxy**2
    ("motion: {sigma_floor_theta: 1.0e300}", "motion.sigma_floor_theta: must be in [1e-06, 1000] rad"),  # OverflowError
    ("motion: {sigma_floor_xy: 1.0e-160, sigma_floor_theta: 1.0e-160}\nalignment: {motion_prior: true}",
     "motion.sigma_floor_xy: must be in [1e-06, 1000] m"),  # OverflowError: sxy**-2 at the repeated stamp
    ("motion: {sigma_floor_xy: 0.01, sigma_floor_theta: 1.0e-160}", "motion.sigma_floor_theta: must be in [1e-06"),
    ("motion: {sigma_accel: 1.0e200}", "motion.sigma_accel: must be in [0.001, 1000] m/s^2"),  # sxy**2 overflowed
    # 0 was "must be > 0" while 1e200 said [0, 1000], and -1 "must be >= 0": one interval, the one that holds
    ("motion: {sigma_accel: 0}", "motion.sigma_accel: must be in [0.001, 1000] m/s^2"),
    ("motion: {sigma_accel: -1}", "motion.sigma_accel: must be in [0.001, 1000] m/s^2"),
    ("motion: {sigma_alpha: 1.0e-300}", "motion.sigma_alpha: must be in [0.001, 1000] rad/s^2"),  # 0 in all but name
    # each ran to its end, exit 0, with a "not healthy" warning (no step matched) or none (a useless run)
    ("alignment: {stride: 1000000000000}", "alignment.stride: must be in [1, 16384] beams"),
    ("alignment: {damping: 1.0e300}", "alignment.damping: must be in [0, 1] of the Hessian's mean eigenvalue"),
    ("alignment: {tolerance_xy: 1.0e300}", "alignment.tolerance_xy: must be in [0, 0.1] m"),
    ("keyframes: {local_map: 1000000000000}", "keyframes.local_map: must be in [1, 1000] keyframes"),
    ("observations: {min_line_points: 1000000000000}", "observations.min_line_points: must be in [0, 16384] beams"),
    ("consistency: {nis_divergence: 0}", "consistency.nis_divergence: must be in [1, 1e+06] per degree of freedom"),
    ("consistency: {max_ambiguous: 2}", "consistency.max_ambiguous: must be in [0, 1] (a share of steps)"),
    ("consistency: {min_matched_fraction: 2}", "consistency.min_matched_fraction: must be in [0, 1] (a share of steps)"),
    ("alignment: {search_candidates: 1000000000}", "alignment.search_candidates: must be in [1, 32]"),  # an ICP per pose
    ("alignment: {search_step: 0.01, search_resolution: 0.01}",
     "the search window would hold 58,049,161 poses"),  # 361 x 401^2
])
def test_search_fields_out_of_bounds_are_one_line_exit_2(sparse_log, tmp_path, capsys, config, expected):
    """Every field of the correlative search and of the prediction's std is checked when the
    config is built, against physical bounds: one line on stderr naming the field and the bound
    that failed, exit status 2, nothing run (no traceback, no numpy warning). On a log that
    searches every step, each of these crashed (OverflowError, exit 1) or printed warnings."""
    out = tmp_path / "o"
    code = _slam_with_config(sparse_log, config, out)
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and expected in err[0], err
    assert "Traceback" not in captured.err and "Warning" not in captured.err
    assert not (out / "metrics.json").exists()


def test_stride_too_coarse_for_the_scans_is_one_line_exit_2(tmp_path, capsys):
    """alignment.stride is bounded by the most beams a scan may have (16,384: 60-150 there keeps as
    many points as 3 on an LMS200; it was at most 30 whatever the scanner), and refused at the first
    scan, before any matching, when it keeps fewer points than the matcher needs: 31 keeps 12 of a
    361-beam scan's beams (it ran to exit 0 with unmatched steps and a warning)."""
    from sim import simulate_records

    records = simulate_records("office", seed=0, duration=4.0, rate_hz=2)
    log = tmp_path / "scans.clf"
    write_log(log, records)
    out = tmp_path / "o"
    assert _slam_with_config(log, "alignment: {stride: 31}", out) == 2
    captured = capsys.readouterr()
    assert captured.err.strip().splitlines() == [
        "lmsbench slam: error: alignment.stride: 31 keeps 12 of the first scan's 361 beams, fewer than the 13 points the scan "
        "matcher needs; at most 30 for these scans"], captured.err
    assert not (out / "metrics.json").exists()


def _slam_with_config(log: Path, config: str, out: Path) -> int:
    """``lmsbench slam LOG --config FILE`` (the YAML ``config`` written beside ``out``) in this
    process with every warning an error; its exit status."""
    from experiments.cli import main

    cfg = out.parent / "config_under_test.yaml"
    cfg.write_text(config + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return main(["slam", str(log), "--config", str(cfg), "--out", str(out), "--quiet", "--no-paper-baseline"])


@pytest.mark.parametrize("config, searched", [
    ("motion: {sigma_floor_xy: 1.0e-6, sigma_floor_theta: 1.0e-6}\nalignment: {motion_prior: true}", 7),
    ("motion: {sigma_floor_xy: 1000, sigma_floor_theta: 1000, sigma_accel: 1000, sigma_alpha: 1000}\n"
     "alignment: {search_sigma: 1.0e-4, fit_sigma: 1.0e-4, ambiguity_sigmas: 100, fit_margin: 1}", 8),
])
def test_search_fields_at_their_bounds_run_without_warnings(sparse_log, tmp_path, capsys, config, searched):
    """The bounds are not too loose: the extreme values allowed run through (the repeated scan
    included) with every warning an error, and search every step 2 s after the last (7 of the
    8), and with a floor of 1000 std also the repeated one."""
    out = tmp_path / "o"
    code = _slam_with_config(sparse_log, config, out)
    assert code == 0
    m = json.loads((out / "metrics.json").read_text())
    assert m["n_scans"] == 9 and m["consistency"]["searched_fraction"] == searched / 8
    assert "Traceback" not in capsys.readouterr().err


def test_search_window_bound_counts_the_poses_the_search_scores(monkeypatch):
    """``search_window_poses`` is the size of the score array ``slam.correlative.search`` fills
    for a whole-turn window of the config's half-side (counted from the kernel's own output)."""
    import slam.correlative as corr
    from slam import SlamConfig
    from slam.config import search_window_poses

    sizes: list[int] = []
    kernel = corr._scores

    def counting(*args):
        out = kernel(*args)
        sizes.append(out.size)
        return out

    monkeypatch.setattr(corr, "_scores", counting)
    field = corr.make_field(np.array([[0.0, 0.0], [3.0, 1.0], [-2.0, 4.0]]), 0.1, 0.2)
    for al in (SlamConfig().alignment,
               SlamConfig.from_dict({"alignment": {"search_step": 0.3, "search_step_theta": 0.05,
                                                   "search_xy": 1.25}}).alignment):
        corr.search(np.array([[1.0, 0.5], [2.0, -1.0]]), field, np.zeros(3), al.search_xy, np.pi, al.search_step,
                    al.search_step_theta, 1, 0.3, 0.1)
        assert sizes[-1] == search_window_poses(al)
    assert sizes[0] == 361 * 21 * 21


@pytest.mark.slow
def test_an_unhealthy_run_warns_on_stderr(tmp_path, capsys):
    """Office seed 1 at 0.5 scans/s slides along a bare corridor (ATE 2.3 m) with 1 of its 44
    steps ambiguous (tests/test_slam_keyframe_logs.py): the command says so in one line on stderr,
    naming the share that metrics.json gives, and still exits 0 (the run finished)."""
    from experiments.cli import main
    from sim import simulate_records

    folder = write_sim_folder(tmp_path / "sparse", simulate_records("office", seed=1, duration=90.0, rate_hz=0.5))
    out = tmp_path / "run"
    assert main(["slam", str(folder), "--out", str(out), "--quiet", "--no-paper-baseline"]) == 0
    m = json.loads((out / "metrics.json").read_text())
    assert not m["consistency"]["healthy"] and m["ate"]["rmse"] > 0.5
    steps = m["n_scans"] - 1
    assert round(m["consistency"]["ambiguous_fraction"] * steps) == 1
    captured = capsys.readouterr()
    warnings = [line for line in captured.err.splitlines() if "warning" in line]
    assert len(warnings) == 1 and "warning" not in captured.out
    assert warnings[0].startswith(f"lmsbench slam: warning: {folder}: the run is not healthy: ")  # as sim2real's
    assert f"1 of {steps} steps ({100 / steps:.1f} %) were ambiguous" in warnings[0]


def _seven_beam_log(tmp_path: Path) -> Path:
    """A CARMEN log of 10 office scans (2 s at 5 scans/s) with 7 valid beams each, every 60th:
    nothing to match or extract a line from."""
    from lms200 import Record
    from sim import simulate_records

    sparse = []
    for r in simulate_records("office", seed=1, duration=2.0, rate_hz=5.0):
        ranges = np.full(r.scan.ranges.size, np.nan)
        ranges[::60] = r.scan.ranges[::60]
        sparse.append(Record(r.scan.replace(ranges=ranges), truth=r.truth))
    write_log(tmp_path / "sparse.clf", sparse)
    return tmp_path / "sparse.clf"


def test_a_run_whose_steps_were_not_matched_is_not_healthy(tmp_path, capsys):
    """Scans with 7 valid beams each give the matcher nothing (it needs 10 points), so every pose
    is the motion model's guess; such a run was reported healthy, silently. Now it is not, and the
    command names the share of matched steps (0 of 9)."""
    from experiments.cli import main

    log = _seven_beam_log(tmp_path)
    out = tmp_path / "run"
    assert main(["slam", str(log), "--out", str(out), "--quiet", "--no-paper-baseline"]) == 0
    m = json.loads((out / "metrics.json").read_text())
    steps = m["n_scans"] - 1
    assert steps == 9 and m["consistency"]["matched_fraction"] == 0.0 and not m["consistency"]["healthy"]
    warnings = [line for line in capsys.readouterr().err.splitlines() if "warning" in line]
    assert len(warnings) == 1 and f"only 0 of {steps} steps (0.0 %) were matched to the map" in warnings[0]


def test_a_paper_run_of_scans_without_a_line_says_so(tmp_path, capsys):
    """The paper preset on scans of 7 valid beams each (no line: nothing is paired with a landmark,
    every pose is the motion model's guess) said nothing, exit 0 (fuzzing): its metrics.json now
    gives matched_fraction 0 and the command warns, naming it; healthy stays the filter's state."""
    from experiments.cli import main

    log = _seven_beam_log(tmp_path)
    out = tmp_path / "run"
    assert main(["slam", str(log), "--preset", "paper", "--out", str(out), "--quiet"]) == 0
    c = json.loads((out / "metrics.json").read_text())["consistency"]
    assert c["matched_fraction"] == 0.0 and c["healthy"]
    warnings = [line for line in capsys.readouterr().err.splitlines() if "warning" in line]
    assert len(warnings) == 1 and "only 0 of 9 steps (0.0 %) were matched to the map" in warnings[0], warnings


def test_a_diverged_run_warns_once_naming_every_reason(tmp_path, capsys):
    """14 scans of uniform random ranges (0.5-8 m) at 5 scans/s: nothing matches (0 of 13 steps),
    10 scans in a row put fewer than 30 % of their points on the map (diverged at the 11th scan,
    t = 2.133 s) and 11 of the 13 searched steps are ambiguous. The divergence used to be printed
    twice (a stdout 'warning:' line and the stderr line) and the stderr line named only the first
    reason; now one stderr line names all three."""
    from experiments.cli import main
    from lms200 import Record
    from sim import simulate_records

    records = simulate_records("office", seed=1, duration=3.0, rate_hz=5.0)
    rng = np.random.default_rng(0)
    junk = [Record(r.scan.replace(ranges=rng.uniform(0.5, 8.0, r.scan.ranges.size)), truth=r.truth) for r in records]
    write_log(tmp_path / "junk.clf", junk)
    out = tmp_path / "run"
    assert main(["slam", str(tmp_path / "junk.clf"), "--out", str(out), "--quiet", "--no-paper-baseline"]) == 0
    c = json.loads((out / "metrics.json").read_text())["consistency"]
    assert c["diverged"] and c["diverged_at"] == pytest.approx(records[10].scan.stamp, abs=1e-6)
    assert c["matched_fraction"] == 0.0 and round(c["ambiguous_fraction"] * 13) == 11 and not c["healthy"]
    captured = capsys.readouterr()
    assert "warning" not in captured.out
    (line,) = [line for line in captured.err.splitlines() if "warning" in line]
    assert line.startswith(f"lmsbench slam: warning: {tmp_path / 'junk.clf'}: the run is not healthy: the estimate "
                           f"diverged at t={c['diverged_at']} (10 scans in a row put fewer than 0.3 of their points")
    assert "; only 0 of 13 steps (0.0 %) were matched to the map" in line
    assert "; 11 of 13 steps (84.6 %) were ambiguous" in line and line.endswith("(metrics.json: consistency.healthy false)")


def test_a_paper_run_that_diverged_but_stayed_healthy_warns_of_the_divergence():
    """The paper preset's health is its filter's state: a divergence (NIS or the point check)
    alone leaves it healthy, and the warning names the divergence (no 'not healthy')."""
    from experiments.commands.slam import _health_warning
    from slam import SlamConfig

    paper = SlamConfig(preset="paper")
    m = {"n_scans": 11, "consistency": {"diverged": True, "diverged_at": 4.5, "healthy": True}}
    assert _health_warning(m, paper) == ("the estimate diverged at t=4.5 (the filter's state broke, the mean NIS per "
                                         "dof over 20 scans exceeded 5, or 10 scans in a row put fewer than 0.3 of "
                                         "their points on the map)")
    m["consistency"]["healthy"] = False
    assert _health_warning(m, paper).startswith("the run is not healthy: the estimate diverged at t=4.5 (")
    assert _health_warning(m, paper).endswith("; the filter's state is not finite or its covariance is not positive "
                                              "definite (metrics.json: consistency.healthy false)")
    assert _health_warning({"n_scans": 11, "consistency": {"diverged": False, "healthy": True}}, paper) == ""


def test_the_odometry_doubt_warning_names_both_causes():
    """A step that doubts the odometry was said to be the odometry's fault alone. On Intel and ACES,
    whose odometry is right, all 30 such steps had the odometry's match right and the
    constant-velocity one slid along a corridor (docs/slam.md), so the phrase names both causes."""
    from experiments.commands.slam import _health_warning
    from slam import SlamConfig

    m = {"n_scans": 101, "consistency": {"diverged": False, "healthy": False, "odometry_doubt_fraction": 0.03}}
    assert _health_warning(m, SlamConfig()) == (
        "the run is not healthy: 3 of 100 steps (3.0 %) doubted the odometry (the match from its step explained "
        "under 0.7 of the points and the constant-velocity prediction's clearly more: a wrong odometry, or matching "
        "that is ambiguous there, as along a corridor; consistency.max_odometry_doubt 0) "
        "(metrics.json: consistency.healthy false)")


def test_slam_refuses_one_scan(sim_folder, tmp_path, capsys):
    """A log of one scan, --max-scans 1, or one scan left in time order, ran a "SLAM" of one pose and reported it healthy
    (matched fraction 1.0 of no step, exit 0). Both are refused in one line, before any output."""
    from experiments.cli import main
    from lms200 import read_log

    import dataclasses

    records = list(read_log(sim_folder / "scans.clf"))[:1]
    write_log(tmp_path / "one.clf", records)
    assert main(["slam", str(tmp_path / "one.clf"), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench slam: error: {tmp_path / 'one.clf'}: holds one scan (stamp {records[0].scan.stamp:.6f} s); "
        "SLAM needs two or more"]
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())
    assert main(["slam", str(sim_folder), "--max-scans", "1", "--out", str(tmp_path / "m"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--max-scans" in err[0] and ">= 2" in err[0]
    from experiments.slamrun import load_input
    from lms200 import LmsbenchError

    with pytest.raises(LmsbenchError, match="--max-scans must be >= 2"):
        load_input(sim_folder, max_scans=1)
    # two scans, the second stamped before the first: --skip-bad-lines left one and ran it (review)
    # (the first one second later: the sim's first stamp is 0, and a log's stamps are never negative)
    two = [dataclasses.replace(records[0], scan=records[0].scan.replace(stamp=records[0].scan.stamp + 1.0)), records[0]]
    write_log(tmp_path / "back.clf", two)
    assert main(["slam", str(tmp_path / "back.clf"), "--skip-bad-lines", "--out", str(tmp_path / "b"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == (f"lmsbench slam: error: {tmp_path / 'back.clf'}: 1 of its 2 scans are in time order; "
                       "SLAM needs two or more")
    assert not (tmp_path / "b").exists() or not any((tmp_path / "b").iterdir())


def test_slam_summary_prints_the_runs_relations_error_beside_the_published_ones():
    """On MIT CSAIL the summary printed 'published relations error (m): scan matching 0.106, ...'
    and not the run's own 0.0283 (README's table), which was in metrics.json alone."""
    from experiments.commands.slam import _score_lines

    table = [{"source": "slam", "relations_trans_mean": 0.028251, "cpu_scans_per_s": 853.2},
             {"source": "paper preset", "relations_trans_mean": 0.58295},
             {"source": "raw odometry", "relations_trans_mean": 1.68146},
             {"source": "paper preset (odometry)", "relations_trans_mean": float("nan")}]
    assert _score_lines({"table": table}) == [
        "  relations error, mean (m): this run 0.0283, paper preset 0.583, raw odometry 1.68"]
    # a run whose relations all lie outside it (its note is printed instead) and an input without scores
    assert _score_lines({"relations": {"n": 0, "note": "none of the 1172 relations falls inside the run"},
                         "table": [{"source": "slam", "relations_n": 0}, table[1]]}) == []
    # an input with no reference says so (it printed nothing: tests/test_walkthrough_scores.py)
    assert _score_lines({"table": [{"source": "slam"}]}) == _score_lines({}) == [
        "  no score: the input has no reference to score the run against (no true or corrected poses, no "
        "relations file: --relations FILE, or NAME.relations beside the log)"]


def test_a_reference_covering_part_of_the_run_is_said(sim_folder, tmp_path, capsys):
    """A groundtruth.tum covering 2 of the run's poses gave the ATE over those 2 as the run's,
    exit 0 and nothing said (the wrong-input hunt). The run still scores what it can, and says
    how much of it that is; a whole reference says nothing."""
    import shutil

    from experiments.cli import main

    short = tmp_path / "short"
    shutil.copytree(sim_folder, short)
    stamps, poses = read_tum(sim_folder / "groundtruth.tum")
    write_tum(short / "groundtruth.tum", stamps[:2], poses[:2])
    argv = ["--out", str(tmp_path / "o"), "--quiet", "--no-paper-baseline", "--max-scans", "20"]
    assert main(["slam", str(short), *argv]) == 0
    err = capsys.readouterr().err
    assert ("the ATE covers 2 of the run's 20 poses, those within the span of its reference (ground truth); the "
            "rest are not scored (metrics.json ate.n)") in err
    assert json.loads((tmp_path / "o" / "metrics.json").read_text())["ate"]["n"] == 2
    assert main(["slam", str(sim_folder), *argv[:1], str(tmp_path / "o2"), *argv[2:]]) == 0
    assert "the ATE covers" not in capsys.readouterr().err


def test_slam_config_yaml_holds_the_extractors_resolved_config_and_the_versions(sim_folder, tmp_path, capsys):
    """Issue #16: every command writes the resolved config of what ran, sensor, extractor, SLAM and
    versions. slam's config.yaml held `extractor_params: {}` (the overrides, none) and no
    versions (an audit of the resolved issues). It now holds every field of the extractor's config
    and the versions; `slam --config` on it reads the slam: section as before and runs the same."""
    import dataclasses

    import yaml

    from experiments.cli import main
    from features.registry import make_config

    out = tmp_path / "run"
    argv = ["--quiet", "--no-paper-baseline", "--max-scans", "15"]
    assert main(["slam", str(sim_folder), "--out", str(out), *argv]) == 0
    record = yaml.safe_load((out / "config.yaml").read_text())
    assert list(record) == ["input", "slam", "extractor_config", "versions"]
    assert record["extractor_config"] == dataclasses.asdict(make_config(record["slam"]["extractor"]))
    assert record["extractor_config"]["k"] == 3 and record["extractor_config"]["sigma_r_cm"] == "auto"
    assert {"lmsbench", "numpy", "numba", "gtsam", "python"} <= set(record["versions"])
    again = tmp_path / "again"
    assert main(["slam", str(sim_folder), "--config", str(out / "config.yaml"), "--out", str(again), *argv]) == 0
    assert (again / "trajectory.tum").read_text() == (out / "trajectory.tum").read_text()
    assert main(["slam", str(sim_folder), "--out", str(out), *argv]) == 0  # its own earlier folder: replaced
    capsys.readouterr()


@pytest.mark.parametrize("preset, label", [("default", "map lines"), ("paper", "line landmarks")])
def test_slam_png_names_the_default_pipelines_lines_as_its_map(sim_folder, tmp_path, monkeypatch, preset, label):
    """slam.png's legend said "line landmarks" for the default pipeline, whose lines are its
    keyframes' merged map, not EKF landmarks (a new user's review); the paper preset keeps it."""
    import matplotlib.figure

    from experiments.cli import main

    seen = []

    def savefig(self, *args, **kwargs):
        seen.extend(t.get_text() for ax in self.axes if ax.get_legend() for t in ax.get_legend().get_texts())
        Path(args[0]).write_bytes(b"")  # the temporary file slam.png is renamed from (written whole)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", savefig)
    baseline = ["--no-paper-baseline"] if preset == "default" else []  # the paper preset's run is no baseline
    assert main(["slam", str(sim_folder), "--preset", preset, "--max-scans", "12", *baseline, "--quiet",
                 "--out", str(tmp_path / "o")]) == 0
    assert label in seen and ({"map lines", "line landmarks"} - {label}).isdisjoint(seen)


@pytest.mark.shared_data
def test_relations_over_part_of_a_log_are_said(shared_data, tmp_path, capsys):
    """`slam mit-csail.clf.gz --max-scans 100` printed 'relations error, mean (m): this run 0.0163'
    beside the published errors over the whole log, and said nothing: 24 of the file's 1172
    relations were scored (a new user's review). It now says how many, and that the figure is not
    comparable."""
    from experiments.cli import main

    argv = ["slam", str(shared_data / "mit-csail.clf.gz"), "--max-scans", "100", "--no-paper-baseline",
            "--no-odometry-baseline", "--quiet", "--out", str(tmp_path / "o")]
    assert main(argv) == 0
    captured = capsys.readouterr()
    err = captured.err
    # and the summary's time is named: 'in 58.1 s (35 scans/s of CPU time)' read as one clock
    assert re.search(r"100 scans in [0-9.]+ s of wall-clock time \([0-9]+ scans/s of CPU time\)", captured.out)
    rel = json.loads((tmp_path / "o" / "metrics.json").read_text())["relations"]
    assert rel["n"] + rel["n_skipped"] == 1172 and rel["n"] < 100
    assert (f"the relations error covers {rel['n']} of the file's 1172 relations, those within the run's time span "
            "(--max-scans or a cut log leave the rest out); it is not comparable with errors over the whole log "
            "(metrics.json relations.n, n_skipped)") in err


def test_slam_set_overrides_its_extractor_as_compare_does(sim_folder, tmp_path, capsys):
    """Issue #16: one spelling of extractor overrides. `slam` had no --set: its extractor took
    overrides only as a config file's extractor_params (an audit of the resolved issues). `--set
    extractor.[METHOD.]FIELD=VALUE` now joins extractor_params, checked as compare checks it."""
    import yaml

    from experiments.cli import main

    argv = ["slam", str(sim_folder), "--quiet", "--no-paper-baseline", "--max-scans", "10"]
    assert main([*argv, "--set", "extractor.k=5", "--set", "extractor.sensor.ad_tau=3.5", "--out", str(tmp_path / "o")]) == 0
    record = yaml.safe_load((tmp_path / "o" / "config.yaml").read_text())
    assert record["slam"]["extractor_params"] == {"k": 5, "ad_tau": 3.5}
    for extra, message in ((["--set", "extractor.kk=1"], "no extractor of this run (sensor) has a field 'kk'"),
                           (["--set", "extractor.hough.rho_step=0.1"], "'hough' is not an extractor of this run"),
                           (["--set", "extractor.k=abc"], "extractor_params.k: must be an integer"),
                           (["--set", "extractor.k=2", "--set", "extractor.k=3"], "--set extractor.k is given twice"),
                           (["--set", "k=5"], "--set takes extractor.FIELD=VALUE"),
                           # yamlio's reason, which said only "'1_0' is not a value" (a review)
                           (["--set", "extractor.k=1_0"], "--set extractor.k: '1_0' is not a value (1_0 is read as 10: "
                                                          "YAML 1.1 drops a number's underscores"),
                           (["--set", "extractor.k=[1"], "--set extractor.k: '[1' is not a value (expected ',' or ']'")):
        assert main([*argv, *extra, "--out", str(tmp_path / "bad")]) == 2
        err = capsys.readouterr().err
        assert message in err and len(err.strip().splitlines()) == 1, err
        assert not (tmp_path / "bad").exists()


def test_a_users_extractor_config_of_numpy_values_and_tuples_is_recorded(sim_folder, tmp_path, monkeypatch, capsys):
    """slam's config.yaml records the extractor's resolved config; a user's config whose defaults
    were numpy values (np.deg2rad(20)) or tuples failed yaml.safe_dump: 'internal error:
    RepresenterError', exit 1, where the run had completed before (a review). compare's config.yaml
    failed the same way. They are written as plain data."""
    import yaml

    from experiments.cli import main
    from features.registry import _REGISTRY

    (tmp_path / "npext.py").write_text(
        "import dataclasses\nimport numpy as np\nfrom features import extract\n\n\n"
        "@dataclasses.dataclass(frozen=True)\nclass Cfg:\n    turn: float = np.deg2rad(20.0)\n"
        "    window: tuple = (1, 2)\n    gains: np.ndarray = dataclasses.field(default_factory=lambda: np.array([0.5, 1.5]))\n\n\n"
        "def ext(scan, config):\n    return extract(scan, method='split_merge')\n\n\next.config_type = Cfg\n")
    monkeypatch.chdir(tmp_path)
    try:
        assert main(["slam", str(sim_folder), "--extractor", "npext:ext", "--out", "o", "--quiet",
                     "--no-paper-baseline", "--max-scans", "8"]) == 0
        assert main(["compare", str(sim_folder), "--methods", "npext:ext", "--max-scans", "3", "--out", "c",
                     "--no-progress"]) == 0
    finally:
        _REGISTRY.pop("npext:ext", None)
    record = yaml.safe_load((tmp_path / "o" / "config.yaml").read_text())["extractor_config"]
    assert record == {"turn": 0.3490658503988659, "window": [1, 2], "gains": [0.5, 1.5]}
    assert yaml.safe_load((tmp_path / "c" / "config.yaml").read_text())["methods"]["npext:ext"] == record
    capsys.readouterr()


@pytest.mark.parametrize("field, value, message", [
    ("huber", 1e-300, r"alignment\.huber: must be in \[1e-06, 1\] m \(a residual's scale: .*\), got 1e-300"),
    ("covariance_inflation", 1e30, r"alignment\.covariance_inflation: must be in \[0\.01, 100\] \(a factor on the "
                                   r"match's covariance; 1, the default, is none\), got 1e\+30")])
def test_slam_config_refuses_an_icp_scale_that_breaks_the_run(sim_folder, tmp_path, capsys, field, value, message):
    """Fuzzing of 2026-12-06: alignment.huber 1e-30 or less weighed every point ~0, and gtsam
    stopped the run ("internal error: RuntimeError: Indeterminate linear system", exit 1);
    covariance_inflation 1e4 or more left the keyframe factors no weight against the rest: a 120 s
    office run 2.5-3.5 m off (0.007 m at 1-1000), exit 0 without a warning. Refused before any work."""
    from experiments.cli import main

    config = tmp_path / "slam.yaml"
    config.write_text(f"alignment: {{{field}: {value!r}}}\n")
    out = tmp_path / "run"
    assert main(["slam", str(sim_folder), "--out", str(out), "--config", str(config), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert re.fullmatch(rf"lmsbench slam: error: {re.escape(str(config))}: {message}\n", err), err
    assert not out.exists()


def test_a_slam_run_of_a_log_named_like_a_boolean_word_reruns_into_its_folder(sim_folder, tmp_path, capsys, monkeypatch):
    """config.yaml was written with yaml.safe_dump, which leaves ``n`` and ``y`` unquoted (text to
    PyYAML): a run on a log named ``n`` wrote ``log: n``, which the loader refuses as a YAML 1.1
    boolean word, so the next run into that --out took the folder for none of slam's ("holds
    config.yaml, ... no earlier lmsbench slam run wrote"). lmsbench's YAML writer quotes them."""
    import shutil

    from experiments.cli import main
    from lms200.yamlio import load

    monkeypatch.chdir(tmp_path)
    shutil.copyfile(sim_folder / "scans.clf", tmp_path / "n")
    for _ in range(2):
        assert main(["slam", "n", "--out", "o", "--quiet", "--max-scans", "5"]) == 0, capsys.readouterr().err
    assert "input:\n  scans: 'n'\n" in (tmp_path / "o" / "config.yaml").read_text()
    assert load((tmp_path / "o" / "config.yaml").read_text())["input"]["scans"] == "n"


def test_a_world_json_wall_of_zero_length_is_refused_before_the_run_naming_the_file(sim_folder, tmp_path, capsys):
    """A simulate folder's world.json with a wall whose ends are equal ran the whole SLAM and then
    failed in map_error, "walls: every wall must have two distinct ends (...)", naming no file."""
    import shutil

    from experiments.cli import main

    run = tmp_path / "run"
    shutil.copytree(sim_folder, run)
    world = json.loads((run / "world.json").read_text())
    world["walls"][3] = [1.0, 1.0, 1.0, 1.0]
    (run / "world.json").write_text(json.dumps(world))
    assert main(["slam", str(run), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench slam: error: {run / 'world.json'}: not a world.json (walls: wall 3, [1.0, 1.0, 1.0, 1.0], has two "
        "equal ends: a wall of zero length has no direction to score the map against)"]
    assert not (tmp_path / "o").exists()


def test_the_slam_figure_draws_walls_and_map_lines_as_one_artist_each(sim_folder, tmp_path, monkeypatch):
    """slam.png drew each wall and map line with its own ax.plot: a world.json of 20,000 walls took
    118 s in plot() (mit's 2,345 several seconds), a hang for a larger one. Now one LineCollection
    each, the axes still spanning every wall."""
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure

    from experiments.slamrun import load_input, plot
    from slam import run_slam

    data = load_input(sim_folder)
    res = run_slam(data.records)
    rng = np.random.default_rng(0)
    far = np.column_stack((rng.uniform(-50, 50, (20_000, 2)), rng.uniform(-50, 50, (20_000, 2))))
    data.walls = np.vstack((data.walls, far, [[-80.0, -1.0, -79.0, -1.0]]))
    seen = {}

    def savefig(fig, *args, **kwargs):  # noqa: ANN001, ANN002, ANN003
        ax = fig.axes[0]
        seen.update(lines=len(ax.lines), segments=[len(c.get_segments()) for c in ax.collections
                                                   if isinstance(c, LineCollection)], xlim=ax.get_xlim())

    monkeypatch.setattr(Figure, "savefig", savefig)
    plot(tmp_path / "slam.png", data, res)
    assert seen["segments"] == [len(data.walls), len(res.map_lines)] and seen["lines"] <= 4  # truth, path, legend
    assert seen["xlim"][0] <= -80.0  # the far wall is in view


def test_a_world_json_of_boxes_with_an_empty_walls_list_is_refused(sim_folder, tmp_path, capsys):
    """simulate writes the boxes (what is scanned) and their faces as walls (what the map is scored
    against); a world.json whose walls list was emptied ran, its map scored against no wall
    (metrics.json map: matched 0, wall_coverage 0.0), exit 0."""
    import shutil

    from experiments.cli import main

    run = tmp_path / "run"
    shutil.copytree(sim_folder, run)
    world = json.loads((run / "world.json").read_text())
    assert world["boxes"] and world["walls"]
    world["walls"] = []
    assert sum(b[5] <= 0.35 <= b[6] for b in world["boxes"]) == 37 and len(world["boxes"]) == 39
    (run / "world.json").write_text(json.dumps(world))
    assert main(["slam", str(run), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench slam: error: {run / 'world.json'}: not a world.json: its walls list is empty beside "
        f"{sum(b[5] <= 0.35 <= b[6] for b in world['boxes'])} of its {len(world['boxes'])} boxes that span the scan plane (at 0.35 m), so the map "
        "would be scored against no wall (simulate writes those boxes' faces there)"]
    assert not (tmp_path / "o").exists()


def test_a_world_json_whose_boxes_all_sit_off_the_scan_plane_is_read(sim_folder, tmp_path):
    """simulate writes no walls for boxes the scan plane does not cut (sim.world.spans_plane): its own
    world.json of low boxes and tall cylinders was refused by slam as 'walls list is empty beside 2 boxes'."""
    import shutil

    from experiments.slamrun import load_input
    from sim.world import World

    run = tmp_path / "run"
    shutil.copytree(sim_folder, run)
    World(name="lowbox", seed=0, boxes=[[0, 0, 0, 0.5, 0.5, 0.0, 0.1], [8, 0, 0, 0.5, 0.5, 0.0, 0.1]],
          cylinders=[[2, 2, 0.3, 0, 2]], scan_height=0.3).to_json(run / "world.json")
    written = json.loads((run / "world.json").read_text())
    assert written["walls"] == [] and len(written["boxes"]) == 2
    data = load_input(run)
    assert "walls" not in data.sources and data.walls is None
    assert data.notes == [f"{run / 'world.json'}: the world has no wall in the scan plane to score the map against "
                          "(no map score)"]
    # one box that reaches the plane (its top exactly at it, ends included as World cuts it) is refused
    written["boxes"][1][6] = 0.3
    (run / "world.json").write_text(json.dumps(written))
    with pytest.raises(LmsbenchError, match=r"empty beside 1 of its 2 boxes that span the scan plane \(at 0.3 m\)"):
        load_input(run)


def test_slam_messages_name_the_logs_own_scan_number_under_every(sim_folder, tmp_path, capsys):
    """docs/commands.md: messages count a log's scans from 0, by the log's own number. With --every 2
    the time-order, skipped-scan, in-scale, no-time-step and max_gap messages named the index among the
    scans kept: "time goes backwards at scan 2" for the log's scan 4."""
    import dataclasses

    from experiments.cli import main
    from lms200 import read_log

    records = list(read_log(sim_folder / "scans.clf"))[:20]
    t = [r.scan.stamp for r in records]

    def log(name: str, stamps: list[float]) -> str:
        write_log(tmp_path / name, [dataclasses.replace(r, scan=r.scan.replace(stamp=s)) for r, s in zip(records, stamps)])
        return str(tmp_path / name)

    back = log("back.clf", [t[1] if k == 4 else s for k, s in enumerate(t)])  # scan 4 before scan 2 (kept: 0, 2, 4, ...)
    assert main(["slam", back, "--every", "2", "--out", str(tmp_path / "o1"), "--quiet"]) == 2
    assert capsys.readouterr().err.startswith(f"lmsbench slam: error: {back}: time goes backwards at scan 4 (stamp "
                                              f"{t[1]:.6f} s after {t[2]:.6f} s)")
    assert main(["slam", back, "--every", "2", "--skip-bad-lines", "--out", str(tmp_path / "o2"), "--quiet"]) == 0
    # kept stamps t0, t2, t1, t6, ...: one of the log's scans 2 and 4 goes (kept scans 1 and 2)
    assert f"{back}: skipped scan 2 (stamp {t[2]:.6f} s): out of time order" in capsys.readouterr().err
    # (a gap beyond slam.run.MAX_STAMP_STEP_S, 1e12 s, no longer reads from a log: its stamps lie in 0 .. 2^32 s,
    # lms200.records.MAX_STAMP_S; run_slam's own check is test_slam_refuses_stamps_and_poses_its_models_overflow_on's)
    odd = log("odd.clf", [t[4] if k == 6 else s + (100.0 if k >= 10 else 0.0) for k, s in enumerate(t)])
    assert main(["slam", odd, "--every", "2", "--out", str(tmp_path / "o4"), "--quiet"]) == 0
    err = capsys.readouterr().err
    assert (f"1 of 9 steps take no time (scan 6 has the stamp of the scan kept before it, scan 4's {t[4]:.6f} s)"
            in err)
    assert f"(scan 10 is stamped {t[10] + 100 - t[8]:.6g} s after scan 8, the one kept before it)" in err


def test_a_world_json_wall_of_three_numbers_is_one_line_naming_the_file_and_the_wall(sim_folder, tmp_path, capsys):
    """The fuzz round: a world.json wall of 3 numbers was numpy's "setting an array element with a
    sequence. The requested array has an inhomogeneous shape after 1 dimensions. The detected shape
    was (140,) + inhomogeneous part." in slam, compare and simulate. Now one line naming world.json,
    the wall's index and what a wall must be, from each command, before any output."""
    import json
    import shutil

    from experiments.cli import main

    run = tmp_path / "run"
    shutil.copytree(sim_folder, run)
    d = {"walls": [[0, 0, 4, 0], [4, 0, 4, 3], [4, 3, 0]], "circles": [], "corners": []}
    (run / "world.json").write_text(json.dumps(d))
    said = "not a world.json (walls: wall 2 is [4, 3, 0] (3 numbers): a wall must be a list of 4 numbers x1, y1, x2, y2 (m))"
    for command in (["slam", str(run), "--quiet"], ["compare", str(run), "--quiet"],
                    ["simulate", "--world", str(run / "world.json"), "--duration", "1"]):
        assert main([*command, "--out", str(tmp_path / "o")]) == 2
        assert capsys.readouterr().err.strip().splitlines() == [
            f"lmsbench {command[0]}: error: {run / 'world.json'}: {said}"], command
        assert not (tmp_path / "o").exists()


def test_a_world_json_number_too_large_for_a_float_is_one_line_naming_the_field_and_row(sim_folder, tmp_path, capsys):
    """A 400-digit whole number in a wall passed is_number and np.asarray raised OverflowError:
    `simulate --world` said "internal error: OverflowError"; slam's check of the boxes beside an empty
    walls list too, and a ragged box there was numpy's "inhomogeneous shape" text."""
    import shutil

    from experiments.cli import main

    run = tmp_path / "run"
    shutil.copytree(sim_folder, run)
    big = int("9" * 400)
    world = tmp_path / "big.json"
    world.write_text(json.dumps({"walls": [[0, 0, 4, 0], [4, 0, 4, 3], [4, 3, 0, big], [0, 3, 0, 0]]}))
    assert main(["simulate", "--world", str(world), "--duration", "1", "--out", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"lmsbench simulate: error: {world}: not a world.json (walls: wall 2 is {'[4, 3, 0, ' + '9' * 30}"
        "...9999999] (411 characters), holding a number too large for a float: a wall must be a list of 4 numbers "
        "x1, y1, x2, y2 (m))"]
    box = "a box must be a list of 7 numbers cx, cy, yaw, hx, hy, z0, z1"
    for boxes, said in [([[0, 0, 0, 1, 1, 0, 1], [0, 0, 0, 1, 1, 0, big]], f"box 1 is [0, 0, 0, 1, 1, 0, {'9' * 21}"
                         "...9999999] (420 characters), holding a number too large for a float: " + box),
                        ([[0, 0, 0, 1, 1, 0, 1], [0, 0, 0, 1, 1, 0]], f"box 1 is [0, 0, 0, 1, 1, 0] (6 numbers): {box}")]:
        (run / "world.json").write_text(json.dumps({"walls": [], "boxes": boxes}))
        assert main(["slam", str(run), "--quiet", "--out", str(tmp_path / "o")]) == 2
        assert capsys.readouterr().err.strip().splitlines() == [
            f"lmsbench slam: error: {run / 'world.json'}: not a world.json (boxes: {said})"]
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("field, rows, row, must", [
    ("boxes", [[0, 0, 0, 1, 1, 0, 1], [0, 0, 0, 1, 1, 0, "BIG"]], "box 1 is [0, 0, 0, 1, 1, 0, 999",
     "a box must be a list of 7 numbers cx, cy, yaw, hx, hy, z0, z1"),
    ("cylinders", [["BIG", 0, 0.2, 0, 2]], "cylinder 0 is [999",
     "a cylinder must be a list of 5 numbers cx, cy, r, z0, z1"),
    ("glass", [[0, 0, 1, 1], [0, 0, 1, "BIG"]], "glass panel 1 is [0, 0, 1, 999",
     "a glass panel must be a list of 4 numbers x1, y1, x2, y2 (m)"),
])
def test_a_world_json_solid_too_large_for_a_float_names_the_row(sim_folder, tmp_path, capsys, field, rows, row, must):
    """A 400-digit number in a world.json's boxes, cylinders or glass given to simulate or compare
    was World's "boxes: must be a (k, 7) array of real numbers (...), got list" (before that an
    internal "OverflowError: int too large to convert to float"), naming no row; now json_rows's
    message, as the walls', naming field and row."""
    from experiments.cli import main

    big = int("9" * 400)
    world = {"walls": [], "boxes": [[2, 0, 0, 0.1, 3, 0, 2], [-2, 0, 0, 0.1, 3, 0, 2]], "cylinders": []}
    world[field] = [[big if v == "BIG" else v for v in r] for r in rows]
    import shutil

    run = tmp_path / "run"
    shutil.copytree(sim_folder, run)
    path = run / "world.json"
    path.write_text(json.dumps(world))
    for command in (["simulate", "--world", str(path), "--duration", "1", "--quiet"],
                    ["compare", str(run), "--no-progress"]):
        assert main([*command, "--out", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and re.fullmatch(
            re.escape(f"lmsbench {command[0]}: error: {path}: not a world.json ({field}: {row}") + r"9*\.\.\.[0-9, .]*\] "
            r"\(4\d\d characters\), " + re.escape(f"holding a number too large for a float: {must})"), err[0]), err
        assert not (tmp_path / "o").exists()


def test_a_world_json_scan_height_too_large_or_a_name_too_long_is_refused(tmp_path):
    """scan_height of 400 digits was "not a world.json (OverflowError: int too large to convert to
    float)"; a name of 100,000 characters was taken and simulate drew it as map.png's title for over
    a minute (30,000: 18 s), the image and its memory growing with it."""
    from lms200 import LmsbenchError
    from sim.world import MAX_NAME_CHARS, World

    boxes = [[2, 0, 0, 0.1, 3, 0, 2], [-2, 0, 0, 0.1, 3, 0, 2]]
    path = tmp_path / "world.json"
    for extra, said in (({"scan_height": int("9" * 400)}, "scan_height: must be a finite height >= 0 m, got "
                         + "9" * 40 + "...99999999 (400 characters)"),
                        ({"name": "x" * 100_000}, "name: at most 255 characters (a title, as a file name), got '"
                         + "x" * 39 + "...xxxxxxx' (100002 characters)")):
        path.write_text(json.dumps({"boxes": boxes, **extra}))
        with pytest.raises(LmsbenchError, match="^" + re.escape(f"{path}: not a world.json ({said})") + "$"):
            World.from_json(path)
    path.write_text(json.dumps({"boxes": boxes, "name": "x" * MAX_NAME_CHARS}))
    assert World.from_json(path).name == "x" * 255


def test_world_json_route_nodes_read_as_walls_are_flat_or_rows(tmp_path):
    """docs/simulator.md: route_nodes, as walls, may be a flat list read two at a time; it was refused
    ("route_nodes: must be a (k, 2) array (x, y), got shape (4,)"), and a bad route row's message bore
    no row index in a world of boxes and a "ValueError: " prefix in a walls-only one."""
    from sim.world import World

    walls = [[0, 0, 4, 0], [4, 0, 4, 3], [4, 3, 0, 3], [0, 3, 0, 0]]
    boxes = [[2, 1.5, 0, 2, 1.5, 0, 1]]
    for extra in ({"walls": walls}, {"walls": [], "boxes": boxes, "cylinders": []}):
        path = tmp_path / "w.json"
        path.write_text(json.dumps({**extra, "route_nodes": [1, 2, 3, 1], "route_edges": [[0, 1]]}))
        assert World.from_json(path).route_nodes.tolist() == [[1.0, 2.0], [3.0, 1.0]]
        path.write_text(json.dumps({**extra, "route_nodes": [[1, 2], [3]]}))
        with pytest.raises(LmsbenchError) as err:
            World.from_json(path)
        assert str(err.value) == (f"{path}: not a world.json (route_nodes: route node 1 is [3] (1 numbers): a route "
                                  "node must be a list of 2 numbers x, y (m))")


def test_slam_on_a_world_with_no_wall_in_the_scan_plane_writes_no_map_score(sim_folder, tmp_path, capsys):
    """A world whose boxes all sit off the scan plane was scored "matched 0, coverage 0.0", exit 0:
    now no map score, and one note saying why."""
    import shutil

    from experiments.cli import main
    from sim.world import World

    run = tmp_path / "run"
    shutil.copytree(sim_folder, run)
    World(name="lowbox", seed=0, boxes=[[0, 0, 0, 0.5, 0.5, 0.0, 0.1]], cylinders=[[2, 2, 0.3, 0, 2]],
          scan_height=0.3).to_json(run / "world.json")
    assert main(["slam", str(run), "--max-scans", "5", "--quiet", "--out", str(tmp_path / "o")]) == 0
    note = f"{run / 'world.json'}: the world has no wall in the scan plane to score the map against (no map score)"
    assert capsys.readouterr().err.strip().splitlines().count(note) == 1
    metrics = json.loads((tmp_path / "o" / "metrics.json").read_text())
    assert "map" not in metrics and "ate" in metrics


HINT = ("set extractor fields under {}extractor_params: (`extractor_params: {{k: 7}}`), or with --set "
        "extractor.FIELD=VALUE (extractor.METHOD.corners.FIELD=VALUE for a baseline's corner field)")


def test_an_edit_of_a_runs_extractor_config_record_is_refused(sim_folder, tmp_path, capsys) -> None:
    """A review: a run's config.yaml records the extractor's resolved settings under extractor_config:,
    which `slam --config` reads past: `k: 3` edited to `k: 7` there ran k = 3, exit 0 (the same
    trajectory, the new run's record saying 3). An edit is refused, naming the key and the field and
    saying where extractor fields go; the record as written is read past as before; extractor_config:
    as a SLAM field (flat, or under slam:) says the same instead of only "unknown SLAM config field".
    The second review: the edits that are read (slam: extractor_params, slam: extractor) leave the record
    behind and are not refused for it (they were: the hint's own way was refused)."""
    import yaml

    from experiments.cli import main

    common = ["--quiet", "--no-paper-baseline", "--max-scans", "4"]
    assert main(["slam", str(sim_folder), "--out", str(tmp_path / "a"), *common]) == 0
    text = (tmp_path / "a" / "config.yaml").read_text()
    assert text.count("\n  k: 3\n") == 1
    edited = tmp_path / "edited.yaml"
    edited.write_text(text.replace("\n  k: 3\n", "\n  k: 7\n"))
    capsys.readouterr()
    assert main(["slam", str(sim_folder), "--config", str(edited), "--out", str(tmp_path / "b"), *common]) == 2  # old: 0
    assert capsys.readouterr().err == (
        f"lmsbench slam: error: {edited}: extractor_config: k: 7, where its slam: section (sensor) gives 3: "
        "extractor_config: is the record of what a run ran, which --config does not read, so an edit there would be "
        "ignored, and a record of another lmsbench version's defaults would not be reproduced; delete "
        f"extractor_config: to run what slam: gives, or {HINT.format('slam: ')}\n")
    assert not (tmp_path / "b").exists()
    edited.write_text(text.replace("extractor_config:\n", "extractor_config:\n  kk: 1\n"))
    assert main(["slam", str(sim_folder), "--config", str(edited), "--out", str(tmp_path / "b"), *common]) == 2
    assert f"{edited}: extractor_config: kk: 1 is a field of no extractor (nor of sensor, which its slam: section " \
        "names)" in capsys.readouterr().err
    assert main(["slam", str(sim_folder), "--config", str(tmp_path / "a" / "config.yaml"), "--out", str(tmp_path / "c"),
                 *common]) == 0  # the record as written
    assert (tmp_path / "c" / "trajectory.tum").read_text() == (tmp_path / "a" / "trajectory.tum").read_text()
    record = yaml.safe_load(text)
    for slam_edit, ran in (({"extractor_params": {"k": 7}}, ("sensor", 7)), ({"extractor": "iepf"}, ("iepf", None))):
        edited.write_text(yaml.safe_dump({**record, "slam": {**record["slam"], **slam_edit}}))
        assert main(["slam", str(sim_folder), "--config", str(edited), "--out", str(tmp_path / "e"), *common]) == 0
        rerun = yaml.safe_load((tmp_path / "e" / "config.yaml").read_text())
        assert (rerun["slam"]["extractor"], rerun["extractor_config"].get("k")) == ran  # the slam: edit ran
    # iepf's record, slam: extractor changed to split_merge, of the same fields (the third review: refused, its
    # split_sigmas 3 against split_merge's 4)
    iepf_record = yaml.safe_load((tmp_path / "e" / "config.yaml").read_text())
    edited.write_text(yaml.safe_dump({**iepf_record, "slam": {**iepf_record["slam"], "extractor": "split_merge"}}))
    assert main(["slam", str(sim_folder), "--config", str(edited), "--out", str(tmp_path / "f"), *common]) == 0
    assert yaml.safe_load((tmp_path / "f" / "config.yaml").read_text())["slam"]["extractor"] == "split_merge"
    for text, where, nested in (("extractor_config: {k: 7}\n", "in it", ""),
                                ("slam: {extractor_config: {k: 7}}\n", "under slam:", "slam: ")):
        edited.write_text(text)
        capsys.readouterr()
        assert main(["slam", str(sim_folder), "--config", str(edited), "--out", str(tmp_path / "d"), *common]) == 2
        assert capsys.readouterr().err == (
            f"lmsbench slam: error: {edited}: extractor_config: {where} is no SLAM config field (a slam run's config.yaml "
            "records the extractor's resolved settings under that name, beside slam:, and --config does not read "
            f"them); {HINT.format(nested)}\n")


def test_every_and_rate_hz_together_are_refused_before_any_work(sim_folder, tmp_path, capsys):
    """`lmsbench slam RUN --every 2 --rate-hz 5` kept the scans by the rate alone (the --every was ignored,
    exit 0, and config.yaml records neither). Each chooses the scans kept: given together they are refused,
    one line, exit 2, no output folder made; the library's load_input likewise."""
    from experiments.cli import main
    from experiments.slamrun import load_input

    message = ("--every 2 and --rate-hz 5 both choose the scans kept (every N-th scan, or about that many a second "
               "by the stamps); give one of them")
    assert main(["slam", str(sim_folder), "--every", "2", "--rate-hz", "5", "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [f"lmsbench slam: error: {message}"]
    assert not (tmp_path / "o").exists()
    with pytest.raises(LmsbenchError, match=re.escape(message)):
        load_input(sim_folder, every=2, rate_hz=5.0)
    every = [r.scan.stamp for r in load_input(sim_folder).records]  # 6 s at the default 37.5 scans/s: 225
    kept = [r.scan.stamp for r in load_input(sim_folder, every=1, rate_hz=5.0).records]  # --every 1 is none given
    assert len(every) == 225 and 29 <= len(kept) <= 31 and set(kept) <= set(every)


def test_a_runs_record_says_which_scans_ran(sim_folder, tmp_path, capsys):
    """A review: config.yaml and metrics.json named the files read but not --every, --rate-hz or --max-scans,
    so a run's record did not say which of the log's scans it ran on. Their input: says it."""
    from experiments.cli import main
    from lms200.yamlio import load

    for flags, kept in ((["--every", "3", "--max-scans", "40"], "40 of the 118 read: one in 3 (--every), at most 40 "
                         "(--max-scans)"), (["--rate-hz", "5"], "29 of the 225 read: the first at least 1/5 s after the last "
                                                              "kept (--rate-hz)")):
        out = tmp_path / flags[0].strip("-")
        assert main(["slam", str(sim_folder), *flags, "--out", str(out), "--quiet", "--no-paper-baseline"]) == 0
        assert load((out / "config.yaml").read_text())["input"]["scans_kept"] == kept
        assert json.loads((out / "metrics.json").read_text())["input"]["scans_kept"] == kept
