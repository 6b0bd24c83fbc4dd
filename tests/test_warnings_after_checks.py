"""A refused run is its error alone: the warnings a command's input checks raise (a log's ranges in
millimetres, a step that takes no time) are said once the checks pass (options.warnings_after_checks,
said_after_checks), or, where a warning is why the error happens, said within the error's one line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from lms200 import Record, Scan, write_log

N_SCANS = 60  # more than lms200.units.UNITS_SCANS: the reader warns after 50 scans, before a damaged line after them


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A log in millimetres (1.5-4 m written as 1500-4000), the same cut short at its 56th scan line, and a
    log in metres whose scans come in pairs of one stamp."""
    root = tmp_path_factory.mktemp("logs")
    mm = root / "mm.clf"
    write_log(mm, [Record(Scan(np.linspace(1500.0, 4000.0, 181) + k, -np.pi / 2, np.pi / 180, 0.0, 8.183,
                               stamp=0.2 * k)) for k in range(N_SCANS)])
    lines = mm.read_text().splitlines(keepends=True)
    scans = [i for i, line in enumerate(lines) if not line.startswith("#")]
    lines[scans[55]] = lines[scans[55]][:100] + "\n"  # fewer fields than the line announces
    bad = root / "mmbad.clf"
    bad.write_text("".join(lines))
    still = root / "still.clf"
    write_log(still, [Record(Scan(np.linspace(1.5, 4.0, 181), -np.pi / 2, np.pi / 180, 0.0, 8.183, stamp=0.2 * (k // 2)))
                      for k in range(10)])
    return {"mm": mm, "mmbad": bad, "still": still}


def _refused(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    from experiments.cli import main

    status = main(argv)
    err = capsys.readouterr().err.splitlines()
    assert (status, len(err)) == (2, 1), err
    return err[0]


@pytest.mark.parametrize("argv", [["slam", "{log}", "--out", "{tmp}/out"], ["info", "{log}"],
                                  ["calibrate", "{log}", "--out", "{tmp}/s.yaml"],
                                  ["lms200", "emulate", "--log", "{log}", "--tcp", "0", "--duration", "1"]])
def test_a_damaged_line_after_a_millimetre_logs_first_scans_is_its_error_alone(logs, tmp_path, capsys, argv) -> None:
    """The reader warns of the units after 50 scans, then meets the damaged line: that warning, then the
    error (two lines for a user error)."""
    line = _refused([a.format(log=logs["mmbad"], tmp=tmp_path) for a in argv], capsys)
    assert line.startswith(f"lmsbench {' '.join(argv[:2 if argv[0] == 'lms200' else 1])}: error: {logs['mmbad']}:"), line
    assert "malformed ROBOTLASER1 line" in line, line


def test_a_held_warning_is_said_once_where_the_work_reads_the_file_again(logs) -> None:
    """catch_warnings reset warnings' registries as the held block ended: a log checked, then read again by
    the work (emulate --log replays it), said its units warning twice. Only its showing is held now: once."""
    import warnings

    from experiments.options import warnings_after_checks
    from lms200 import read_log
    from lms200.units import RangeUnitsWarning

    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("default")
        with warnings_after_checks():
            sum(1 for _ in read_log(logs["mm"]))
        sum(1 for _ in read_log(logs["mm"]))
    assert [w.category for w in said] == [RangeUnitsWarning], said


@pytest.mark.parametrize("command, says", [
    (["slam"], f"none of its {N_SCANS} scans has a valid beam, nothing to localise against: all "),
    (["calibrate"], f"too few straight runs of beams at 1-4 m in {N_SCANS} scan(s) to estimate the range noise "
                    f"(0 beam triples): none of the first 50 scans has a valid beam: all "),
    (["demo", "--no-sweep", "--log"], f"none of its {N_SCANS} scans has a valid beam, no scan to draw for Fig. 9: all "),
    (["figures", "--log"], f"none of its {N_SCANS} scans has a valid beam, no scan to draw for Fig. 9: all ")])
def test_a_millimetre_log_refused_says_its_units_in_the_error(logs, tmp_path, capsys, command, says) -> None:
    """The units warning was the error's reason, said on a line of its own before it: now the error says it."""
    line = _refused([*command, str(logs["mm"]), "--out", str(tmp_path / ("s.yaml" if command == ["calibrate"] else "out"))],
                    capsys)
    assert line.startswith(f"lmsbench {command[0]}: error: {logs['mm']}: {says}"), line
    # divided by 100, 15-41 m: beyond the range_max, within an LMS200's reach in centimetres (which it does not bound)
    assert "would be in range divided by 1000, 100 % within an LMS200's reach divided by 100: ranges in millimetres or centimetres given as metres?" in line, line


def test_slams_own_warning_before_an_odometry_refusal_is_unsaid(logs, tmp_path, capsys) -> None:
    """`slam LOG --odometry` on a log without odometry whose steps take no time said the steps' warning,
    then the odometry's error."""
    line = _refused(["slam", str(logs["still"]), "--odometry", "--out", str(tmp_path / "out")], capsys)
    assert line == f"lmsbench slam: error: {logs['still']}: --odometry needs odometry on every scan, and this input has none"


@pytest.mark.parametrize("command", [["slam", "--out", "{tmp}/out"], ["calibrate", "--out", "{tmp}/s.yaml"]])
def test_what_skip_bad_lines_skipped_is_held_with_the_warnings(logs, tmp_path, capsys, command) -> None:
    """`--skip-bad-lines` printed its report of the lines skipped as it read, inside the held checks: a
    refused run said it, then its error (review of round 11)."""
    line = _refused([command[0], str(logs["mmbad"]), "--skip-bad-lines", *(a.format(tmp=tmp_path) for a in command[1:])],
                    capsys)
    assert line.startswith(f"lmsbench {command[0]}: error: ") and "millimetres" in line, line


def test_a_held_warning_is_said_when_the_checks_pass(logs, capsys) -> None:
    """The held warnings of a run that goes on are said, once: `info` of a log in millimetres."""
    from experiments.cli import main

    assert main(["info", str(logs["mm"])]) == 0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and "warning:" in err[0] and "millimetres" in err[0], err
