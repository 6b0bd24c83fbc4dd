"""A ``lmsbench simulate`` folder is a log for every command that reads one (README: "slam, info,
compare, sim2real and figures --log" read it): slam and compare took it, but info, calibrate,
sim2real, figures --log, demo --log and lms200 emulate --log said "DIR is a folder but not a ROS 2
bag (no metadata.yaml)". One function (options.simulate_log, through options.check_log) resolves
it for all; a folder that is neither kind says what was expected."""

from __future__ import annotations

from pathlib import Path

import pytest

from experiments.cli import main
from lms200 import LmsbenchError


@pytest.fixture(scope="module")
def sim_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("simfolder") / "run"
    assert main(["simulate", "--duration", "1", "--rate-hz", "4", "--out", str(out), "--quiet"]) == 0
    return out


class _Reached(LmsbenchError):
    """Raised in place of a command's work: it got past its input checks with this log."""


def _stop_with(monkeypatch: pytest.MonkeyPatch, target: object, name: str, seen: list) -> None:
    def stop(*args, **kwargs):
        seen.append(next((a for a in (*args, *kwargs.values()) if "scans.clf" in str(a)), args))
        raise _Reached("reached the work")

    monkeypatch.setattr(target, name, stop)


def test_info_reads_a_simulate_folder(sim_folder: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["info", str(sim_folder / "scans.clf"), "--json"]) == 0
    direct = capsys.readouterr().out
    assert main(["info", str(sim_folder), "--json"]) == 0
    assert capsys.readouterr().out == direct and '"scans": 5' in direct
    assert main(["info", str(sim_folder)]) == 0
    assert capsys.readouterr().out.splitlines()[0] == str(sim_folder / "scans.clf")  # what it read


@pytest.mark.parametrize("argv, module, name", [
    (["calibrate", "{sim}"], "experiments.calibrate", "calibrate_log"),
    (["sim2real", "{sim}", "--out", "{tmp}/s2r"], "experiments.sim2real", "sim2real"),
    (["figures", "--log", "{sim}", "--out", "{tmp}/figs"], "experiments.figures.study", "run_study"),
    (["demo", "--log", "{sim}", "--out", "{tmp}/demo"], "experiments.demo", "run_demo"),
    (["lms200", "emulate", "--log", "{sim}", "--duration", "0.1"], "experiments.commands.lms200", "log_scans"),
])
def test_every_command_that_reads_a_log_takes_a_simulate_folder(sim_folder, tmp_path, monkeypatch, capsys,
                                                                 argv, module, name) -> None:
    import importlib

    seen: list = []
    _stop_with(monkeypatch, importlib.import_module(module), name, seen)
    words = [w.format(sim=sim_folder, tmp=tmp_path) for w in argv]
    assert main(words) == 2
    err = capsys.readouterr().err
    assert err.endswith("error: reached the work\n"), err  # past every check of the input
    reached = seen[0]
    read = reached.intel_log if hasattr(reached, "intel_log") else reached  # figures / demo: the study's config
    if isinstance(read, tuple):  # run_demo(out, cfg, ...)
        read = next(a.intel_log for a in read if hasattr(a, "intel_log"))
    assert Path(read) == sim_folder / "scans.clf"


@pytest.mark.parametrize("argv", [
    ["info", "{d}"], ["calibrate", "{d}"], ["sim2real", "{d}", "--out", "{tmp}/s2r"], ["slam", "{d}", "--out", "{tmp}/sl"],
    ["compare", "{d}", "--out", "{tmp}/cmp"], ["figures", "--log", "{d}", "--out", "{tmp}/figs"],
    ["lms200", "emulate", "--log", "{d}", "--duration", "0.1"],
])
def test_a_folder_of_neither_kind_says_what_was_expected(tmp_path, capsys, argv) -> None:
    folder = tmp_path / "notes"
    folder.mkdir()
    (folder / "readme.txt").write_text("not a log\n")
    assert main([w.format(d=folder, tmp=tmp_path) for w in argv]) == 2
    err = capsys.readouterr().err
    assert err.endswith(f"error: {folder} is a folder but neither a ROS 2 bag (no metadata.yaml) nor a lmsbench "
                        "simulate folder (no scans.clf)\n"), err
    assert err.count("\n") == 1


def test_read_log_of_a_simulate_folder_names_its_log(sim_folder: Path) -> None:
    """The library's read_log said "DIR is a folder but not a ROS 2 bag (no metadata.yaml)" for the
    folder every command takes: it is still refused (lms200 does not know the command line's folders,
    nor its check that the run finished), but the message says which file to read instead."""
    from lms200 import read_log
    from lms200.errors import LogNotFoundError

    log = sim_folder / "scans.clf"
    with pytest.raises(LogNotFoundError) as info:
        read_log(sim_folder)
    message = str(info.value)
    assert message == (f"{sim_folder} is a folder, not a log: it holds scans.clf, as a lmsbench simulate output folder "
                       f"does; read_log({str(log)!r}) reads its scans (`lmsbench info {sim_folder}` also checks that "
                       "its run finished)")
    assert "\n" not in message and len(list(read_log(log))) == 5
