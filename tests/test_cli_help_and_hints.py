"""What the command line tells a new user: help texts that list every world (compare --help listed
five of seven), "did you mean" for a near miss of a command's option, and ``lmsbench --version``."""

from __future__ import annotations

import subprocess
import sys

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
