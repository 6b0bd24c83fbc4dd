"""A user's own extractor (``--methods MODULE:FUNCTION``, docs/baselines.md) that raises: the
user's code failing, said as such in one line naming the method, the source and the scan (exit 2),
not as a bug in lmsbench ("internal error: RuntimeError: x (a bug in lmsbench; ...)", exit 1)."""

from __future__ import annotations

from pathlib import Path

import sys

import pandas as pd
import pytest

from experiments.cli import main

TRACEBACK_HINT = " (LMSBENCH_TRACEBACK=1 shows its traceback)"
USER_MODULES = ("boomext", "wrongext", "fine", "exitext", "exitatimport")


@pytest.fixture
def boom(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, user_methods_dropped: None):
    """A folder (the current one) with boomext.py: ``boom`` raises on the third scan it is given,
    ``quiet`` raises an exception without a message."""
    monkeypatch.delenv("LMSBENCH_TRACEBACK", raising=False)
    (tmp_path / "boomext.py").write_text(
        "from features import extract\n"
        "calls = []\n"
        "def boom(scan):\n"
        "    calls.append(scan.stamp)\n"
        "    if len(calls) == 3:\n"
        "        raise RuntimeError('x')\n"
        "    return extract(scan, method='split_merge')\n"
        "def quiet(scan):\n"
        "    raise KeyError\n")
    monkeypatch.chdir(tmp_path)
    for name in USER_MODULES:  # each test's own files, not an earlier test's modules
        sys.modules.pop(name, None)
    yield tmp_path
    for name in USER_MODULES:
        sys.modules.pop(name, None)


def test_compare_says_a_users_extractor_failed_naming_method_source_and_scan(boom, capsys) -> None:
    # the first call is the untimed warm-up on scan 0, the second the timed one on scan 0, the third scan 1's
    assert main(["compare", "office:0", "--duration", "2", "--rate", "2", "--methods", "boomext:boom",
                 "--out", "cmp", "--no-progress"]) == 2
    assert capsys.readouterr().err == ("lmsbench compare: error: your extractor boomext:boom raised RuntimeError: x "
                                       f"on office:0 scan 1{TRACEBACK_HINT}\n")
    assert main(["compare", "office:0", "--duration", "1", "--methods", "boomext:quiet", "--out", "cmp2",
                 "--no-progress"]) == 2
    assert capsys.readouterr().err == ("lmsbench compare: error: your extractor boomext:quiet raised KeyError "
                                       f"on office:0 scan 0{TRACEBACK_HINT}\n")


