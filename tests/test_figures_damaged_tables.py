"""`lmsbench figures --tables DIR` / `--sweep DIR` with damaged inputs (a damaged-input fuzz round):
each refused before any output, one line, exit 2, naming the table; none drawn empty or left out
silently."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from experiments.cli import main
from lms200 import LmsbenchError


@pytest.fixture
def tables(tmp_path) -> Path:
    """A tables folder Fig. 7 and Fig. 10 are drawn from (study settings, timing, trajectory, map)."""
    t = tmp_path / "tables"
    t.mkdir()
    (t / "study.yaml").write_text(yaml.safe_dump({"world": "office", "seed": 0, "duration": 1.0, "resolved": {"sensor": {}}}))
    pd.DataFrame({"method": ["sensor"] * 3, "scan": [0, 1, 2], "time_ms": [0.05, 0.04, 0.06]}).to_parquet(
        t / "timing.parquet", index=False)
    pd.DataFrame({"source": ["truth", "truth", "slam", "slam"], "t": [0.0, 1.0, 0.0, 1.0], "x": [0.0, 1.0, 0.0, 1.1],
                  "y": [0.0, 0.0, 0.0, 0.1]}).to_parquet(t / "trajectory.parquet", index=False)
    pd.DataFrame({"source": ["truth", "slam"], "x1": [0.0, 0.0], "y1": [1.0, 1.1], "x2": [2.0, 2.0],
                  "y2": [1.0, 1.1]}).to_parquet(t / "map.parquet", index=False)
    return t


def _only(tables: Path, *names: str) -> Path:
    """``tables`` with only the tables ``names`` beside its study.yaml: the figures a test does not
    look at (Fig. 7, Fig. 10: ~1 s of CPU a run) are not drawn."""
    for table in tables.glob("*.parquet"):
        if table.stem not in names:
            table.unlink()
    return tables


def _refused(capsys, tables: Path, out: Path) -> str:
    assert main(["figures", "--tables", str(tables), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert not out.exists()  # before any output: no figures.yaml, no figure
    return err.rstrip("\n")


@pytest.mark.parametrize("table, column, value", [
    ("timing", "time_ms", np.nan), ("timing", "time_ms", np.inf), ("trajectory", "x", np.nan), ("map", "y2", -np.inf)])
def test_a_table_whose_plotted_column_holds_no_finite_number_is_refused(tables, tmp_path, capsys, table, column, value):
    # drawn as empty axes, exit 0: every figure of the table useless
    frame = pd.read_parquet(tables / f"{table}.parquet")
    frame[column] = value
    frame.to_parquet(tables / f"{table}.parquet", index=False)
    n = len(frame)
    assert _refused(capsys, tables, tmp_path / "o") == (
        f"lmsbench figures: error: --tables {tables}: table {table}'s column {column} holds no finite number ({n} rows, "
        "all nan or infinite), so its figure would be empty: a damaged table, or not one of `lmsbench figures` or "
        "`lmsbench demo`")


def test_a_table_with_some_nan_is_drawn(tables, tmp_path, capsys):
    frame = pd.read_parquet(tables / "timing.parquet")
    frame.loc[0, "time_ms"] = np.nan
    frame.to_parquet(tables / "timing.parquet", index=False)
    assert main(["figures", "--tables", str(_only(tables, "timing")), "--out", str(tmp_path / "o")]) == 0, capsys.readouterr().err
    assert pd.read_csv(tmp_path / "o" / "fig7_timing.csv").shape[0] == 3


def test_a_folder_in_place_of_a_table_is_refused(tables, tmp_path, capsys):
    # pyarrow read it as an empty dataset: fig7_timing was left out, exit 0
    (tables / "timing.parquet").unlink()
    (tables / "timing.parquet").mkdir()
    assert _refused(capsys, tables, tmp_path / "o") == (
        f"lmsbench figures: error: {tables / 'timing.parquet'}: a folder where a table of the study goes; a table is "
        "a Parquet file")


def test_a_table_saved_as_csv_is_refused(tables, tmp_path, capsys):
    # left out, its figure not drawn, exit 0
    pd.read_parquet(tables / "trajectory.parquet").to_csv(tables / "trajectory.csv", index=False)
    (tables / "trajectory.parquet").unlink()
    assert _refused(capsys, tables, tmp_path / "o") == (
        f"lmsbench figures: error: {tables / 'trajectory.csv'}: the study's tables are read as Parquet "
        "(trajectory.parquet, as `lmsbench figures` and `lmsbench demo` save them), not CSV")


@pytest.fixture(scope="module")
def sweeps(tmp_path_factory) -> dict[str, Path]:
    """Two finished sweeps of different parameters (extract cells over k, over ad_tau), about 2 s."""
    root = tmp_path_factory.mktemp("sweeps")
    out = {}
    for name, grid in (("k", {"extractor.k": [3, 5]}), ("tau", {"extractor.ad_tau": [2.0, 4.0, 8.0]})):
        spec = root / f"{name}.yaml"
        spec.write_text(yaml.safe_dump({"name": name, "kind": "extract", "fixed": {"duration": 0.5, "rate_hz": 4.0},
                                        "grid": grid}))
        out[name] = root / name
        assert main(["sweep", str(spec), "--inprocess", "--no-progress", "--out", str(out[name])]) == 0
    return out


def _sweep_refused(capsys, tables: Path, sweep: Path, out: Path) -> str:
    capsys.readouterr()
    assert main(["figures", "--tables", str(tables), "--sweep", str(sweep), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert not out.exists()
    return err.rstrip("\n")


def test_a_sweep_folder_whose_table_and_sweep_yaml_are_of_different_sweeps_is_refused(sweeps, tables, tmp_path, capsys):
    import shutil

    mixed = tmp_path / "mixed"
    shutil.copytree(sweeps["k"], mixed)
    shutil.copy(sweeps["tau"] / "sweep.yaml", mixed / "sweep.yaml")
    # it said "its results.parquet holds 2 of the 3 cells of its sweep.yaml: the sweep did not finish ..."
    assert _sweep_refused(capsys, tables, mixed, tmp_path / "o") == (
        f"lmsbench figures: error: --sweep {mixed}: its results.parquet has no column extractor.ad_tau, a parameter of "
        f"its sweep.yaml ({mixed / 'sweep.yaml'}): the table and the sweep.yaml are of different sweeps (one copied over "
        "the other's?); run the sweep again into a new folder")
    shutil.copy(sweeps["tau"] / "results.parquet", mixed / "results.parquet")
    shutil.copy(sweeps["k"] / "sweep.yaml", mixed / "sweep.yaml")
    table = pd.read_parquet(mixed / "results.parquet").assign(**{"extractor.k": 3})  # a column of k's name, 3 cells
    table.to_parquet(mixed / "results.parquet", index=False)
    # it said "holds 3 of the 2 cells of its sweep.yaml: the sweep did not finish"
    assert _sweep_refused(capsys, tables, mixed, tmp_path / "o") == (
        f"lmsbench figures: error: --sweep {mixed}: its results.parquet holds 3 cells, more than the 2 of its sweep.yaml "
        f"({mixed / 'sweep.yaml'}): the table and the sweep.yaml are of different sweeps (one copied over the other's?); "
        "run the sweep again into a new folder")


@pytest.mark.parametrize("table, column, values", [
    ("map", "y2", [1e308, -1e308]),      # was "internal error: ValueError: Axis limits cannot be NaN or Inf"
    ("timing", "time_ms", [1e300] * 3),  # was drawn under matplotlib's overflow warnings, exit 0
])
def test_a_table_of_numbers_beyond_any_plot_is_refused(tables, tmp_path, capsys, table, column, values):
    """Fuzz round 5: a finite number no table of lmsbench holds (beyond +-1e100) overflowed the plots' axis
    arithmetic; now refused before any output, naming the table, column and row."""
    frame = pd.read_parquet(tables / f"{table}.parquet")
    frame[column] = values
    frame.to_parquet(tables / f"{table}.parquet", index=False)
    assert _refused(capsys, tables, tmp_path / "o") == (
        f"lmsbench figures: error: {tables / f'{table}.parquet'}: its column {column} holds {values[0]:g} (row 0), "
        "beyond +-1e+100, where its plot's axis arithmetic would overflow: the figures cannot draw it (lmsbench's own "
        "tables hold stamps below 2^32 s and coordinates within 1e9 m: a damaged or edited table, or a sweep's "
        "parameter or metric that large)")


@pytest.mark.parametrize("table, column, value, said", [
    # each drawn on Fig. 7's log axis, exit 0: -9e99 and 0 under matplotlib's warnings, 9e99 as 100 decades of nothing
    ("timing", "time_ms", -9e99, "holds -9e+99 (row 1), which is no time per scan (1 ns to a day, 1e-06 to 8.64e+07 ms)"),
    ("timing", "time_ms", 9e99, "holds 9e+99 (row 1), which is no time per scan"),
    ("timing", "time_ms", 0.0, "holds 0 (row 1), which is no time per scan"),
    ("timing", "time_ms", np.inf, "holds inf (row 1), which is no time per scan"),
    ("summary", "time_ms_median", -1.0, "holds -1 (row 1), which is no time per scan"),
    ("summary", "f1", 7.0, "holds 7 (row 1), which is no line F1 score (0 to 1)"),  # drawn off its 0-1.02 axis
    # a figure of one dot at 9e99 m, exit 0
    ("trajectory", "x", 9e99, "holds 9e+99 (row 1), which is no position (x and y within +-1e+09 m, as every log and "
                              "trajectory lmsbench reads or writes)"),
    ("map", "y2", -2e9, "holds -2e+09 (row 1), which is no position"),
    # a 25 % time above the median: "internal error: ValueError: 'xerr' must not contain negative values"
    ("summary", "time_ms_p25", 0.5, "row 1 holds the times time_ms_p25 0.5, time_ms_median 0.05, time_ms_p75 0.06 ms, "
                                    "not in that order"),
])
def test_a_time_score_or_position_the_figures_cannot_draw_as_one_is_refused(tables, tmp_path, capsys, table, column, value,
                                                                           said):
    """Round 7: finite values under the 1e100 bound that no time per scan (log axes), F1 or position can be."""
    pd.DataFrame({"method": ["sensor", "iepf"], "f1": [0.9, 0.8], "time_ms_median": [0.05, 0.05],
                  "time_ms_p25": [0.04, 0.04], "time_ms_p75": [0.06, 0.06]}).to_parquet(tables / "summary.parquet")
    frame = pd.read_parquet(tables / f"{table}.parquet")
    frame.loc[1, column] = value
    frame.to_parquet(tables / f"{table}.parquet", index=False)
    err = _refused(capsys, tables, tmp_path / "o")
    assert err.startswith(f"lmsbench figures: error: --tables {tables}: table {table}")
    assert said in err and err.endswith("a damaged table, or not one of `lmsbench figures` or `lmsbench demo`")


@pytest.mark.parametrize("edit, said", [
    # k 1e308 beside the sweep's k [3, 5] was "internal error: ValueError: arange: cannot compute length"
    (lambda t: t.assign(**{"extractor.k": [1e308, -1e308]}), "row 0 (extractor.k=1e+308, seed=0) is no cell"),
    # values of another grid, or text, under the sweep's own cell ids were drawn, exit 0
    (lambda t: t.assign(**{"extractor.k": [3, 8]}), "row 1 (extractor.k=8, seed=0) is no cell"),
    (lambda t: t.assign(**{"extractor.k": ["a", "b"]}), "row 0 (extractor.k='a', seed=0) is no cell"),
    # each cell 50 times was drawn as a mean over "50 seeds", exit 0
    (lambda t: pd.concat([t] * 50, ignore_index=True), "row 2 repeats a cell of an earlier row"),
])
def test_a_sweep_table_whose_rows_are_not_its_sweep_yamls_cells_is_refused(sweeps, tables, tmp_path, capsys, edit, said):
    import shutil

    edited = tmp_path / "edited"
    shutil.copytree(sweeps["k"], edited)
    edit(pd.read_parquet(edited / "results.parquet")).to_parquet(edited / "results.parquet", index=False)
    err = _sweep_refused(capsys, tables, edited, tmp_path / "o")
    assert err.startswith(f"lmsbench figures: error: --sweep {edited}: its results.parquet's row "), err
    assert said in err and err.endswith(f"the table and the sweep.yaml ({edited / 'sweep.yaml'}) are of different sweeps, "
                                        "or the table was edited; run the sweep again into a new folder"), err


def test_a_sweep_table_that_is_no_sweeps_or_a_folder_is_refused(sweeps, tables, tmp_path, capsys):
    import shutil

    folder = tmp_path / "s"
    shutil.copytree(sweeps["k"], folder)
    shutil.copy(tables / "timing.parquet", folder / "results.parquet")
    # it said "no successful cell to plot (3 cells, all failed; their `error` column says why)"
    assert _sweep_refused(capsys, tables, folder, tmp_path / "o") == (
        f"lmsbench figures: error: --sweep {folder / 'results.parquet'}: not the table of `lmsbench sweep` (no status "
        "column: one row per cell with its status; another program's table, or edited?)")
    (folder / "results.parquet").unlink()
    (folder / "results.parquet").mkdir()
    # it said "no results.parquet: the sweep did not finish; finish it with lmsbench sweep ..."
    assert _sweep_refused(capsys, tables, folder, tmp_path / "o") == (
        f"lmsbench figures: error: --sweep {folder / 'results.parquet'}: a folder where the sweep's table goes; it is "
        "the Parquet file `lmsbench sweep` writes")


def test_both_sweeps_draw(sweeps, tables, tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["figures", "--tables", str(_only(tables, "timing")), "--sweep", str(sweeps["k"]), "--sweep", str(sweeps["tau"]),
                 "--out", str(out)]) == 0, capsys.readouterr().err
    assert (out / "sweep_k_f1.png").is_file() and (out / "sweep_tau_f1.png").is_file()


@pytest.mark.parametrize("gone", ["map", "office_corners"])
def test_a_table_drawn_beside_another_is_required_with_it(tables, tmp_path, capsys, gone):
    # without office_corners Fig. 9 failed after the figures before it ("the tables do not hold what the figures
    # read (KeyError: 'office_corners')", figures.yaml and five figures written); without map Fig. 10 was left out.
    # Drawn whole first with the figure of the two tables alone (Fig. 10, or Fig. 9)
    if gone == "map":
        _only(tables, "trajectory", "map")
    else:
        _only(tables)
        pd.DataFrame({"panel": [0, 0], "label": ["a", "a"], "x": [1.0, 2.0], "y": [0.0, 0.5]}).to_parquet(
            tables / "office_points.parquet", index=False)
        pd.DataFrame({"panel": [0], "x1": [1.0], "y1": [0.0], "x2": [2.0], "y2": [0.5]}).to_parquet(
            tables / "office_lines.parquet", index=False)
        pd.DataFrame({"panel": [0], "x": [1.0], "y": [0.0]}).to_parquet(tables / "office_corners.parquet", index=False)
    assert main(["figures", "--tables", str(tables), "--out", str(tmp_path / "ok")]) == 0, capsys.readouterr().err
    (tables / f"{gone}.parquet").unlink()
    driving = "trajectory" if gone == "map" else "office_points"
    assert _refused(capsys, tables, tmp_path / "o") == (
        f"lmsbench figures: error: --tables {tables}: table {driving} has no {gone} beside it ({gone}.parquet), which "
        "its figure draws with it: a tables folder of `lmsbench figures` or `lmsbench demo` holds both")


def _points(tables: Path, panels: list[float]) -> None:
    n = len(panels)
    pd.DataFrame({"panel": panels, "label": ["s"] * n, "x": np.linspace(1, 2, n), "y": np.zeros(n)}).to_parquet(
        tables / "office_points.parquet", index=False)
    pd.DataFrame({"panel": [0], "x1": [1.0], "y1": [0.0], "x2": [2.0], "y2": [0.5]}).to_parquet(
        tables / "office_lines.parquet", index=False)
    pd.DataFrame({"panel": [0], "x": [1.0], "y": [0.0]}).to_parquet(tables / "office_corners.parquet", index=False)


def test_a_points_table_of_too_many_or_null_panels_is_refused(tables, tmp_path, capsys):
    # 1,441 panels: "terminate called after throwing an instance of 'std::bad_alloc'", exit 134
    _points(tables, list(range(17)))
    assert _refused(capsys, tables, tmp_path / "o") == (
        f"lmsbench figures: error: --tables {tables}: table office_points holds 17 panels (scans), more than Fig. 9 "
        "draws (at most 16; a study draws 4): a damaged table, or not one of `lmsbench figures` or `lmsbench demo`")
    # a nan panel: "internal error: IndexError: single positional indexer is out-of-bounds", after five figures
    _points(tables, [0.0, np.nan])
    assert _refused(capsys, tables, tmp_path / "o") == (
        f"lmsbench figures: error: --tables {tables}: table office_points's column panel has empty (null or nan) values "
        "in 1 of its 2 rows, where every row names its scan: a damaged table, or not one of `lmsbench figures` or "
        "`lmsbench demo`")
    _points(_only(tables), list(range(16)))  # Fig. 9 alone
    assert main(["figures", "--tables", str(tables), "--out", str(tmp_path / "ok")]) == 0, capsys.readouterr().err


def test_a_trajectory_without_truth_or_estimate_and_a_map_without_walls_are_refused(tables, tmp_path, capsys):
    trajectory = pd.read_parquet(tables / "trajectory.parquet")
    trajectory.assign(source="other").to_parquet(tables / "trajectory.parquet", index=False)
    # "internal error: ValueError: Number of columns must be a positive integer, not 0"
    assert _refused(capsys, tables, tmp_path / "o") == (
        f"lmsbench figures: error: --tables {tables}: table trajectory has no rows of source truth, which Fig. 10 draws: "
        "a damaged table, or not one of `lmsbench figures` or `lmsbench demo`")
    trajectory.to_parquet(tables / "trajectory.parquet", index=False)
    pd.read_parquet(tables / "map.parquet").assign(source="slam").to_parquet(tables / "map.parquet", index=False)
    # drawn without the true walls, exit 0
    assert _refused(capsys, tables, tmp_path / "o") == (
        f"lmsbench figures: error: --tables {tables}: table map has no rows of source truth (the true walls Fig. 10 "
        "draws): a damaged table, or not one of `lmsbench figures` or `lmsbench demo`")


def test_a_signals_table_longer_than_a_scan_is_refused(tables, tmp_path, capsys):
    # a million rows drew for over two minutes
    n = (1 << 14) + 1
    pd.DataFrame({c: np.linspace(0, 1, n) for c in ("beam", "bearing_deg", "range_m", "ad", "theta_deg", "psi_deg")}).to_parquet(
        tables / "signals.parquet", index=False)
    assert _refused(capsys, tables, tmp_path / "o") == (
        f"lmsbench figures: error: --tables {tables}: table signals holds {n} rows, more than a scan's beams (at most "
        "16384; it is one scan): a damaged table, or not one of `lmsbench figures` or `lmsbench demo`")


def test_a_timing_table_with_a_null_method_is_refused(tables, tmp_path, capsys):
    # drawn without its label ("No artists with labels found to put in legend"), exit 0
    pd.read_parquet(tables / "timing.parquet").assign(method=None).to_parquet(tables / "timing.parquet", index=False)
    assert _refused(capsys, tables, tmp_path / "o") == (
        f"lmsbench figures: error: --tables {tables}: table timing's column method has empty (null or nan) values in 3 "
        "of its 3 rows, where every row names its extractor: a damaged table, or not one of `lmsbench figures` or "
        "`lmsbench demo`")


@pytest.mark.parametrize("method, shown", [(7, "int values (7)"), (True, "bool values (True)")])
def test_a_timing_table_whose_method_is_no_text_is_refused(tables, tmp_path, capsys, method, shown):
    # fuzz round 5: "internal error: TypeError: 'int' object is not iterable", after figures.yaml
    pd.read_parquet(tables / "timing.parquet").assign(method=method).to_parquet(tables / "timing.parquet", index=False)
    assert _refused(capsys, _only(tables, "timing"), tmp_path / "o") == (
        f"lmsbench figures: error: --tables {tables}: table timing's column method holds {shown}, where every row names "
        "its extractor as text: a damaged table, or not one of `lmsbench figures` or `lmsbench demo`")


def test_a_signals_table_whose_ad_band_is_text_is_refused(tables, tmp_path, capsys):
    # fuzz round 5: "internal error: TypeError: operation 'rsub' not supported for dtype 'str'"; ad_band is
    # drawn only where the table has it, and a signals table without it is still drawn
    n = 11
    signals = pd.DataFrame({"beam": np.arange(n), "bearing_deg": np.linspace(-90, 90, n), "range_m": np.full(n, 2.0),
                            "ad": np.zeros(n), "theta_deg": np.zeros(n), "psi_deg": np.zeros(n)})
    signals.to_parquet(_only(tables) / "signals.parquet", index=False)
    assert main(["figures", "--tables", str(tables), "--out", str(tmp_path / "drawn")]) == 0, capsys.readouterr().err
    signals.assign(ad_band="x").to_parquet(tables / "signals.parquet", index=False)
    assert _refused(capsys, tables, tmp_path / "o") == (
        f"lmsbench figures: error: --tables {tables}: table signals's column ad_band holds str values, where the figures "
        "plot numbers: not a table of `lmsbench figures` or `lmsbench demo` (edited, or another program's?)")


@pytest.mark.parametrize("field, value, said", [
    # "internal error: TypeError: can only concatenate str (not "int") to str"
    ("signals_k", "abc", "signals_k: must be a whole number from 1 to 8192, the AD window of Figs. 4-6 (got 'abc')"),
    # drawn with AD_i-5 and its reference line, exit 0
    ("signals_k", -5, "signals_k: must be a whole number from 1 to 8192, the AD window of Figs. 4-6 (got -5)"),
    # "internal error: MemoryError: Unable to allocate 7.28 TiB", after figures.yaml
    ("signals_k", 10**12, "signals_k: must be a whole number from 1 to 8192, the AD window of Figs. 4-6 (got 1000000000000)"),
    ("world", [1, 2], "world: must be the name of the simulated world (got [1, 2])"),
    # each below was taken, exit 0, the figures drawn (fuzz round 6); a study writes none of them
    ("world", " ", "world: must be a built-in world's name (office, corridor, angles, pillars, random, cluttered, "
                   "mit) or a world.json path (got ' ')"),
    ("seed", "abc", "seed: must be a whole number from 0 (got 'abc')"),
    ("seed", -1, "seed: must be a whole number from 0 (got -1)"),
    ("duration", -5.0, "duration: must be a positive number of seconds (got -5.0)"),
    ("duration", float("nan"), "duration: must be a positive number of seconds (got nan)"),
    ("rate_hz", True, "rate_hz: must be a positive number of scans/s (got True)"),
    ("methods", "sensor", "methods: must be a list of extractor names (got 'sensor')"),
    ("methods", [], "methods: must be a list of extractor names (got [])"),
    ("panels", 0, "panels: must be a whole number from 1 to 16 (got 0)"),
    ("slam", "no", "slam: must be true or false (got 'no')"),  # taken as true: "table trajectory is missing"
    ("intel_log", 7, "intel_log: must be a log's path or null (got 7)"),
    ("resolved", [1], "resolved: must be a mapping (got [1])"),
    ("sensor", "x", "sensor: must be a mapping (got 'x')"),
])
def test_a_study_yaml_field_the_figures_draw_with_is_checked(tables, tmp_path, capsys, field, value, said):
    settings = yaml.safe_load((tables / "study.yaml").read_text())
    (tables / "study.yaml").write_text(yaml.safe_dump({**settings, field: value}))
    assert _refused(capsys, tables, tmp_path / "o") == (
        f"lmsbench figures: error: {tables / 'study.yaml'}: not the study.yaml of lmsbench figures / demo ({said})")


def test_a_study_yaml_that_run_study_writes_from_python_is_taken(tables):
    """The check took the command line's bounds: a study run from Python with a world.json path or
    seed=2**40 (run_study takes both) was refused as no study.yaml of lmsbench (review)."""
    from experiments.figures.study import load_config

    settings = yaml.safe_load((tables / "study.yaml").read_text())
    (tables / "study.yaml").write_text(yaml.safe_dump({**settings, "world": "/tmp/w/world.json", "seed": 2**40,
                                                       "duration": 0.05, "rate_hz": 1e-4}))
    cfg = load_config(tables)
    assert (cfg.world, cfg.seed, cfg.duration, cfg.rate_hz) == ("/tmp/w/world.json", 2**40, 0.05, 1e-4)


def test_binary_notes_and_a_table_of_column_levels_are_refused(tables, tmp_path, capsys):
    (tables / "notes.txt").write_bytes(b"\xff\xfe\x00")
    # "internal error: UnicodeDecodeError"
    assert _refused(capsys, tables, tmp_path / "o") == (
        f"lmsbench figures: error: {tables / 'notes.txt'}: not UTF-8 text (byte 0); a study's notes are a text file")
    (tables / "notes.txt").write_text("")
    frame = pd.read_parquet(tables / "timing.parquet")
    frame.columns = pd.MultiIndex.from_tuples([(c, "a") for c in frame.columns])
    frame.to_parquet(tables / "timing.parquet")
    # "internal error: AttributeError: 'DataFrame' object has no attribute 'dtype'"
    assert _refused(capsys, tables, tmp_path / "o") == (
        f"lmsbench figures: error: {tables / 'timing.parquet'}: its column ('method', 'a') is no plain name (a table of "
        "named columns, one level, as `lmsbench figures` saves them)")


def test_an_empty_sweep_table_is_said_empty(sweeps, tables, tmp_path, capsys):
    import shutil

    folder = tmp_path / "s"
    shutil.copytree(sweeps["k"], folder)
    pd.read_parquet(folder / "results.parquet").iloc[:0].to_parquet(folder / "results.parquet", index=False)
    # it said "no successful cell to plot (0 cells, all failed; their `error` column says why)"
    assert _sweep_refused(capsys, tables, folder, tmp_path / "o") == (
        f"lmsbench figures: error: --sweep {folder / 'results.parquet'}: an empty table (no cell); run the sweep again "
        "into its folder to write it")


@pytest.mark.parametrize("value, said", [("0.5", "str"), ([0.5], "object")])
def test_a_sweep_metric_of_text_is_refused(sweeps, tables, tmp_path, capsys, value, said):
    import shutil

    folder = tmp_path / "s"
    shutil.copytree(sweeps["k"], folder)
    table = pd.read_parquet(folder / "results.parquet")
    table["f1"] = [value] * len(table)
    table.to_parquet(folder / "results.parquet", index=False)
    # "internal error: TypeError: dtype 'str' does not support operation 'mean'" (lists: "agg function failed")
    assert _sweep_refused(capsys, tables, folder, tmp_path / "o") == (
        f"lmsbench figures: error: --sweep {folder}: its results.parquet's column f1 holds {said} values, where a "
        "sweep's metric is a number: a damaged or edited table, or not one of `lmsbench sweep`")


def test_a_sweep_metric_of_no_finite_value_is_not_plotted(sweeps, tables, tmp_path, capsys):
    import shutil

    folder = tmp_path / "s"
    shutil.copytree(sweeps["k"], folder)
    table = pd.read_parquet(folder / "results.parquet")
    table["f1"] = np.inf
    table.to_parquet(folder / "results.parquet", index=False)
    out = tmp_path / "o"
    assert main(["figures", "--tables", str(_only(tables, "timing")), "--sweep", str(folder), "--out", str(out)]) == 0, \
        capsys.readouterr().err
    assert not (out / "sweep_k_f1.png").exists()  # an empty plot of all inf was drawn
    assert (out / "sweep_k_corner_f1.png").is_file()


@pytest.mark.parametrize("name", ["../../outside", ["a", "b"], "", "a" * 300])
def test_a_sweep_name_that_is_no_plain_name_is_refused(sweeps, tables, tmp_path, capsys, name):
    import shutil

    folder = tmp_path / "deep" / "er" / "s"
    shutil.copytree(sweeps["k"], folder)
    spec = yaml.safe_load((folder / "sweep.yaml").read_text())
    (folder / "sweep.yaml").write_text(yaml.safe_dump({**spec, "name": name}))
    out = tmp_path / "deep" / "er" / "o"
    # "../../outside" wrote its plots beside --out, through a folder sweep_.. it made there, exit 0
    err = _sweep_refused(capsys, tables, folder, out)
    assert err.startswith(f"lmsbench figures: error: --sweep {folder}: its sweep.yaml's name: "), err
    assert err.endswith("is no name a file can take (text of at most 150 characters, without / and not starting with .), "
                        "and it names the sweep's plots (sweep_NAME_METRIC): not a sweep.yaml `lmsbench sweep` wrote (edited?)")
    assert sorted(p.name for p in (tmp_path / "deep" / "er").iterdir()) == ["s"]


def test_times_scores_and_positions_at_the_bounds_and_nan_rows_are_taken(tables) -> None:
    """The review of round 7: the checks above refuse nothing at their bounds (1 ns and a day a scan, F1 0
    and 1, +-1e9 m) nor a NaN row (a method with no time, a row lmsbench leaves empty on purpose)."""
    from experiments.figures.make import check_tables

    frames = {name: pd.read_parquet(tables / f"{name}.parquet") for name in ("timing", "trajectory", "map")}
    frames["timing"]["time_ms"] = [1e-6, 8.64e7, np.nan]
    frames["trajectory"]["x"] = [1e9, -1e9, np.nan, 0.0]
    frames["map"]["y2"] = [-1e9, np.nan]
    frames["summary"] = pd.DataFrame({"method": ["sensor", "iepf", "hough"], "f1": [0.0, 1.0, np.nan],
                                      "time_ms_median": [1e-6, 0.05, np.nan], "time_ms_p25": [1e-6, 0.04, np.nan],
                                      "time_ms_p75": [1e-6, 0.06, np.nan]})
    check_tables(frames, str(tables))  # raises on a refused value
    frames["timing"].loc[0, "time_ms"] = 0.9e-6  # and just beyond a bound is refused (the test can fail)
    with pytest.raises(LmsbenchError, match=r"holds 9e-07 \(row 0\), which is no time per scan"):
        check_tables(frames, str(tables))
