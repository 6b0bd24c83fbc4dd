"""`lmsbench info` and `lmsbench demo` through the command-line entry point."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from experiments.cli import main
from lms200 import LmsbenchError


@pytest.mark.shared_data
def test_info_json_on_intel(shared_data: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["info", str(shared_data / "intel-corrected.log.gz"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["scans"] == 910 and info["beams"] == 180 and info["beams_min"] == info["beams_max"] == 180
    assert info["fov_deg"] == pytest.approx(179.0) and info["resolution_deg"] == pytest.approx(1.0)
    assert info["duration_s"] == pytest.approx(2650.8632, abs=1e-3)
    assert info["scan_rate_hz"] == pytest.approx(909 / 2650.8632, rel=1e-6)
    assert 0.02 < info["no_return_fraction"] < 0.03 and info["invalid_fraction"] == 0.0
    assert info["odometry"] is True and info["truth"] is False
    assert info["stamps_back"] == 4  # scans 295, 601, 627, 725 are stamped 0.05-0.86 s before the previous one (slam --skip-bad-lines skips 294, 600, 626, 724)


def test_info_errors_are_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["info", str(tmp_path / "missing.clf")]) == 2
    assert "no such log" in capsys.readouterr().err
    bad = tmp_path / "bad.clf"
    bad.write_text("FLASER 361 1 2 3\n")
    assert main(["info", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "bad.clf:1:" in err and err.count("\n") == 1


@pytest.mark.parametrize("content", [b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00\x00", b'{"walls": [[0, 0, 1, 1]]}\n', b""])
def test_info_on_a_file_without_laser_messages_is_an_error(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                           content: bytes) -> None:
    path = tmp_path / "notalog.png"
    path.write_bytes(content)
    assert main(["info", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"lmsbench info: error: {path}") and err.count("\n") == 1
    # a binary or empty file is refused by its content before reading; a text file by its lines
    # (none starts with a CARMEN message name: the reader's own error, which said nothing before)
    assert any(s in err for s in (": not a CARMEN log", "a binary file", "empty file")), err


def test_info_json_numbers_are_numbers(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from lms200 import Record, Scan, write_log

    scans = [Scan.lms200(np.full(361, 2.0), stamp=0.5 * k) for k in range(3)]
    scans.append(Scan(np.full(181, 3.0), -np.pi / 2, np.pi / 180, scans[0].range_min, scans[0].range_max, stamp=1.5))
    write_log(tmp_path / "mixed.clf", [Record(s) for s in scans])
    assert main(["info", str(tmp_path / "mixed.clf"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["scans"] == 4 and info["beams"] is None and (info["beams_min"], info["beams_max"]) == (181, 361)
    assert info["duration_s"] == pytest.approx(1.5) and info["scan_rate_hz"] == pytest.approx(2.0)
    assert info["stamps_back"] == 0
    write_log(tmp_path / "alike.clf", [Record(s.replace(stamp=2.0)) for s in scans[:3]])  # it said "0.00 scans/s"
    assert main(["info", str(tmp_path / "alike.clf")]) == 0
    assert "scan rate       unknown (every scan stamped alike)\n" in capsys.readouterr().out
    write_log(tmp_path / "back.clf", [Record(s.replace(stamp=t)) for s, t in zip(scans[:3], (0.0, 1.0, 0.5))])
    assert main(["info", str(tmp_path / "back.clf")]) == 0
    assert "time order      1 scan stamped before the previous one (slam needs --skip-bad-lines)" in capsys.readouterr().out
    write_log(tmp_path / "one.clf", [Record(s) for s in scans[:3]])
    assert main(["info", str(tmp_path / "one.clf"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["beams"] == 361 and isinstance(info["fov_deg"], float) and info["fov_deg"] == pytest.approx(180.0)
    # docs/commands.md's list of the keys names every key --json gives (it lacked laser_mount and laser_mount_changes)
    doc = (Path(__file__).resolve().parents[1] / "docs" / "commands.md").read_text()
    keys = doc[doc.index("Its keys (`experiments.loginfo.LogSummary`)"):doc.index("A command whose output's reader")]
    assert not [k for k in info if f"`{k}`" not in keys], [k for k in info if f"`{k}`" not in keys]
    # invalid readings: nan, 0 m (a logger's missing reading) and finite ones out of limits, not +inf
    r = np.full(361, 2.0)
    r[:10], r[10:30], r[30:31], r[31:36] = np.nan, 0.0, 9.0, np.inf
    write_log(tmp_path / "bad.clf", [Record(scans[0].replace(ranges=r))])
    assert main(["info", str(tmp_path / "bad.clf"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["invalid_fraction"] == pytest.approx(31 / 361) and info["no_return_fraction"] == pytest.approx(5 / 361)


def test_os_errors_are_one_line_with_exit_status_2(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    afile = tmp_path / "afile"
    afile.write_text("")
    # an output folder under a regular file: NotADirectoryError from mkdir
    assert main(["simulate", "--duration", "0.1", "--out", str(afile / "x")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("lmsbench simulate: error: ") and err.count("\n") == 1 and "afile" in err
    # an unreachable scheduler: distributed raises OSError("Timed out trying to connect ...")
    import experiments.sweep.runner as runner

    def unreachable(executor, workers):
        raise OSError(f"Timed out trying to connect to {executor} after 10 s")

    monkeypatch.setattr(runner, "sweep_client", unreachable)
    spec = tmp_path / "s.yaml"
    spec.write_text("kind: extract\ngrid:\n  method: [sensor]\n")
    assert main(["sweep", str(spec), "--scheduler", "tcp://127.0.0.1:1", "--no-progress",
                 "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err == "lmsbench sweep: error: Timed out trying to connect to tcp://127.0.0.1:1 after 10 s\n"


def test_keyboard_interrupt_exits_130(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    import experiments.commands.info as info

    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(info, "run", interrupted)
    assert main(["info", "whatever.clf"]) == 130
    assert "lmsbench info: interrupted" in capsys.readouterr().err


def test_bench_with_an_unknown_name_is_a_one_line_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from experiments.commands.bench import discover

    assert main(["bench", "nosuch", "--out", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    # it read "unknown benchmark(s) ['nosuch']; available: ['baselines', ...]", Python's list syntax
    assert err == f"lmsbench bench: error: unknown benchmark(s) nosuch; known: {', '.join(discover())}\n"
    assert "features, lms200" in err
    assert not (tmp_path / "b").exists()
    assert main(["bench", "", "--out", str(tmp_path / "b")]) == 2  # an empty name was shown as nothing
    assert capsys.readouterr().err.startswith("lmsbench bench: error: unknown benchmark(s) ''; known: ")
    assert main(["bench", " sim", "--out", str(tmp_path / "b")]) == 2  # it said "unknown benchmark(s) sim"
    assert capsys.readouterr().err.startswith("lmsbench bench: error: unknown benchmark(s) ' sim'; known: ")
    assert main(["bench", "--help"]) == 0  # the areas are named before a user has to guess one
    assert f"{', '.join(discover())} (default: all)" in " ".join(capsys.readouterr().out.split())


@pytest.mark.parametrize("command, flag, dest, value", [
    (["compare", "office"], ["--rate-hz", "4"], "rate", 4.0),
    (["compare", "office"], ["--quiet"], "no_progress", True),
    (["sweep", "s.yaml"], ["--quiet"], "no_progress", True),
    (["simulate", "--out", "o"], ["--no-progress"], "quiet", True),
    (["slam", "run", "--out", "o"], ["--no-progress"], "quiet", True),
    # `slam LOG --stride 4` (compare, calibrate and sim2real thin a log so) and `figures --log LOG`
    # (demo's name for Fig. 9's log) were 'unrecognized arguments' too
    (["slam", "run", "--out", "o"], ["--stride", "4"], "every", 4),
    (["figures"], ["--log", "x.clf"], "intel", Path("x.clf")),
])
def test_the_rate_and_progress_options_take_the_other_commands_spelling(command, flag, dest, value) -> None:
    """`lmsbench compare office --rate-hz 4` (simulate, demo, figures and sim2real spell it so) was
    'unrecognized arguments'; so were `slam ... --no-progress` and `sweep ... --quiet`, the progress
    switch of the other commands. Each now takes both spellings of both."""
    from experiments.cli import build_parser

    args = build_parser().parse_args(command + flag)
    assert getattr(args, dest) == value


def test_the_research_scripts_docs_name_answer_help_without_running(capsys: pytest.CaptureFixture[str],
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    """`python -m experiments.benchmarks.features --help` (docs/features.md's accuracy table) ignored
    --help and ran the whole table; `python -m experiments.slameval --help` (docs/slam.md) showed a
    description cut mid-sentence ("..., a long") and options with no word of help or default, and built
    its parser by importing the simulator (0.5 s; its --duration bound is now from lms200.timing)."""
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[1]
    bench = subprocess.run([sys.executable, "-m", "experiments.benchmarks.features", "--help"], cwd=root,
                           capture_output=True, text=True, timeout=120)
    assert bench.returncode == 0 and "usage: python -m experiments.benchmarks.features" in bench.stdout
    assert "world=office" not in bench.stdout
    from experiments import slameval

    for name in ("sim", "sim.records", "sim.sensor"):  # importing any of them fails
        monkeypatch.setitem(sys.modules, name, None)
    with pytest.raises(SystemExit) as stop:
        slameval.main(["--help"])
    assert stop.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "paper preset against the default." in text and "(default 0-20)" in text and "(default 90)" in text
    assert f"at least {slameval.min_duration():g}: two scans at 5 scans/s" in text


@pytest.mark.parametrize("given, message", [
    (["--long", "1e-400"], "argument --long: must be a finite number >= 0 and <= 3600 s, got '1e-400': 1e-400 rounds "
                           "to 0 in float64"),
    (["--duration", "1e-400"], "argument --duration: must be a finite number >= {shortest} and <= 3600 s, got '1e-400': "
                               "1e-400 rounds to 0"),
    (["--duration", "0.2"], "argument --duration: must be a finite number >= {shortest} and <= 3600 s, got '0.2'"),
    (["--long", "1e-3"], "argument --long: must be a finite number >= 0.1 and <= 3600 s, got '1e-3' (or 0: no "
                         "consistency run)"),
    (["--seeds", "5-2"], "argument --seeds: must be a seed or a range LO-HI of seeds with LO <= HI, got '5-2'"),
    (["--seeds", "0-99999999999"], "argument --seeds: must be a seed or a range LO-HI of seeds (0-20), got '0-99999999999': "
                                   "each must be a whole number >= 0 and <= 4294967295"),
    (["--seeds", "0-1000"], "argument --seeds: at most 1000 seeds, got '0-1000' (1,001)"),
    (["--seeds", "3-"], "argument --seeds: must be a seed or a range LO-HI of seeds (0-20), got '3-': no HI"),
])
def test_the_slam_evaluations_options_are_checked_as_the_commands_are(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                                      given: list[str], message: str) -> None:
    """`python -m experiments.slameval --long 1e-400` read 0 ("no consistency run") and ran without it, exit 0;
    `--duration 1e-400` and `--long 1e-3` failed inside the simulator (a traceback), `--duration 0.2` after its
    runs ("ate: fewer than 2 estimated poses"); `--seeds 0-99999999999` was a MemoryError, `--seeds 3-` ran seed 3,
    One line, exit 2, nothing run."""
    from experiments import slameval

    with pytest.raises(SystemExit) as stop:
        slameval.main(["--out", str(tmp_path / "o"), *given])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    message = message.format(shortest=f"{slameval.min_duration():g}")
    assert err.startswith(f"python -m experiments.slameval: error: {message}") and err.count("\n") == 1, err
    assert not (tmp_path / "o").exists()


def test_the_slam_evaluations_shortest_duration_keeps_two_scans_at_each_rate(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """--duration's minimum is the shortest run that keeps two scans at each rate (the ATE's fewest), as the
    simulator keeps them, and a run of it leaves only its own outputs in an earlier run's folder; an existing
    file as --out was a FileExistsError traceback, `--out ""` wrote into the current folder: one line, exit 2."""
    import argparse

    from experiments import slameval
    from experiments.options import MAX_DURATION_S, SLAMEVAL_OWNER
    from experiments.provenance import read_parquet
    from lms200.yamlio import load as load_yaml
    from sim import SensorConfig, simulate_records
    from sim.records import scan_stamps

    sensor = SensorConfig()  # the simulator's value, which the parser took from it (importing it: 0.5 s a build)
    assert (sensor.n_beams, sensor.resolution) == (slameval.SIM_BEAMS, slameval.SIM_RESOLUTION_RAD)
    for rates in [slameval.RATES_HZ, (37.5,), (5.0,), (1.0,), (20.0, 3.0), (0.01,)]:
        need = max(float(scan_stamps(sensor, MAX_DURATION_S, rate)[1]) for rate in rates) + sensor.beam_time_offsets.max()
        assert slameval.min_duration(rates) == math.ceil(need * 100 - 1e-6) / 100, rates
    for rate in (1 / 3600, 0.0):  # a run of the longest keeps one scan: 3600.02 s was given for the first
        assert len(scan_stamps(sensor, MAX_DURATION_S, rate or 1e-300)) == 1
        with pytest.raises(LmsbenchError, match=f"^min_duration: at {rate:g} scans/s no simulated run of at most 3600 s "
                                                "keeps two scans"):
            slameval.min_duration((5.0, rate))
    shortest = slameval.min_duration()
    # the run at the shortest duration, into an earlier run's folder (told by its slameval.yaml): an earlier
    # long.parquet and mit.parquet stayed beside the tables of a run that wrote neither (`--long 0`, no MIT log),
    # read as this run's; its own outputs are what is left
    out = tmp_path / "eval"
    out.mkdir()
    for name in slameval.OUTPUTS:
        (out / name).write_text("an earlier run's\n")
    (out / slameval.RECORD).write_text(slameval.record(argparse.Namespace(seeds=[0, 1], duration=1.0, long=0.0,
                                                                          mit=None)))
    # no --mit, and no log where the default looks: said on stderr (the run passed over it in silence)
    monkeypatch.setattr(slameval, "MIT_LOG", tmp_path / "shared" / "mit-csail.clf.gz")
    assert slameval.main(["--out", str(out), "--seeds", "0", "--long", "0", "--duration", f"{shortest:g}"]) == 0
    assert sorted(p.name for p in out.iterdir()) == sorted([slameval.RECORD, "sim.parquet", "tables.md"])
    assert SLAMEVAL_OWNER.told(out) == {slameval.RECORD}
    assert load_yaml((out / slameval.RECORD).read_text())["seeds"] == "0"
    table = read_parquet(out / "sim.parquet")  # two scans or more at each rate (the simulator's, as run)
    assert sorted(table.rate_hz) == sorted(slameval.RATES_HZ) and set(table.seed) == {0} and table.scans.min() >= 2
    said = capsys.readouterr()
    assert (out / "tables.md").read_text().strip() in said.out
    assert said.err == (f"no MIT CSAIL log at {tmp_path / 'shared' / 'mit-csail.clf.gz'}: no MIT CSAIL run (give --mit "
                        "LOG, or --mit none to say so)\n")
    assert load_yaml((out / slameval.RECORD).read_text())["mit"] is None
    assert len(simulate_records("office", seed=0, duration=shortest - 0.01, rate_hz=min(slameval.RATES_HZ))) == 1
    (tmp_path / "f").write_text("mine\n")
    with pytest.raises(SystemExit) as stop:
        slameval.main(["--out", str(tmp_path / "f"), "--seeds", "0", "--long", "0", "--mit", "none"])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith(f"python -m experiments.slameval: error: --out {tmp_path / 'f'}: exists and is not a folder"), err
    assert (tmp_path / "f").read_text() == "mine\n"
    with pytest.raises(SystemExit) as stop:  # it wrote into the current folder
        slameval.main(["--out", "", "--seeds", "0"])
    assert stop.value.code == 2
    assert capsys.readouterr().err.startswith("python -m experiments.slameval: error: argument --out: empty path ''")


def test_the_slam_evaluation_replaces_only_an_earlier_runs_outputs(tmp_path: Path,
                                                                   capsys: pytest.CaptureFixture[str]) -> None:
    """A user's own long.parquet (or slameval.yaml) in --out was removed by its name alone: a file of its output
    names is replaced only beside the slameval.yaml an earlier run wrote (options.SLAMEVAL_OWNER), else refused and
    kept (the --mit given is no log: a run that got past the check would fail there, fast, with another line)."""
    import argparse

    from experiments import slameval

    bad = tmp_path / "bad.log"
    bad.write_text("hello\n")
    earlier = slameval.record(argparse.Namespace(seeds=[0, 1], duration=1.0, long=0.0, mit=bad))
    for mine in [{"long.parquet": "mine\n"}, {"slameval.yaml": "command: mine\n", "tables.md": "mine\n"},
                 {"slameval.yaml": earlier.replace("experiments.slameval\n", "experiments.other\n", 1)}]:
        out = tmp_path / f"eval{len(mine)}{len(mine[next(iter(mine))])}"
        out.mkdir()
        for name, text in mine.items():
            (out / name).write_text(text)
        with pytest.raises(SystemExit) as stop:
            slameval.main(["--out", str(out), "--seeds", "0", "--long", "0", "--mit", str(bad)])
        assert stop.value.code == 2
        shown = " and ".join(mine)
        said = (f" (its record {out / 'slameval.yaml'} is not one such a run leaves: its command: is 'mine', not "
                "'python -m experiments.slameval')" if "tables.md" in mine else "")
        assert capsys.readouterr().err.startswith(
            f"python -m experiments.slameval: error: --out {out}: holds {shown}, which this run would replace but no "
            f"earlier python -m experiments.slameval run wrote{said}; give a new or empty folder"), mine
        assert {p.name: p.read_text() for p in out.iterdir()} == mine
    # a folder written before slameval.yaml, told by its sim.parquet's columns, was refused as no earlier run's:
    # it passes the folder's check (and the log given, no log, is refused after it)
    import pandas as pd

    old = tmp_path / "before-record"
    old.mkdir()
    pd.DataFrame({"seed": [0], "rate_hz": [5.0], "ate_rmse_m": [0.01], "cpu_scans_per_s": [900.0]}).to_parquet(
        old / "sim.parquet")
    (old / "tables.md").write_text("| seed |\n")
    with pytest.raises(SystemExit) as stop:
        slameval.main(["--out", str(old), "--seeds", "0", "--long", "0", "--mit", str(bad)])
    assert stop.value.code == 2
    assert capsys.readouterr().err.startswith(f"python -m experiments.slameval: error: {bad}: not a CARMEN log")
    assert sorted(p.name for p in old.iterdir()) == ["sim.parquet", "tables.md"]


def test_the_slam_evaluation_reads_its_log_before_it_removes_an_earlier_runs_outputs(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A --mit file that is no log (or a log without its relations, a TypeError traceback after the runs) was
    refused after the folder's earlier outputs, hours of runs, were removed: it is read first, and they stay."""
    import argparse

    from experiments import slameval

    out = tmp_path / "eval"
    out.mkdir()
    for name in slameval.OUTPUTS:
        (out / name).write_text("an earlier run's\n")
    earlier = slameval.record(argparse.Namespace(seeds=[0], duration=1.0, long=0.0, mit=None))
    (out / slameval.RECORD).write_text(earlier)
    bad, bare = tmp_path / "bad.log", tmp_path / "bare.log"
    bad.write_text("hello\n")
    bare.write_text("".join(f"FLASER 181 {' '.join(['2.00'] * 181)} 0 0 0 0 0 0 {t:g} host {t:g}\n" for t in (0, 0.2, 0.4)))
    gone = tmp_path / "mit-csail.clf.gz"  # a log given that is not there was passed over, and no MIT CSAIL table written
    for log, says in [(bad, f"{bad}: not a CARMEN log"), (bare, f"--mit {bare}: no relations file beside it"),
                      (gone, f"argument --mit: {gone}: no such log (give 'none' for no MIT CSAIL run)"),
                      # a name beyond NAME_MAX was an OSError traceback ("File name too long")
                      (tmp_path / ("x" * 300), f"argument --mit: {tmp_path / ('x' * 300)}: file name too long")]:
        with pytest.raises(SystemExit) as stop:
            slameval.main(["--out", str(out), "--seeds", "0", "--long", "0", "--mit", str(log)])
        assert stop.value.code == 2
        assert capsys.readouterr().err.startswith(f"python -m experiments.slameval: error: {says}")
        assert {p.name: p.read_text() for p in out.iterdir()} == {**dict.fromkeys(slameval.OUTPUTS, "an earlier run's\n"),
                                                                  slameval.RECORD: earlier}


