"""The log geometry flags (--laser-fov-deg, --laser-resolution-deg, --laser-angle-min-deg,
--laser-range-max) read numbers as every other option does (options.plain_number): they took Python's
float(), so `--laser-fov-deg 1_0` read a 10 deg field of view and `--laser-range-max ١٢` 12 m, exit 0
(a fuzzing round)."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.mark.parametrize("flag", ["--laser-fov-deg", "--laser-resolution-deg", "--laser-angle-min-deg",
                                  "--laser-range-max"])
@pytest.mark.parametrize("word", ["1_0", "\u0661\u0662"])
def test_a_log_geometry_flag_refuses_underscores_and_non_ascii_digits(tmp_path: Path, capsys, flag, word) -> None:
    from experiments.cli import main

    log = tmp_path / "a.log"
    log.write_text("FLASER 3 1 2 3 0 0 0 0 0 0 1.0 h 1.0\nFLASER 3 1 2 3 0 0 0 0 0 0 2.0 h 2.0\n")
    assert main(["info", str(log), flag, word]) == 2  # old: 0, read as 10 (or 12)
    assert capsys.readouterr().err == (f"lmsbench info: error: argument {flag}: invalid float value: {word!r} "
                                       "(see lmsbench info --help)\n")
    assert main(["info", str(log), "--json", flag, "10" if flag != "--laser-resolution-deg" else "90"]) == 0
