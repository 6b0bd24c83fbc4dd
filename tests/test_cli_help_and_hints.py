"""What the command line tells a new user: help texts that list every world (compare --help listed
five of seven), "did you mean" for a near miss of a command's option, and ``lmsbench --version``."""

from __future__ import annotations

import re
import subprocess
import sys
from importlib import metadata

import pytest

from experiments.cli import main
from sim import WORLD_NAMES

WORLD_HELP = [["compare"], ["simulate"], ["demo"], ["figures"], ["sim2real"], ["calibrate"], ["lms200", "emulate"]]


@pytest.mark.parametrize("command", WORLD_HELP, ids=" ".join)
def test_help_lists_every_world(command: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    assert main([*command, "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())  # argparse wraps the lines
    listed = ", ".join(WORLD_NAMES)
    assert listed in text, text
    assert "{worlds}" not in text


def test_building_the_parsers_imports_neither_the_simulator_nor_numba() -> None:
    """The world names are read when a help is shown, not when every command's parser is built."""
    code = ("import sys; from experiments.cli import build_parser; build_parser(); "
            "print(sorted(m for m in ('sim', 'numba') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


SEED = "--seed is an option of: demo, figures, lms200 emulate, simulate; "


@pytest.mark.parametrize("argv, hint, elsewhere", [
    (["compare", "office", "--seed", "1"], "--seed 1; did you mean --seeds?", SEED),  # simulate's spelling
    (["simulate", "--out", "x", "--seeds", "1"], "--seeds 1; did you mean --seed?",
     "--seeds is an option of: compare, sim2real; "),  # compare's spelling
    (["compare", "office", "--seed=1"], "--seed=1; did you mean --seeds?", SEED),
    (["compare", "office", "-seeds", "1"], "-seeds 1; did you mean --seeds?", ""),
    (["compare", "office", "--dur", "3"], "--dur 3; did you mean --duration?", ""),  # the start of one option
    (["slam", "x", "--out", "y", "--extracter", "sensor"], "--extracter sensor; did you mean --extractor?", ""),
    (["lms200", "emulate", "--tpc", "3"], "--tpc 3; did you mean --tcp?", ""),  # two letters swapped
    (["compare", "office", "--seed", "1", "--ot", "x"], "--seed 1 --ot x; did you mean --seeds for --seed, --out for --ot?", SEED),
])
def test_an_unrecognized_option_near_a_real_one_says_which(argv, hint, elsewhere, capsys) -> None:
    assert main(argv) == 2
    command = " ".join(w for w in argv[:2] if not w.startswith("-") and w in ("compare", "simulate", "slam", "lms200", "emulate"))
    assert capsys.readouterr().err == f"lmsbench {command}: error: unrecognized arguments: {hint} ({elsewhere}see lmsbench {command} --help)\n"


@pytest.mark.parametrize("argv, message", [
    (["lms200", "emulate", "--max-scans", "3"], "lmsbench lms200 emulate: error: unrecognized arguments: --max-scans 3 "
     "(--max-scans is an option of: calibrate, compare, lms200 record, sim2real, slam; see lmsbench lms200 emulate --help)"),
    (["info", "x", "--max-scans=3", "--seed", "2", "--bogus"], "lmsbench info: error: unrecognized arguments: --max-scans=3 "
     "--seed 2 --bogus (--max-scans is an option of: calibrate, compare, lms200 record, sim2real, slam; " + SEED +
     "see lmsbench info --help)"),
    (["simulate", "--methods", "sensor", "--out", "x"], "lmsbench simulate: error: unrecognized arguments: --methods sensor "
     "(--methods is an option of: compare, figures; see lmsbench simulate --help)"),
    (["info", "x", "--version"], "lmsbench info: error: unrecognized arguments: --version (--version is an option of "
     "lmsbench itself, given before the command; see lmsbench info --help)"),
])
def test_an_option_of_another_command_names_the_commands_that_take_it(argv, message, capsys) -> None:
    """`lmsbench lms200 emulate --max-scans 3` said only "unrecognized arguments": the option is
    another command's, and the one line now says whose."""
    assert main(argv) == 2
    assert capsys.readouterr().err == message + "\n"


@pytest.mark.parametrize("argv", [["compare", "office", "--bogus"], ["compare", "office", "--o", "x"], ["--bogus", "compare", "office"]])
def test_an_option_near_none_gets_no_guess(argv, capsys) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "unrecognized arguments:" in err and "did you mean" not in err


def test_version_names_the_installed_package_and_the_checkouts_commit(capsys) -> None:
    from experiments.provenance import CHECKOUT

    assert main(["--version"]) == 0
    out = capsys.readouterr().out
    assert re.fullmatch(rf"lmsbench {re.escape(metadata.version('lmsbench'))}( \(git [0-9a-f]{{12}}(, modified)?\))?\n", out), out
    if (CHECKOUT / ".git").exists():  # make test runs in a checkout: its commit is named
        head = subprocess.run(["git", "-C", str(CHECKOUT), "rev-parse", "--short=12", "HEAD"], capture_output=True,
                              text=True).stdout.strip()
        assert f"(git {head}" in out


def test_version_outside_a_checkout_is_the_package_version_alone(tmp_path, monkeypatch, capsys) -> None:
    import experiments.provenance as provenance

    monkeypatch.setattr(provenance, "CHECKOUT", tmp_path)  # an installed wheel: no .git beside the code
    assert main(["--version"]) == 0
    assert capsys.readouterr().out == f"lmsbench {metadata.version('lmsbench')}\n"


def test_version_is_cheap_it_loads_neither_numba_nor_the_simulator() -> None:
    code = ("import sys; from experiments.cli import main; status = main(['--version']); "
            "print(status, sorted(m for m in ('sim', 'numba') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.splitlines()[-1] == "0 []"


def test_compare_help_says_what_each_poses_choice_does(capsys) -> None:
    """--poses {auto,corrected,none}: the help said what auto and none do, not corrected."""
    assert main(["compare", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "auto (default): when the file name says 'corrected'" in text
    assert "corrected: always (a log without such anchors: its odometry taken as corrected poses)" in text
    assert "none: never" in text


@pytest.mark.parametrize("argv, hint", [
    (["compare", "office", "--seeds", "0-2"], "got '0-2'; the seeds are listed one by one, not as a range: 0 1 2 "),
    (["sim2real", "x.clf", "--seeds", "40-63"],
     "got '40-63'; the seeds are listed one by one, not as a range: $(seq 40 63) in a shell, or 40 41 ... 63 written out"),
    (["sim2real", "x.clf", "--probe-seeds", "100..103"], "not as a range: 100 101 102 103 "),
])
def test_a_range_of_seeds_says_how_to_list_them(argv, hint, capsys) -> None:
    """The README names seed sets as ranges ("seeds 40-63"); `--seeds 40-63` said only "must be a
    whole number", as for any other word."""
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"lmsbench {argv[0]}: error: argument {argv[2]}: must be a whole number >= 0")
    assert hint in err and err.count("\n") == 1


@pytest.mark.parametrize("word", ["5-2", "-1", "a-b", "1.5"])
def test_a_seed_that_is_no_range_gets_no_range_hint(word, capsys) -> None:
    assert main(["compare", "office", "--seeds", word]) == 2
    err = capsys.readouterr().err
    assert "must be a whole number" in err and "range" not in err


def test_calibrate_help_names_every_fit_its_world_runs(capsys) -> None:
    """calibrate --world said it fits "the spot width and the outlier baseline"; the same world's runs
    fit the residual tail and the clustering of the tail and of the nans too (experiments.calibrate.fit_sensor)."""
    assert main(["calibrate", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert ("simulated world of the fits by simulation (spot width, outlier baseline, residual tail, the tail's "
            "and the nans' clustering)") in text