def test_a_missing_input_names_the_file_it_was_likely_meant_to_be(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                   capsys: pytest.CaptureFixture[str]) -> None:
    """`lmsbench info ../shared/data/carmen/mit-csail.clf` (the file is mit-csail.clf.gz) said
    "no such log" and no more; so did a one-letter slip (`intel-corected`). Now the message names the
    compressed file or the close name beside it; a name with nothing near gets no guess."""
    (tmp_path / "mit-csail.clf.gz").write_bytes(b"")
    (tmp_path / "intel-corrected.log").write_text("")
    (tmp_path / "k_vs_noise.yaml").write_text("")
    monkeypatch.chdir(tmp_path)
    for argv, said in ((["info", "mit-csail.clf"], "mit-csail.clf: no such log (did you mean mit-csail.clf.gz?)"),
                       (["info", str(tmp_path / "intel-corected.log")],
                        f"{tmp_path / 'intel-corected.log'}: no such log (did you mean {tmp_path / 'intel-corrected.log'}?)"),
                       (["slam", "mit-csail.clf", "--out", "o"], "mit-csail.clf: no such input (did you mean mit-csail.clf.gz?)"),
                       (["sweep", "k_vs_nois.yaml"], "k_vs_nois.yaml: no such file (did you mean k_vs_noise.yaml?)"),
                       (["info", "other.bag"], "other.bag: no such log")):
        assert main(argv) == 2
        assert capsys.readouterr().err == f"lmsbench {argv[0]}: error: {said}\n"