def test_lmsbench_traceback_shows_the_users_code_and_still_exits_2(boom, capsys, monkeypatch) -> None:
    monkeypatch.setenv("LMSBENCH_TRACEBACK", "1")
    assert main(["compare", "office:0", "--duration", "1", "--methods", "boomext:quiet", "--out", "cmp",
                 "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert f'File "{boom / "boomext.py"}", line 9, in quiet' in err and "\nKeyError\n" in err
    assert err.endswith("lmsbench compare: error: your extractor boomext:quiet raised KeyError on office:0 scan 0\n")


def test_a_bug_in_lmsbench_beside_a_user_extractor_is_still_an_internal_error(boom, capsys, monkeypatch) -> None:
    import experiments.compare

    def broken(*args, **kwargs):
        raise RuntimeError("y")

    monkeypatch.setattr(experiments.compare, "explained_fraction", broken)  # lmsbench's own code, after the call
    (boom / "fine.py").write_text("from features import extract\ndef f(scan):\n    return extract(scan, method='iepf')\n")
    assert main(["compare", "office:0", "--duration", "1", "--methods", "fine:f", "--out", "cmp2",
                 "--no-progress"]) == 1
    assert capsys.readouterr().err == ("lmsbench compare: internal error: RuntimeError: y (a bug in lmsbench; "
                                       "LMSBENCH_TRACEBACK=1 shows where)\n")


def test_a_user_extractor_calling_sys_exit_is_said_in_one_line_not_a_silent_exit(boom, capsys) -> None:
    """The wrong-input hunt: sys.exit(0) in a user's extractor ended `compare` silently with exit 0
    (as if it had finished; nothing written), sys.exit(3) with 3, sys.exit() at its module's import
    the same, and GeneratorExit with a traceback, exit 1: each is now the user's code failing."""
    (boom / "exitext.py").write_text("import sys\ndef zero(scan):\n    sys.exit(0)\n"
                                     "def gen(scan):\n    raise GeneratorExit\n")
    (boom / "exitatimport.py").write_text("import sys\nsys.exit(0)\ndef f(scan):\n    pass\n")
    for fn, said in (("zero", "SystemExit: 0 (it called sys.exit)"), ("gen", "GeneratorExit")):
        assert main(["compare", "office:0", "--duration", "1", "--methods", f"exitext:{fn}", "--out", f"c_{fn}",
                     "--no-progress"]) == 2
        assert capsys.readouterr().err == (f"lmsbench compare: error: your extractor exitext:{fn} raised {said} "
                                           f"on office:0 scan 0{TRACEBACK_HINT}\n")
    assert main(["compare", "office:0", "--duration", "1", "--methods", "exitatimport:f", "--out", "c_imp",
                 "--no-progress"]) == 2
    assert capsys.readouterr().err == ("lmsbench compare: error: exitatimport:f: importing 'exitatimport' failed: "
                                       "SystemExit: 0 (it called sys.exit)\n")


def test_sys_exit_in_code_a_command_runs_is_one_line_exit_2_not_its_status(boom, capsys, monkeypatch) -> None:
    """No command calls sys.exit(): a SystemExit out of one came from code it ran, and ended the
    command with that status (0 said a run that stopped half-way had finished)."""
    import experiments.compare

    def exits(*args, **kwargs):
        sys.exit(0)

    monkeypatch.setattr(experiments.compare, "explained_fraction", exits)
    (boom / "fine.py").write_text("from features import extract\ndef f(scan):\n    return extract(scan, method='iepf')\n")
    assert main(["compare", "office:0", "--duration", "1", "--methods", "fine:f", "--out", "cmp",
                 "--no-progress"]) == 2
    assert capsys.readouterr().err == ("lmsbench compare: error: code the command ran called sys.exit(0), which "
                                       "stopped it before it finished (a user's extractor or sweep cell kind?; "
                                       "LMSBENCH_TRACEBACK=1 shows where)\n")


def test_slam_with_a_failing_user_extractor_names_the_scan(boom, capsys) -> None:
    assert main(["simulate", "--duration", "2", "--out", "run", "--quiet"]) == 0
    capsys.readouterr()
    for preset in ("paper", "default"):  # paper: scan by scan in batches; default: the keyframes at the end
        if "boomext" in sys.modules:  # the run before called it: count this run's calls afresh
            sys.modules["boomext"].calls.clear()
        assert main(["slam", "run", "--extractor", "boomext:boom", "--preset", preset, "--out", f"slam-{preset}",
                     "--quiet"]) == 2
        err = capsys.readouterr().err
        assert err.startswith("lmsbench slam: error: your extractor boomext:boom raised RuntimeError: x on run scan ")
        assert err.endswith(TRACEBACK_HINT + "\n") and err.count("\n") == 1
    assert main(["slam", "run", "--extractor", "boomext:quiet", "--preset", "paper", "--out", "slam-q", "--quiet"]) == 2
    assert capsys.readouterr().err == ("lmsbench slam: error: your extractor boomext:quiet raised KeyError on run "
                                       f"scan 0{TRACEBACK_HINT}\n")


def test_a_sweep_cell_records_the_users_failure_and_its_line(boom) -> None:
    from experiments.sweep.cells import run_cell

    row = run_cell("extract", {"method": "boomext:quiet", "world": "office", "seed": 2, "duration": 1.0, "rate_hz": 2.0})
    assert row["status"] == "error"
    assert row["error"] == ("UserMethodFailed: your extractor boomext:quiet raised KeyError on office:2 scan 0 "
                            "(boomext.py:9)")


def test_a_wrong_result_names_its_scan_too(boom, capsys) -> None:
    (boom / "wrongext.py").write_text("def f(scan):\n    return 42\n")
    assert main(["compare", "office:0", "--duration", "1", "--methods", "wrongext:f", "--out", "cmp",
                 "--no-progress"]) == 2
    assert capsys.readouterr().err == ("lmsbench compare: error: your extractor wrongext:f returned int, not a "
                                       "features.FeatureSet on office:0 scan 0\n")


def test_a_users_lines_out_of_their_meaning_are_refused_naming_the_method_outside_the_timing(boom, capsys) -> None:
    """A user's extractor's ``Lines.from_arrays`` with a nan rho or first > last (scored nan,
    silently, before the fuzz round) is one error naming the method, in compare, extract and
    extract_many; the rows are checked after the call, not inside ``FeatureSet()`` (which cost a
    user's extractor 50-70 us a scan of its timed span)."""
    import numpy as np

    from features import FeatureSet, extract, extract_many
    from features.errors import ConfigError
    from experiments.compare import parse_sources
    from experiments.user_methods import ensure_method

    (boom / "wrongext.py").write_text(
        "import numpy as np\n"
        "from features import Corners, FeatureSet, Lines\n"
        "def lines(rho, first):\n"
        "    return Lines.from_arrays([rho], [0.0], [[1.0, -1.0]], [[1.0, 1.0]], [np.eye(2) * 1e-4], [first], [49], [0])\n"
        "def nan(scan):\n"
        "    return FeatureSet(lines(float('nan'), 10), Corners.empty(), 'nan')\n"
        "def inverted(scan):\n"
        "    return FeatureSet(lines(1.0, 60), Corners.empty(), 'inverted')\n")
    assert main(["compare", "office:0", "--duration", "1", "--methods", "wrongext:nan", "--out", "cmp",
                 "--no-progress"]) == 2
    assert capsys.readouterr().err == (
        "lmsbench compare: error: your extractor wrongext:nan returned features out of their meaning: lines: line 0: "
        "its values must be finite (rho, alpha, x0, y0, x1, y1, first, last = nan, 0, 1, -1, 1, 1, 10, 49) "
        "on office:0 scan 0\n")
    import wrongext

    bad = wrongext.inverted(None)  # built as cheaply as an extractor's: its rows are checked where the method's result is
    assert isinstance(bad, FeatureSet) and bad.lines.first.tolist() == [60]
    scan = next(iter(parse_sources(["office:0"], duration=1.0)[0].records)).scan
    ensure_method("wrongext:inverted")
    message = r"^method 'wrongext:inverted': its run returned features out of their meaning: lines: line 0: its beams must be whole"
    with pytest.raises(ConfigError, match=message):
        extract(scan, "wrongext:inverted")
    with pytest.raises(ConfigError, match=message):
        extract_many([scan, scan], "wrongext:inverted")
    assert np.isnan(wrongext.nan(None).lines.rho[0])


LAZY_MODULES = ("lazyext", "lazyhelper")


def last_searched(folder: str) -> int:
    """How many finders of sys.meta_path search ``folder`` after every other place."""
    from experiments.user_methods import FolderFinder

    return sum(isinstance(f, FolderFinder) and f.folder == folder for f in sys.meta_path)


def test_a_folder_beside_a_user_module_does_not_shadow_lmsbench(tmp_path) -> None:
    """`lmsbench bench` (its experiments area imports its cell kind as a user's module is imported)
    in a folder holding an earlier `slam --out slam` failed in its slam area: "internal error:
    ImportError: cannot import name 'SlamConfig' from 'slam' (unknown location)", exit 1. The
    current folder was left on sys.path, "last", but an editable install's finder comes after the
    path's, so ./slam/ was imported as a namespace package in place of lmsbench's slam."""
    import subprocess

    (tmp_path / "slam").mkdir()  # an output folder, as `lmsbench slam RUN --out slam` leaves it
    (tmp_path / "slam" / "trajectory.tum").write_text("")
    (tmp_path / "myext.py").write_text("def lines(scan):\n    return None\n")
    code = ("from experiments.user_methods import import_named\n"
            "import_named('myext:lines', 'myext:lines')\n"
            "import slam\n"
            "print(hasattr(slam, 'SlamConfig'), slam.__file__ is not None)\n")
    out = subprocess.run([sys.executable, "-P", "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["True", "True"]  # old: False False (a namespace package)


def test_a_user_extractor_that_imports_a_sibling_when_called_finds_it(tmp_path, monkeypatch, capsys,
                                                                      user_methods_dropped) -> None:
    """`lmsbench compare office:0 --methods lazyext:lines`, lazyext.py importing lazyhelper.py (beside
    it) inside its function: the current folder was put on the path for the import and taken off
    after it, so the call failed, "your extractor lazyext:lines raised ModuleNotFoundError: No module
    named 'lazyhelper' on office:0 scan 0", exit 2 (the installed script's path does not start with
    the current folder). The folder is now searched for the run, after every other place."""
    from features import FeatureSet

    from experiments.user_methods import import_named

    (tmp_path / "lazyext.py").write_text("def lines(scan):\n"
                                         "    import lazyhelper  # a sibling, imported when called\n"
                                         "    return lazyhelper.lines(scan)\n")
    (tmp_path / "lazyhelper.py").write_text("from features import extract\n"
                                            "def lines(scan):\n"
                                            "    return extract(scan, method='split_merge')\n")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "path", [p for p in sys.path if p not in ("", ".", str(tmp_path))])  # as `lmsbench`
    # the folder's finder goes with the test (conftest.meta_path_after)
    for name in LAZY_MODULES:
        monkeypatch.delitem(sys.modules, name, raising=False)
    fn = import_named("lazyext:lines", "lazyext:lines")
    from lms200 import Scan
    import numpy as np

    assert isinstance(fn(Scan.lms200(np.full(361, 2.0))), FeatureSet)  # old: ModuleNotFoundError
    assert str(tmp_path) not in sys.path and last_searched(str(tmp_path)) == 1  # searched last: it shadows nothing
    monkeypatch.delitem(sys.modules, "lazyhelper")
    assert main(["compare", "office:0", "--duration", "1", "--methods", "lazyext:lines", "--out", "cmp",
                 "--no-progress"]) == 0, capsys.readouterr().err
    assert str(tmp_path) not in sys.path and last_searched(str(tmp_path)) == 1
    summary = pd.read_csv(tmp_path / "cmp" / "summary.csv")
    assert list(summary["method"]) == ["lazyext:lines"] and summary["lines_per_scan"].iloc[0] > 0
    for name in LAZY_MODULES:
        sys.modules.pop(name, None)


def test_a_test_keeps_the_finders_it_added_but_a_user_folders():
    """conftest's restore of sys.meta_path drops the user folders' finders a test added and keeps
    any other (dask's importlib_metadata backport appends one and deletes the standard finder's
    find_distributions: dropping it left importlib.metadata finding no package at all)."""
    from conftest import meta_path_after
    from experiments.user_methods import FolderFinder

    kept, other, users, earlier = object(), object(), FolderFinder("/x"), FolderFinder("/y")
    assert meta_path_after([kept, earlier], [kept, earlier, other, users]) == [kept, earlier, other]


def test_compare_names_a_logs_own_scan_number_under_stride(boom, capsys) -> None:
    """docs/commands.md: a scan is named by the log's own number. compare --stride 2 named the third
    call's scan (warm-up and timed on the log's scan 0, then its scan 2) 'scan 1', the index among those kept."""
    from lms200 import write_log
    from sim import simulate_records

    write_log(boom / "run.clf", simulate_records("office", seed=0, duration=2.0)[:8])
    assert main(["compare", "run.clf", "--stride", "2", "--methods", "boomext:boom", "--out", "cmp",
                 "--no-progress"]) == 2
    assert capsys.readouterr().err == ("lmsbench compare: error: your extractor boomext:boom raised RuntimeError: x "
                                       f"on run.clf scan 2{TRACEBACK_HINT}\n")


def test_slam_every_names_the_failing_scan_by_the_logs_own_number(boom, capsys) -> None:
    """slam --every 2 --extractor: the user's extractor failing on the log's scan 4 (the third kept) was
    named 'scan 2', the index among the scans kept (docs/commands.md: the log's own number)."""
    from lms200 import write_log
    from sim import simulate_records

    records = simulate_records("office", seed=0, duration=2.0)[:12]
    write_log(boom / "run.clf", records)
    (boom / "late.py").write_text(
        "from features import extract\n"
        "def late(scan):\n"
        f"    if scan.stamp >= {records[4].scan.stamp!r}:\n"
        "        raise RuntimeError('late')\n"
        "    return extract(scan, method='split_merge')\n")
    sys.modules.pop("late", None)
    try:
        assert main(["slam", "run.clf", "--every", "2", "--extractor", "late:late", "--preset", "paper", "--out", "s",
                     "--quiet"]) == 2
    finally:
        sys.modules.pop("late", None)
    assert capsys.readouterr().err == ("lmsbench slam: error: your extractor late:late raised RuntimeError: late on "
                                       f"run.clf scan 4{TRACEBACK_HINT}\n")


def test_a_users_lines_past_the_scans_beams_are_refused_naming_the_method_and_scan(boom, capsys) -> None:
    """fuzz4: lines reaching past the scan's last beam were said by the scoring as "fs: its lines span beams
    0..411, the scan has 361", naming neither the extractor nor the scan; `features.extract` handed them on."""
    from features import ConfigError, extract
    from features.registry import get_method
    from experiments.user_methods import ensure_method
    from lms200 import Scan

    (boom / "wrongext.py").write_text(
        "import dataclasses\n"
        "from features import FeatureSet, extract\n"
        "def past(scan):\n"
        "    fs = extract(scan, method='split_merge')\n"
        "    return FeatureSet([dataclasses.replace(l, last=len(scan) + 50) for l in fs.lines], fs.corners)\n")
    assert main(["compare", "office:0", "--duration", "0.5", "--methods", "wrongext:past", "--out", "cmp",
                 "--no-progress"]) == 2
    assert capsys.readouterr().err == ("lmsbench compare: error: your extractor wrongext:past returned features that "
                                       "reach beam 411 of a 361-beam scan (features of another scan?) on office:0 scan 0\n")
    ensure_method("wrongext:past")
    assert get_method("wrongext:past") is not None
    with pytest.raises(ConfigError, match=r"^method 'wrongext:past': its run returned features that reach beam 411 "
                                          r"of a 361-beam scan"):
        extract(Scan.lms200([2.0] * 361), method="wrongext:past")