def test_info_says_when_scans_repeat_the_stamp_before_them(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The wrong-input hunt (duplicated stamps): a log of every line twice, or of three scans of one
    stamp, said 'time order      yes' and nothing else (the scan rate read as the lines'). Now the
    time order line counts the scans stamped like the one before (``stamps_repeated`` in --json)."""
    from lms200 import Record, Scan, write_log

    scans = [Scan.lms200(np.full(361, 2.0 + k), stamp=0.5 * k) for k in range(3)]
    write_log(tmp_path / "twice.clf", [Record(s) for s in scans for _ in range(2)])
    assert main(["info", str(tmp_path / "twice.clf")]) == 0
    out = capsys.readouterr().out
    assert ("time order      yes; 3 scans stamped like the previous one (the same scan twice, or a coarse clock)"
            in out.splitlines()[-2])  # old: "time order      yes"
    write_log(tmp_path / "back.clf", [Record(s.replace(stamp=t)) for s, t in zip(scans, (1.0, 1.0, 0.5))])
    assert main(["info", str(tmp_path / "back.clf"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert (info["stamps_back"], info["stamps_repeated"]) == (1, 1)
    write_log(tmp_path / "ok.clf", [Record(s) for s in scans])
    assert main(["info", str(tmp_path / "ok.clf")]) == 0
    assert "  time order      yes\n" in capsys.readouterr().out


def test_info_says_on_how_many_scans_odometry_or_truth_is_when_not_on_all(tmp_path: Path,
                                                                          capsys: pytest.CaptureFixture[str]) -> None:
    """Found by fuzzing: a log (or a bag whose poses came late) with odometry on 1 of its 40 scans
    said 'odometry yes', as a log of odometry on every scan; slam --odometry then refused it (39 of
    the 40 scans have none). The text says how many scans have it; --json gives the counts."""
    from lms200 import Record, Scan, write_log

    recs = [Record(Scan(np.full(181, 2.0), -np.pi / 2, np.pi / 180, 0.0, 8.0, stamp=1.0 + 0.1 * k),
                   odom=(0.1 * k, 0.0, 0.0) if k < 3 else None, truth=(0.0, 0.0, 0.0) if k == 5 else None) for k in range(40)]
    write_log(tmp_path / "part.clf", recs)
    assert main(["info", str(tmp_path / "part.clf")]) == 0
    out = capsys.readouterr().out
    assert "  odometry        yes, on 3 of 40 scans\n" in out and "  true poses      yes, on 1 of 40 scans\n" in out
    assert main(["info", str(tmp_path / "part.clf"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert (info["odometry"], info["odometry_scans"], info["truth"], info["truth_scans"]) == (True, 3, True, 1)
    write_log(tmp_path / "all.clf", [Record(r.scan, odom=(0.0, 0.0, 0.0)) for r in recs])
    assert main(["info", str(tmp_path / "all.clf")]) == 0
    out = capsys.readouterr().out
    assert "  odometry        yes\n" in out and "  true poses      no\n" in out


def test_the_slam_evaluation_checks_a_given_mit_log_once(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    """An explicit `--mit LOG` had its head read twice: check_log when parsed, then again in read_mit.
    Now read_mit reads the log check_log returned at parse; the default log (not parsed) is still checked there."""
    import experiments.options
    from experiments import slameval

    heads: list[Path] = []
    real = experiments.options._head
    monkeypatch.setattr(experiments.options, "_head", lambda p, *a, **k: heads.append(Path(p)) or real(p, *a, **k))
    bare = tmp_path / "bare.log"
    bare.write_text("".join(f"FLASER 181 {' '.join(['2.00'] * 181)} 0 0 0 0 0 0 {t:g} host {t:g}\n" for t in (0, 0.2, 0.4)))
    with pytest.raises(SystemExit) as stop:  # read, then refused for its missing relations: no run
        slameval.main(["--out", str(tmp_path / "eval"), "--seeds", "0", "--long", "0", "--mit", str(bare)])
    assert stop.value.code == 2
    assert capsys.readouterr().err.startswith(f"python -m experiments.slameval: error: --mit {bare}: no relations file")
    assert heads == [bare]
    heads.clear()
    monkeypatch.setattr(slameval, "MIT_LOG", bare)  # the default: checked once, in read_mit
    with pytest.raises(SystemExit):
        slameval.main(["--out", str(tmp_path / "eval"), "--seeds", "0", "--long", "0"])
    assert heads == [bare]
    assert capsys.readouterr().err.startswith(f"python -m experiments.slameval: error: --mit {bare}: no relations file")
