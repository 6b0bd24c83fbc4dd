"""One rule for every command's --out folder (options.Owner): a file of an output name is replaced
only when what the command left tells an earlier run of it wrote it; otherwise the run is refused
before any work, one line, exit 2, the file kept. check_out went by file names alone: a user's
config.yaml, summary.txt, sim2real.md, bench.csv or results.csv in a folder of nothing else was
written over. Outputs never overwrite inputs: `slam RUN --config DIR/config.yaml --out DIR` wrote
the resolved settings over the given file."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from experiments.cli import main
from experiments.options import BENCH_OUTPUTS, BENCH_OWNER, DEMO_SWEEP, SIM2REAL_OUTPUTS, SIM2REAL_OWNER, SIM2REAL_UNFINISHED, SWEEP_OUTPUTS, SWEEP_OWNER, OutTree


@pytest.fixture(scope="module")
def sim(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("sim") / "run"
    assert main(["simulate", "--duration", "2", "--out", str(out), "--quiet"]) == 0
    return out


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory) -> Path:
    f = tmp_path_factory.mktemp("sw") / "sweep.yaml"
    f.write_text(yaml.safe_dump({"name": "t", "kind": "extract", "fixed": {"duration": 0.5}, "grid": {"extractor.k": [3]}}))
    return f


def _refused(capsys, argv: list[str], folder: Path, name: str, command: str) -> None:
    before = (folder / name).read_bytes()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.splitlines() == [f"lmsbench {command}: error: --out {folder}: holds {name}, which this run would replace "
                                f"but no earlier lmsbench {command} run wrote; give a new or empty folder"], err
    assert (folder / name).read_bytes() == before
    assert sorted(p.name for p in folder.iterdir()) == [name]


@pytest.mark.parametrize("command, name, argv", [
    ("simulate", "config.yaml", ["simulate", "--duration", "1", "--quiet"]),
    ("simulate", "map.png", ["simulate", "--duration", "1", "--quiet"]),
    ("slam", "config.yaml", ["slam", "{sim}", "--quiet"]),
    ("compare", "summary.txt", ["compare", "office", "--duration", "1", "--seeds", "1"]),
    ("compare", "config.yaml", ["compare", "office", "--duration", "1", "--seeds", "1"]),
    ("sim2real", "sim2real.md", ["sim2real", "{sim}/scans.clf"]),
    ("sim2real", "config.yaml", ["sim2real", "{sim}/scans.clf"]),
    ("bench", "bench.csv", ["bench", "lms200"]),
    ("sweep", "results.csv", ["sweep", "{sweep}", "--inprocess"]),
])
def test_a_users_file_of_an_output_name_is_refused(sim, sweep_file, tmp_path, capsys, command, name, argv):
    """Before: the folder passed by its file names and the run wrote over the user's file, exit 0."""
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / name).write_text("my notes\n")
    argv = [a.format(sim=sim, sweep=sweep_file) for a in argv] + ["--out", str(folder)]
    _refused(capsys, argv, folder, name, command)


@pytest.mark.slow
def test_rerun_into_its_own_folder_is_accepted(sim, tmp_path, capsys):
    """simulate, slam and compare run twice into one folder: the second run replaces the first's outputs."""
    sim2 = tmp_path / "sim"
    for _ in range(2):
        assert main(["simulate", "--duration", "1", "--out", str(sim2), "--quiet"]) == 0
    slam = tmp_path / "slam"
    for _ in range(2):
        assert main(["slam", str(sim), "--out", str(slam), "--quiet"]) == 0
    cmp = tmp_path / "cmp"
    for _ in range(2):
        assert main(["compare", "office", "--duration", "1", "--seeds", "1", "--out", str(cmp)]) == 0
    assert (cmp / "summary.txt").is_file() and (slam / "metrics.json").is_file() and (sim2 / "map.png").is_file()


def test_compare_run_again_leaves_none_of_the_earlier_runs_outputs_beside_its_own(sim, tmp_path, capsys):
    """`compare a.clf --out D` then `compare b.clf --out D` left a.clf's realdata_* figure and rows
    beside a summary of b.clf alone, and a `--format csv` run left the earlier run's compare.parquet
    beside its compare.csv: files of another run shown as this run's (slam removes its earlier
    outputs alike)."""
    import shutil

    for name in ("a.clf", "b.clf"):
        shutil.copy(sim / "scans.clf", tmp_path / name)
    out = tmp_path / "cmp"
    base = ["--methods", "sensor", "--max-scans", "3", "--no-progress", "--out", str(out)]
    assert main(["compare", str(tmp_path / "a.clf"), *base]) == 0
    assert {p.name for p in out.iterdir()} >= {"compare.parquet", "realdata_a_clf.png", "realdata_a_clf.csv"}
    capsys.readouterr()
    (out / "realdata_notes.csv").write_text("mine\n")  # a user's file of a name compare's realdata_* matched: kept
    assert main(["compare", str(tmp_path / "b.clf"), *base, "--format", "csv"]) == 0
    assert (out / "realdata_notes.csv").read_text() == "mine\n"  # it was removed as the earlier run's (round 11)
    (out / "realdata_notes.csv").unlink()
    written = sorted(p.name for p in out.iterdir())
    assert written == [
        "compare.csv", "config.yaml", "realdata_b_clf.csv", "realdata_b_clf.pdf", "realdata_b_clf.png",
        "summary.csv", "summary.txt"]
    assert sorted(yaml.safe_load((out / "config.yaml").read_text())["figures"]) == written[2:5]
    wrote = [line for line in capsys.readouterr().out.splitlines() if line.startswith("wrote ")]
    assert sorted(Path(p).name for p in wrote[0][len("wrote "):].split(", ")) == written  # the .pdf and .csv were left out


def test_slam_config_in_out_is_refused(sim, tmp_path, capsys):
    """`slam RUN --config DIR/config.yaml --out DIR` wrote the resolved settings over the given file."""
    out = tmp_path / "slam"
    assert main(["slam", str(sim), "--out", str(out), "--quiet"]) == 0
    cfg = out / "config.yaml"
    before = cfg.read_bytes()
    capsys.readouterr()
    assert main(["slam", str(sim), "--config", str(cfg), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.splitlines() == [f"lmsbench slam: error: --out {out}: the run would write config.yaml over {cfg}, which it "
                                "reads; give another folder"], err
    assert cfg.read_bytes() == before


def test_simulate_config_in_out_is_refused(sim, capsys):
    assert main(["simulate", "--config", str(sim / "config.yaml"), "--out", str(sim), "--quiet"]) == 2
    assert "the run would write config.yaml over" in capsys.readouterr().err


def test_slam_into_its_input_folder_says_so(sim, capsys):
    """`slam RUN --out RUN` was refused as "holds groundtruth.tum, map.png, scans.clf and 1 more,
    which this command does not write": true, but not why."""
    names = sorted(p.name for p in sim.iterdir())
    assert main(["slam", str(sim), "--out", str(sim), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.splitlines() == [f"lmsbench slam: error: --out {sim} is the input folder {sim}, which the run reads; "
                                "give another folder for its outputs"], err
    assert sorted(p.name for p in sim.iterdir()) == names
    for command in ("sim2real",):  # the same rule (compare names the config.yaml it would write over)
        assert main([command, str(sim), "--out", str(sim)]) == 2
        assert capsys.readouterr().err.splitlines() == [
            f"lmsbench {command}: error: --out {sim} is the input folder {sim}, which the run reads; give another "
            "folder for its outputs"]


def test_simulate_world_in_out_is_refused(sim, tmp_path, capsys):
    """`simulate --world DIR/world.json --out DIR` wrote world.json over the file it read (so did a
    --config naming that world.json)."""
    world = sim / "world.json"
    before = world.read_bytes()
    assert main(["simulate", "--world", str(world), "--duration", "1", "--out", str(sim), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.splitlines() == [f"lmsbench simulate: error: --out {sim}: the run would write world.json over {world}, "
                                "which it reads; give another folder"], err
    cfg = tmp_path / "run.yaml"
    cfg.write_text(yaml.safe_dump({"world": str(world), "seed": 0, "duration": 1.0}))
    assert main(["simulate", "--config", str(cfg), "--out", str(sim), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.splitlines() == [f"lmsbench simulate: error: --out {sim}: the run would write world.json over {world}, "
                                "which it reads; give another folder"], err
    assert world.read_bytes() == before


def test_what_bench_sim2real_and_sweep_tell_as_their_own(tmp_path):
    """The records the slower commands leave (their own formats) make the folder theirs; a figure or
    table alone, or a record of another kind, does not."""
    b = tmp_path / "bench"
    b.mkdir()
    (b / "bench.csv").write_text("area,case,method\nlms200,x,y\n")
    (b / "versions.yaml").write_text(yaml.safe_dump({"benchmarks": ["lms200"], "quick": True, "versions": {}}))
    assert BENCH_OWNER.foreign(b, OutTree(BENCH_OUTPUTS)) == []
    (b / "bench.csv").write_text("a,b\n")
    (b / "versions.yaml").write_text("python: 3.11\n")
    assert BENCH_OWNER.foreign(b, OutTree(BENCH_OUTPUTS)) == ["bench.csv", "versions.yaml"]
    s = tmp_path / "s2r"
    s.mkdir()
    (s / "sim2real.png").write_bytes(b"\x89PNG")
    assert SIM2REAL_OWNER.foreign(s, OutTree(SIM2REAL_OUTPUTS)) == ["sim2real.png"]
    (s / "config.yaml").write_text(yaml.safe_dump({"log": "x.clf", "world": "mit"}))  # not all of its keys
    assert SIM2REAL_OWNER.foreign(s, OutTree(SIM2REAL_OUTPUTS)) == ["config.yaml", "sim2real.png"]
    (s / "config.yaml").write_text(yaml.safe_dump({"log": "x.clf", "world": "mit", "seeds": [0], "probe_seeds": [0],
                                                   "robot": {}, "checks": {}}))
    assert SIM2REAL_OWNER.foreign(s, OutTree(SIM2REAL_OUTPUTS)) == []
    w = tmp_path / "sweep"
    (w / "cells").mkdir(parents=True)
    (w / "cells" / "a.parquet").write_bytes(b"PAR1")
    assert SWEEP_OWNER.foreign(w, SWEEP_OUTPUTS) == ["cells/a.parquet"]
    (w / "sweep.yaml").write_text("name: t\nkind: extract\n")
    assert SWEEP_OWNER.foreign(w, SWEEP_OUTPUTS) == []


def test_demo_refuses_a_users_report_and_tells_its_own_folder(tmp_path, capsys):
    """`demo --out DIR`, DIR holding the user's own report.md: written over before; now refused.
    A folder with the demo's study settings (tables/study.yaml, written first) is its own."""
    from experiments.options import DEMO_OUTPUTS, DEMO_OWNER

    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "report.md").write_text("# my report\n")
    _refused(capsys, ["demo", "--no-sweep", "--out", str(mine)], mine, "report.md", "demo")
    own = tmp_path / "own"
    (own / "tables").mkdir(parents=True)
    (own / "report.md").write_text("# lmsbench demo: fast feature extraction in sensor coordinates\n")
    assert DEMO_OWNER.foreign(own, DEMO_OUTPUTS) == []
    (own / "report.md").write_text("# my report\n")
    (own / "tables" / "summary.parquet").write_bytes(b"PAR1")
    assert DEMO_OWNER.foreign(own, DEMO_OUTPUTS) == ["report.md", "tables/summary.parquet"]
    (own / "tables" / "study.yaml").write_text(yaml.safe_dump({"world": "office", "seed": 0, "duration": 5.0,
                                                               "resolved": {"sensor": {}}}))
    assert DEMO_OWNER.foreign(own, DEMO_OUTPUTS) == ["report.md"]  # a record that says otherwise stays the user's
    (own / "report.md").unlink()
    assert DEMO_OWNER.foreign(own, DEMO_OUTPUTS) == []  # an interrupted demo's tables


def test_bench_runs_again_into_its_own_folder(tmp_path, monkeypatch, capsys):
    """`lmsbench bench features --out DIR` twice: the second run refused DIR ("holds bench.csv ...
    no earlier lmsbench bench run wrote"), as bench.csv was told by a header starting area,case,
    while its second column is the first area's own first key (features: benchmark; sim: world).
    Found by running bench twice after a431e72. Areas stubbed with each real area's first keys."""
    import types

    import experiments.commands.bench as bench

    areas = {name: types.SimpleNamespace(run=lambda quick, k=key: [{k: "x", "scans_per_s": 1.0}])
             for name, key in (("features", "benchmark"), ("sim", "world"), ("slam", "case"))}
    monkeypatch.setattr(bench, "discover", lambda: areas)
    out = tmp_path / "b"
    for names in (["features"], ["sim", "slam"], ["slam"]):
        assert main(["bench", *names, "--out", str(out)]) == 0, capsys.readouterr().err
        assert (out / "bench.csv").read_text().startswith("area,")
    with monkeypatch.context() as m:  # stopped at its bench.csv: the earlier run's was left beside its versions.yaml
        _stop_at_write(m, out, 2)
        assert main(["bench", "features", "--out", str(out)]) == 130
    assert yaml.safe_load((out / "versions.yaml").read_text())["benchmarks"] == ["features"]
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == ["versions.yaml"]
    assert main(["bench", "features", "--out", str(out)]) == 0, capsys.readouterr().err
    (out / "bench.csv").write_text("region,area\n")  # not bench's own: refused, left as it is
    (out / "versions.yaml").unlink()
    assert main(["bench", "slam", "--out", str(out)]) == 2
    assert "holds bench.csv, which this run would replace but no earlier lmsbench bench run wrote" in capsys.readouterr().err
    assert (out / "bench.csv").read_text() == "region,area\n"


@pytest.fixture(scope="module")
def tables(tmp_path_factory) -> Path:
    """The smallest tables folder a figure is drawn from: the study's settings and a timing table
    (Fig. 7 alone, about a second)."""
    import pandas as pd

    t = tmp_path_factory.mktemp("tables")
    (t / "study.yaml").write_text(yaml.safe_dump({"world": "office", "seed": 0, "duration": 1.0, "resolved": {"sensor": {}}}))
    pd.DataFrame({"method": ["sensor"] * 3, "scan": [0, 1, 2], "time_ms": [0.05, 0.04, 0.06]}).to_parquet(
        t / "timing.parquet", index=False)
    return t


@pytest.mark.parametrize("name", ["fig7_timing.png", "accuracy_speed.csv", "fig3_scan_lines.csv"])
@pytest.mark.parametrize("study", [[], ["--no-slam", "--duration", "1", "--rate-hz", "2", "--methods", "sensor"]])
def test_figures_refuses_a_users_file_of_a_figure_name(tables, tmp_path, capsys, name, study):
    """`figures --out DIR` went by names alone: a user's own fig7_timing.png or accuracy_speed.csv
    in DIR was written over, exit 0. Now refused before any work, the file kept (redrawing from
    --tables as computing the study)."""
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / name).write_bytes(b"\x89PNG my own figure\n")
    argv = ["figures", *(study or ["--tables", str(tables)]), "--out", str(folder)]
    _refused(capsys, argv, folder, name, "figures")


@pytest.mark.slow
def test_figures_runs_again_into_its_own_folder_and_a_demos(tables, tmp_path, capsys):
    """A second `figures` into its own folder replaces its figures (its figures.yaml, written
    first, tells the folder); so does a folder of a run before figures.yaml (tables/study.yaml),
    and a demo's figures/ (`figures --tables DEMO/tables --out DEMO/figures`), which the next demo
    into DEMO still takes as its own. A figures/ folder in a folder the demo did not write is not."""
    from experiments.options import DEMO_OUTPUTS, DEMO_OWNER, FIGURES_OUTPUTS, FIGURES_OWNER

    own = tmp_path / "own"
    for _ in range(2):
        assert main(["figures", "--tables", str(tables), "--out", str(own)]) == 0, capsys.readouterr().err
    assert yaml.safe_load((own / "figures.yaml").read_text())["command"] == "lmsbench figures"
    assert sorted(p.name for p in own.iterdir()) == ["fig7_timing.csv", "fig7_timing.pdf", "fig7_timing.png", "figures.yaml"]
    older = tmp_path / "older"  # a run before figures.yaml: its tables' settings tell it
    (older / "tables").mkdir(parents=True)
    (older / "tables" / "study.yaml").write_text((tables / "study.yaml").read_text())
    (older / "fig7_timing.png").write_bytes(b"old")
    assert FIGURES_OWNER.foreign(older, FIGURES_OUTPUTS) == []
    demo = tmp_path / "demo"
    (demo / "figures").mkdir(parents=True)
    (demo / "tables").mkdir()
    for name in ("study.yaml", "timing.parquet"):  # the demo's own tables: only they redraw its figures
        (demo / "tables" / name).write_bytes((tables / name).read_bytes())
    (demo / "figures" / "fig7_timing.png").write_bytes(b"the demo's")
    assert main(["figures", "--tables", str(demo / "tables"), "--out", str(demo / "figures")]) == 0, capsys.readouterr().err
    assert (demo / "figures" / "fig7_timing.png").read_bytes().startswith(b"\x89PNG")
    assert DEMO_OWNER.foreign(demo, DEMO_OUTPUTS) == [] and DEMO_OUTPUTS.foreign(demo) == []
    pre = tmp_path / "pre"  # `figures --tables T --out DIR` before figures.yaml: no table, no record
    assert main(["figures", "--tables", str(tables), "--out", str(pre)]) == 0, capsys.readouterr().err
    (pre / "figures.yaml").unlink()  # was refused: "no earlier lmsbench figures run wrote"
    (pre / "fig4_ad.csv").write_text("beam,bearing_deg,range_m,ad,ad_band,theta_deg,psi_deg,reference\n")  # as it wrote
    assert main(["figures", "--tables", str(tables), "--out", str(pre)]) == 0, capsys.readouterr().err
    other = tmp_path / "other" / "figures"
    other.mkdir(parents=True)
    (other / "fig7_timing.png").write_bytes(b"mine")
    _refused(capsys, ["figures", "--tables", str(tables), "--out", str(other)], other, "fig7_timing.png", "figures")


def _stop_at_write(monkeypatch, folder: Path, n: int) -> None:
    """Ctrl-C (KeyboardInterrupt) as the ``n``-th file in ``folder`` is opened for writing, that file
    left created and empty, as a stop between its open and its write leaves it: files opened with
    open() (text, YAML, JSON, CSV, TUM, figures) and Parquet tables."""
    import builtins
    import io
    import os

    import pandas as pd

    opened, real_open, real_parquet = [], io.open, pd.DataFrame.to_parquet

    def stop(file) -> bool:
        inside = isinstance(file, (str, os.PathLike)) and Path(file).absolute().is_relative_to(folder.absolute())
        opened.extend([file] if inside else [])
        return inside and len(opened) == n

    def open_(file, mode="r", *args, **kwargs):
        if any(c in mode for c in "wxa") and stop(file):
            real_open(file, mode).close()
            raise KeyboardInterrupt
        return real_open(file, mode, *args, **kwargs)

    def to_parquet(self, path, *args, **kwargs):
        if stop(path):
            Path(path).write_bytes(b"")
            raise KeyboardInterrupt
        return real_parquet(self, path, *args, **kwargs)

    monkeypatch.setattr(builtins, "open", open_)
    monkeypatch.setattr(io, "open", open_)
    monkeypatch.setattr(pd.DataFrame, "to_parquet", to_parquet)


def _stubbed_bench(monkeypatch) -> None:
    import types

    import experiments.commands.bench as bench

    monkeypatch.setattr(bench, "discover", lambda: {"slam": types.SimpleNamespace(run=lambda quick: [{"case": "x", "hz": 1.0}])})


@pytest.mark.parametrize("n", [1, 2])
@pytest.mark.parametrize("argv", [
    ["simulate", "--duration", "1", "--quiet"],
    ["slam", "{sim}", "--quiet"],
    ["compare", "office", "--duration", "1", "--seeds", "1"],
    ["bench", "slam"],
    ["sweep", "{sweep}", "--inprocess", "--no-progress"],
    ["figures", "--tables", "{tables}"],
], ids=lambda argv: argv[0])
def test_a_run_stopped_at_its_first_files_leaves_a_folder_the_next_run_takes(sim, sweep_file, tables, tmp_path,
                                                                             capsys, monkeypatch, argv, n):
    """A run stopped (Ctrl-C, kill) before it wrote a file that tells its folder left files the next
    run into the same --out refused ("holds scans.clf, which this run would replace but no earlier
    lmsbench simulate run wrote"): simulate's scans.clf, slam's trajectory.tum, compare's
    compare.parquet, all written before their config.yaml; a cut (empty) sweep.yaml or bench.csv.
    Each command now writes a record first and whole (provenance.write_record). Found by stopping
    each command at its first and second file."""
    argv = [a.format(sim=sim, sweep=sweep_file, tables=tables) for a in argv]
    out = tmp_path / "out"
    if argv[0] == "bench":
        _stubbed_bench(monkeypatch)
    with monkeypatch.context() as m:
        _stop_at_write(m, out, n)
        assert main(argv + ["--out", str(out)]) == 130
    assert capsys.readouterr().err.splitlines()[-1:] == [f"lmsbench {argv[0]}: interrupted"]
    assert main(argv + ["--out", str(out)]) == 0, capsys.readouterr().err
    assert not [p for p in out.rglob(".*")]  # no temporary file left behind


@pytest.mark.slow
def test_a_demo_or_sim2real_stopped_at_its_first_files_is_taken_by_the_next_run(sim, tmp_path, capsys, monkeypatch):
    """The same for the slower commands: a demo stopped among its tables (Parquet files before
    tables/study.yaml) and sim2real stopped after sim2real.csv were refused by the next run. The
    next demo is stopped again at its first file (it got past the check: 130, not 2); the study
    it runs is stubbed with a timing table."""
    import pandas as pd

    import experiments.demo

    timing = pd.DataFrame({"method": ["sensor"], "scan": [0], "time_ms": [0.05]})
    monkeypatch.setattr(experiments.demo, "run_study", lambda cfg, log=print: ({"timing": timing, "summary": timing}, []))
    demo = tmp_path / "demo"
    for n in (2, 1):
        with monkeypatch.context() as m:
            _stop_at_write(m, demo, n)
            assert main(["demo", "--no-sweep", "--duration", "1", "--out", str(demo)]) == 130, capsys.readouterr().err
        assert capsys.readouterr().err.splitlines()[-1:] == ["lmsbench demo: interrupted"]
    s2r = tmp_path / "s2r"
    argv = ["sim2real", str(sim / "scans.clf"), "--world", "office", "--seeds", "0", "--duration", "2", "--rate-hz", "1",
            "--stride", "4", "--max-scans", "10", "--fit-duration", "1", "--out", str(s2r)]  # the fit: 1 s runs, not 30
    with monkeypatch.context() as m:  # at its figure (files: the marker, config.yaml, the tables, the report, the figure)
        _stop_at_write(m, s2r, 6)
        assert main(argv) == 130
    capsys.readouterr()
    # the tables and report without the figure and sensor.yaml: said by the marker (there was none), which holds the settings
    assert sorted(p.name for p in s2r.iterdir() if not p.name.endswith(".tmp")) == [
        SIM2REAL_UNFINISHED, "config.yaml", "scene.csv", "sim2real.csv", "sim2real.md"]
    assert (s2r / SIM2REAL_UNFINISHED).read_text().split("\n")[2:] == (s2r / "config.yaml").read_text().split("\n")
    assert main(argv) == 0, capsys.readouterr().err
    assert sorted(p.name for p in s2r.iterdir()) == sorted(SIM2REAL_OUTPUTS)  # the marker and temporary files gone


def _finished_sweep(folder: Path, raw: dict) -> list[str]:
    """A sweep folder as a finished run of ``raw`` leaves it (sweep.yaml, results.parquet of every cell with
    an f1, the cells' files), without computing a cell; returns its cell files' names (``cells/KEY.parquet``)."""
    import pandas as pd

    from experiments.sweep import SweepSpec, cell_key
    from experiments.sweep.runner import spec_record

    spec = SweepSpec.from_dict(raw)
    rows = [{**params, "f1": 0.5 + 0.01 * i, "status": "ok", "error": "", "elapsed_s": 0.1,
             "cell": cell_key(spec.kind, params)} for i, params in enumerate(spec.cells())]
    (folder / "cells").mkdir(parents=True, exist_ok=True)
    (folder / "sweep.yaml").write_text(spec_record(spec))
    pd.DataFrame(rows).to_parquet(folder / "results.parquet", index=False)
    for row in rows:
        pd.DataFrame([row]).to_parquet(folder / "cells" / f"{row['cell']}.parquet", index=False)
    return [f"cells/{row['cell']}.parquet" for row in rows]


def test_a_demo_run_again_leaves_no_figures_record_beside_its_own_figures(tmp_path, capsys, monkeypatch):
    """`figures --tables DEMO/tables --out DEMO/figures` leaves its figures.yaml there; the next
    demo into DEMO redrew the figures and kept it, a record of a figures run (its tables, its
    versions) beside figures the demo drew (a review). The demo removes it; the study and sim2real are stubbed.
    So are the earlier demo's files this one does not write again: with --no-sweep or without the
    sim2real log its sweep, sweep plots and sim2real files stayed beside the new report as its own."""
    import pandas as pd

    import experiments.demo

    timing = pd.DataFrame({"method": ["sensor"], "scan": [0], "time_ms": [0.05]})
    monkeypatch.setattr(experiments.demo, "run_study", lambda cfg, log=print: ({"timing": timing, "summary": timing}, []))
    monkeypatch.setattr(experiments.demo, "_sim2real_section", lambda cfg, out, log: None)
    demo, argv = tmp_path / "demo", ["demo", "--no-sweep", "--duration", "1", "--out", str(tmp_path / "demo")]
    assert main(argv) == 0, capsys.readouterr().err
    assert main(["figures", "--tables", str(demo / "tables"), "--out", str(demo / "figures")]) == 0
    assert (demo / "figures" / "figures.yaml").is_file()
    earlier = ["figures/sweep_demo_k_vs_noise_f1.png", "figures/sweep_demo_k_vs_noise_f1.csv", "sim2real/sim2real.csv",
               "tables/trajectory.parquet"]
    for name in earlier:  # an earlier demo's (with its sweep, sim2real and SLAM), as its report.md tells them
        (demo / name).parent.mkdir(parents=True, exist_ok=True)
        (demo / name).write_bytes(b"earlier")
    _finished_sweep(demo / "sweeps" / "demo_k_vs_noise", DEMO_SWEEP)  # its cells by their keys
    # a user's files of names the demo's patterns matched (figures/sweep_demo_k_vs_noise_*, cells/*.parquet) stay:
    # they were removed with the earlier demo's (round 11); the earlier demo's own are named exactly
    mine = ["figures/sweep_demo_k_vs_noise_notes.csv", "sweeps/demo_k_vs_noise/cells/mine.parquet"]
    for name in mine:
        (demo / name).write_bytes(b"mine")
    assert main(argv) == 0, capsys.readouterr().err
    assert all((demo / name).read_bytes() == b"mine" for name in mine)
    assert sorted(p.name for p in (demo / "figures").iterdir()) == [
        "fig7_timing.csv", "fig7_timing.pdf", "fig7_timing.png", "sweep_demo_k_vs_noise_notes.csv"]
    assert sorted(str(p.relative_to(demo / "sweeps")) for p in (demo / "sweeps").rglob("*")) == [
        "demo_k_vs_noise", "demo_k_vs_noise/cells", "demo_k_vs_noise/cells/mine.parquet"]
    assert sorted(p.name for p in demo.iterdir()) == ["figures", "report.html", "report.md", "sweeps", "tables"]
    assert sorted(p.name for p in (demo / "tables").iterdir()) == ["notes.txt", "study.yaml", "summary.parquet", "timing.parquet"]


def test_figures_run_again_removes_the_earlier_runs_files_it_does_not_write(tables, tmp_path, capsys, monkeypatch):
    """`figures --no-slam --out D` over a run with SLAM left its fig10_slam.* and tables/trajectory.parquet
    beside its own, exit 0: `figures --tables D/tables` then drew Fig. 10 of the earlier study as the new
    one's (its study.yaml said slam: false); a run stopped while drawing left the earlier run's figures
    beside its first ones. The earlier run's files go before this run writes its own (--tables: its
    figures; the study is stubbed with a timing table)."""
    import pandas as pd

    import experiments.figures.study as study

    timing = pd.read_parquet(tables / "timing.parquet")
    monkeypatch.setattr(study, "run_study", lambda cfg, log=print: ({"timing": timing}, []))
    monkeypatch.setattr(study, "check_panel_log", lambda cfg: None)
    out = tmp_path / "out"
    computed = ["figures", "--no-slam", "--duration", "1", "--methods", "sensor", "--out", str(out)]
    figures = ["fig7_timing.csv", "fig7_timing.pdf", "fig7_timing.png"]
    redrawn = ["figures", "--tables", str(tables), "--out", str(out)]
    for argv in (computed, redrawn):
        assert main(argv) == 0, capsys.readouterr().err
        for name in ("fig10_slam.png", "fig10_slam_map.csv", "tables/trajectory.parquet"):
            (out / name).write_bytes(b"earlier")  # a run's with SLAM (figures.yaml tells them)
        # a user's files that match the figures' patterns (sweep_*, STEM_*.csv) are no output of a run: kept
        # (the review of round 10: removed with the earlier run's files, silently)
        mine = ["fig3_scan_extra.csv", "sweep_mynotes.csv"]
        for name in mine:
            (out / name).write_bytes(b"mine")
        assert main(argv) == 0, capsys.readouterr().err
        assert sorted(p.name for p in out.iterdir()) == sorted([*figures, *mine, "figures.yaml", "tables"])
        assert all((out / name).read_bytes() == b"mine" for name in mine)
        for name in mine:
            (out / name).unlink()
        # --tables from elsewhere writes no table: tables/ is left as it was
        left = ["notes.txt", "study.yaml", "timing.parquet"] + (["trajectory.parquet"] if argv is redrawn else [])
        assert sorted(p.name for p in (out / "tables").iterdir()) == left
    # an earlier --sweep run's plots, which its figures.yaml lists, go when a run without --sweep replaces it (they
    # stayed: README); a user's sweep_mynotes.csv stays
    sweep = tmp_path / "sw"
    _finished_sweep(sweep, {"name": "k", "kind": "extract", "grid": {"extractor.k": [3, 5]}})
    assert main([*redrawn, "--sweep", str(sweep)]) == 0, capsys.readouterr().err
    plots = ["sweep_k_f1.csv", "sweep_k_f1.pdf", "sweep_k_f1.png"]
    assert sorted(yaml.safe_load((out / "figures.yaml").read_text())["sweep_plots"]) == plots
    (out / "sweep_mynotes.csv").write_bytes(b"mine")
    assert main(redrawn) == 0, capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == sorted([*figures, "sweep_mynotes.csv", "figures.yaml", "tables"])


@pytest.mark.slow
def test_figures_without_tables_into_a_demos_figures_is_refused(tables, tmp_path, capsys, monkeypatch):
    """`figures --out DEMO/figures` without --tables computed a study of its own, drew its figures
    over some of the demo's and saved its tables in DEMO/figures/tables/; the next `demo --out DEMO`
    then refused DEMO, exit 2 ("holds figures/tables/, which this command does not write"). Found
    by a review; reproduced with `demo --no-sweep --duration 1 --rate-hz 2` and `figures --no-slam
    --duration 1 --rate-hz 2 --methods sensor --out DEMO/figures`. Now refused before any work, the
    demo's figures kept; redrawing them from the demo's tables still runs, and the demo takes DEMO
    again. The demo's study and sim2real are stubbed."""
    import pandas as pd

    import experiments.demo

    timing = pd.DataFrame({"method": ["sensor"], "scan": [0], "time_ms": [0.05]})
    monkeypatch.setattr(experiments.demo, "run_study", lambda cfg, log=print: ({"timing": timing, "summary": timing}, []))
    monkeypatch.setattr(experiments.demo, "_sim2real_section", lambda cfg, out, log: None)
    demo = tmp_path / "demo"
    argv = ["demo", "--no-sweep", "--duration", "1", "--out", str(demo)]
    assert main(argv) == 0, capsys.readouterr().err
    figures = demo / "figures"
    before = {p.name: p.read_bytes() for p in figures.iterdir()}
    capsys.readouterr()
    for out in (figures, demo / "sub" / ".." / "figures"):
        assert main(["figures", "--no-slam", "--duration", "1", "--rate-hz", "2", "--methods", "sensor",
                     "--out", str(out)]) == 2
        shown = out.parent
        assert capsys.readouterr().err.splitlines() == [
            f"lmsbench figures: error: --out {out}: the figures of the lmsbench demo in {shown}, drawn from its "
            "tables/ and shown in its report.md; without --tables this run computes a study of its own, whose figures "
            f"and tables would not match them: give --tables {shown / 'tables'} to redraw the demo's figures, or another --out"]
    assert {p.name: p.read_bytes() for p in figures.iterdir()} == before
    assert main(["figures", "--tables", str(demo / "tables"), "--out", str(figures)]) == 0, capsys.readouterr().err
    assert main(argv) == 0, capsys.readouterr().err
    # a figures/ folder of no demo: a study of its own, as before. The study is stubbed as the demo's
    # (a real one, with the Intel log present, drew eight figures: 13 of the test's 15 s); the
    # command's checks, its record, its tables and its drawing are the real ones
    import experiments.figures.study as study

    stub_study = lambda cfg, log=print: ({"timing": timing, "summary": timing}, [])  # noqa: E731
    monkeypatch.setattr(study, "run_study", stub_study)
    elsewhere = tmp_path / "other" / "figures"
    assert main(["figures", "--no-slam", "--duration", "1", "--rate-hz", "2", "--methods", "sensor",
                 "--out", str(elsewhere)]) == 0, capsys.readouterr().err
    assert (elsewhere / "tables" / "study.yaml").is_file() and (elsewhere / "fig7_timing.png").is_file()


def test_figures_from_another_studys_tables_into_a_demos_figures_is_refused(tables, tmp_path, capsys, monkeypatch):
    """`figures --tables X/tables --out DEMO/figures`, X another study's folder, drew X's figures over
    the demo's, exit 0: fig7_timing then showed X's three scans beside the demo's own fig10_slam and
    under its report.md, which still described the demo's study (a review, after 1f17742 refused the
    same without --tables). Now refused before any work, the demo's figures kept, pointing to a new
    --out; the demo's own tables, however named (through a link too), redraw them as before. The
    demo's study and sim2real are stubbed."""
    import pandas as pd

    import experiments.demo

    timing = pd.DataFrame({"method": ["sensor"], "scan": [0], "time_ms": [0.05]})
    monkeypatch.setattr(experiments.demo, "run_study", lambda cfg, log=print: ({"timing": timing, "summary": timing}, []))
    monkeypatch.setattr(experiments.demo, "_sim2real_section", lambda cfg, out, log: None)
    demo = tmp_path / "demo"
    assert main(["demo", "--no-sweep", "--duration", "1", "--out", str(demo)]) == 0, capsys.readouterr().err
    figures = demo / "figures"
    before = {p.name: p.read_bytes() for p in figures.iterdir()}
    capsys.readouterr()
    for out in (figures, demo / "sub" / ".." / "figures"):
        assert main(["figures", "--tables", str(tables), "--out", str(out)]) == 2
        shown = out.parent
        assert capsys.readouterr().err.splitlines() == [
            f"lmsbench figures: error: --out {out}: the figures of the lmsbench demo in {shown}, drawn from its "
            f"tables/ and shown in its report.md; figures drawn from --tables {tables}, not the demo's tables, would "
            f"not match them: give a new folder as --out, or --tables {shown / 'tables'} to redraw the demo's figures"]
    assert {p.name: p.read_bytes() for p in figures.iterdir()} == before
    (tmp_path / "link").symlink_to(demo / "tables")
    for own in (demo / "tables", demo / "figures" / ".." / "tables", tmp_path / "link"):
        assert main(["figures", "--tables", str(own), "--out", str(figures)]) == 0, capsys.readouterr().err
    assert pd.read_csv(figures / "fig7_timing.csv").shape[0] == 1  # the demo's one scan, not the other study's three
    fresh = tmp_path / "fresh"  # the other study's figures in a new folder: as before
    assert main(["figures", "--tables", str(tables), "--out", str(fresh)]) == 0, capsys.readouterr().err
    assert (fresh / "fig7_timing.png").is_file()


@pytest.mark.parametrize("table, frame, said", [
    # text where numbers are plotted: "internal error: TypeError: Cannot perform reduction 'median' with
    # string dtype", exit 1, after figures.yaml was written
    ("timing", {"method": ["sensor"] * 2, "scan": ["0", "1"], "time_ms": ["0.05", "0.04"]},
     "table timing's column scan holds"),
    # a trajectory and map as text: drawn on categorical axes, exit 0
    ("trajectory", {"source": ["truth", "slam"], "t": [0.0, 0.0], "x": ["1.0", "2.0"], "y": ["0", "1"]},
     "table trajectory's column x holds"),
    ("timing", {"method": ["sensor"], "t": [0.05]}, "table timing has no columns scan, time_ms, which the figures read"),
])
def test_figures_from_a_foreign_table_is_refused_before_any_output(tables, tmp_path, capsys, table, frame, said):
    """The wrong-input hunt: a table of a figure's name that lmsbench did not write (edited, or
    another program's) failed part-way through the drawing as an internal error, or was drawn."""
    import pandas as pd

    folder = tmp_path / "tables"
    folder.mkdir()
    (folder / "study.yaml").write_bytes((tables / "study.yaml").read_bytes())
    (folder / "timing.parquet").write_bytes((tables / "timing.parquet").read_bytes())
    if table == "trajectory":
        pd.DataFrame({"source": ["truth"], "x1": [0.0], "y1": [0.0], "x2": [1.0], "y2": [0.0]}).to_parquet(
            folder / "map.parquet", index=False)
    pd.DataFrame(frame).to_parquet(folder / f"{table}.parquet", index=False)
    out = tmp_path / "figs"
    assert main(["figures", "--tables", str(folder), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"lmsbench figures: error: --tables {folder}: {said}") and err.count("\n") == 1, err
    assert "not a table of `lmsbench figures` or `lmsbench demo` (edited, or another program's?)" in err
    assert not out.exists()


def test_figures_from_tables_whose_notes_are_a_pipe_is_refused_not_a_hang(tables, tmp_path, capsys):
    """The wrong-input hunt: a named pipe as a tables folder's notes.txt was read, and waited on for ever."""
    import os

    folder = tmp_path / "tables"
    folder.mkdir()
    for name in ("study.yaml", "timing.parquet"):
        (folder / name).write_bytes((tables / name).read_bytes())
    os.mkfifo(folder / "notes.txt")
    assert main(["figures", "--tables", str(folder), "--out", str(tmp_path / "figs")]) == 2
    assert capsys.readouterr().err == (f"lmsbench figures: error: {folder / 'notes.txt'}: not a regular file (a pipe, "
                                       "a device or a socket); a study's notes are a text file\n")


def test_a_study_yaml_larger_than_any_config_is_refused_unread(tmp_path):
    """study.yaml had no size bound, unlike every other YAML the commands read (a 30 MB one took
    10 s to parse); it now takes lms200.yamlio.MAX_YAML_BYTES, as config and sweep files do."""
    from experiments.figures.study import load_config
    from lms200 import LmsbenchError
    from lms200.yamlio import MAX_YAML_BYTES

    (tmp_path / "study.yaml").write_text("world: office\n" + "# padding\n" * (MAX_YAML_BYTES // 10 + 1))
    with pytest.raises(LmsbenchError, match=r"study.yaml: 1,048,5\d\d bytes, more than the 1,048,576"):
        load_config(tmp_path)
    (tmp_path / "study.yaml").write_text("world: office\nseed: 3\n")
    assert load_config(tmp_path).seed == 3


def test_a_read_only_output_is_refused_only_where_this_run_writes_it(sim, tmp_path, capsys, monkeypatch):
    """A review: check_out refused a read-only file of every name the command may write, patterns too, so
    `figures --out O` without --sweep was refused over O's read-only sweep_*.png ("which this run would
    replace"; it was left as it was). A read-only file of a pattern (an earlier run's realdata_* here) is
    removed as before; one of a name the run writes (summary.txt) is refused before any work. As root every
    file is writable, so "read-only" is what os.access says (the permission tests run as another user)."""
    import os
    import shutil

    from experiments import options

    for name in ("a.clf", "b.clf"):
        shutil.copy(sim / "scans.clf", tmp_path / name)
    out = tmp_path / "cmp"
    base = ["--methods", "sensor", "--max-scans", "3", "--no-progress", "--out", str(out)]
    assert main(["compare", str(tmp_path / "a.clf"), *base]) == 0
    read_only = {out / "realdata_a_clf.png"}
    real_access = os.access
    monkeypatch.setattr(options.os, "access", lambda p, mode, **kw: not (mode & os.W_OK and Path(p) in read_only)
                        and real_access(p, mode, **kw))
    capsys.readouterr()
    assert main(["compare", str(tmp_path / "b.clf"), *base]) == 0  # was 2: "... realdata_a_clf.png cannot be written"
    assert not (out / "realdata_a_clf.png").exists() and (out / "realdata_b_clf.png").exists()
    read_only.add(out / "summary.txt")
    capsys.readouterr()
    assert main(["compare", str(tmp_path / "a.clf"), *base]) == 2
    assert capsys.readouterr().err.strip() == (
        f"lmsbench compare: error: --out {out}: {out / 'summary.txt'} cannot be written (permission denied: read-only), "
        "and this run would replace it; make it writable (chmod u+w), or give another folder")


def test_a_read_only_file_the_run_may_write_under_a_pattern_is_refused(tmp_path, monkeypatch):
    """The second review: skipping every pattern (above) let a read-only figure CSV (STEM_*.csv) or table
    (tables/*.parquet) through, which figures writes in place: the study ran, then failed writing it. Those
    are refused, saying the run may write them; compare's realdata_*, which it removes, are not."""
    import os

    from experiments import options

    out = tmp_path / "o"
    (out / "tables").mkdir(parents=True)
    for name in ("fig10_slam_map.csv", "tables/summary.parquet", "realdata_a_clf.png"):
        (out / name).write_text("x")
    read_only = {out / "fig10_slam_map.csv"}
    real_access = os.access
    monkeypatch.setattr(options.os, "access", lambda p, mode, **kw: not (mode & os.W_OK and Path(p) in read_only)
                        and real_access(p, mode, **kw))
    tree = options.OutTree(("fig*_*.csv", "realdata_*.png"), {"tables": options.OutTree(("*.parquet",))})
    with pytest.raises(options.InputError, match=r"fig10_slam_map\.csv cannot be written \(permission denied: "
                                                 r"read-only\), and this run may write it;"):
        options._check_replaceable(out, tree)
    read_only = {out / "tables" / "summary.parquet"}
    with pytest.raises(options.InputError, match=r"summary\.parquet cannot be written .* this run may write it;"):
        options._check_replaceable(out, tree)
    read_only = {out / "realdata_a_clf.png"}
    options._check_replaceable(out, tree, removed=("realdata_*.png",))  # removed by the run: allowed
    with pytest.raises(options.InputError, match=r"realdata_a_clf\.png cannot be written"):
        options._check_replaceable(out, tree)


def test_a_figures_runs_sweep_plots_in_a_demos_figures_folder_go_with_the_next_run(tmp_path, capsys, monkeypatch):
    """`figures --sweep S --out DEMO/figures`, then a figures run there without --sweep: the plots of S
    stayed (in a demo's folder figures removed nothing), and its figures.yaml, their one list, was written
    over, so the next demo left them beside its report too (review of round 11). A figures run there
    removes the plots its earlier figures.yaml lists, but the demo's own; so does the demo."""
    import pandas as pd

    import experiments.demo

    timing = pd.DataFrame({"method": ["sensor"], "scan": [0], "time_ms": [0.05]})
    monkeypatch.setattr(experiments.demo, "run_study", lambda cfg, log=print: ({"timing": timing, "summary": timing}, []))
    monkeypatch.setattr(experiments.demo, "_sim2real_section", lambda cfg, out, log: None)
    demo, sw = tmp_path / "demo", tmp_path / "sw"
    argv = ["demo", "--no-sweep", "--duration", "1", "--out", str(demo)]
    assert main(argv) == 0, capsys.readouterr().err
    _finished_sweep(sw, {"name": "k", "kind": "extract", "grid": {"extractor.k": [3, 5]}})
    plots = {"sweep_k_f1.png", "sweep_k_f1.pdf", "sweep_k_f1.csv"}
    drawn = ["figures", "--tables", str(demo / "tables"), "--sweep", str(sw), "--out", str(demo / "figures")]
    for then in (["figures", "--tables", str(demo / "tables"), "--out", str(demo / "figures")], argv):
        assert main(drawn) == 0, capsys.readouterr().err
        assert plots <= {p.name for p in (demo / "figures").iterdir()}
        (demo / "figures" / "sweep_mine.csv").write_text("a user's\n")
        assert main(then) == 0, capsys.readouterr().err
        left = {p.name for p in (demo / "figures").iterdir()}
        assert not plots & left and "sweep_mine.csv" in left, (then[0], left)


def test_the_demo_sweeps_files_are_named_by_one_public_function(tmp_path):
    """The demo and `figures --out DEMO/figures` both name the demo's sweep files by
    options.demo_sweep_files (figures called the demo's private _sweep_files), beside DEMO_SWEEP and the
    demo's output tree, which named the sweep's folder a second time: its cells by their keys, and its
    plots only where its table is."""
    from experiments.options import DEMO_OUTPUTS, DEMO_SWEEP, demo_sweep_files
    from experiments.sweep import SweepSpec, cell_key

    spec = SweepSpec.from_dict(DEMO_SWEEP)
    cells = [f"sweeps/{spec.name}/cells/{cell_key(spec.kind, params)}.parquet" for params in spec.cells()]
    assert demo_sweep_files(tmp_path) == cells and len(cells) == 9
    assert list(DEMO_OUTPUTS.folders["sweeps"].folders) == [spec.name]


@pytest.mark.parametrize("damage, said", [
    (b"", "it is empty"),
    (b"name: t\nkind: extract\nfixed:\n  duration: [0.5", "it does not parse as YAML (line 4, column 17: expected ',' or ']', but got '<stream end>'"),
    (b"- name\n- kind\n", "it holds a list, not a mapping"),
    (b"name: t\nfixed: {duration: 0.5}\n", "it has no kind:"),
    (b"\xff\xfe\x00", "it is not UTF-8 text"),
], ids=["empty", "truncated", "list", "no-kind", "binary"])
def test_a_damaged_sweep_yaml_beside_a_sweeps_outputs_is_named_in_the_refusal(sweep_file, tmp_path, capsys, damage, said):
    """A sweep folder whose sweep.yaml was damaged by hand (cut, emptied, retyped) was refused as any
    user's folder ("holds cells/..., which this run would replace but no earlier lmsbench sweep run
    wrote"), naming no record: the message now names the damaged record and what is wrong with it,
    one line, exit 2, nothing removed."""
    out = tmp_path / "sw"
    cells = _finished_sweep(out, yaml.safe_load(sweep_file.read_text()))
    (out / "sweep.yaml").write_bytes(damage)
    before = sorted(str(p.relative_to(out)) for p in out.rglob("*"))
    assert main(["sweep", str(sweep_file), "--inprocess", "--no-progress", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1, err
    assert err.startswith(f"lmsbench sweep: error: --out {out}: holds {cells[0]} and results.parquet and sweep.yaml, which "
                          "this run would replace but no earlier lmsbench sweep run wrote (its record "
                          f"{out / 'sweep.yaml'} is not one such a run leaves: {said}"), err
    assert err.endswith("); give a new or empty folder\n"), err
    assert sorted(str(p.relative_to(out)) for p in out.rglob("*")) == before
    assert (out / "sweep.yaml").read_bytes() == damage


def test_one_walk_to_the_nearest_existing_folder_for_check_out_and_the_sweeps_store(tmp_path):
    """sweep.store._check_made_in repeated options._nearest_existing, but for a dangling link, where it
    stops (the store says the link is no folder) and check_out's walk goes past it to the folder holding
    it: one helper, options.nearest_existing, with both behaviours, and the messages as they were."""
    from lms200 import LmsbenchError
    from experiments.options import nearest_existing
    from experiments.sweep.store import _check_made_in

    (tmp_path / "dangling").symlink_to(tmp_path / "nowhere")
    deep = tmp_path / "dangling" / "a" / "b"
    assert nearest_existing(deep) == tmp_path
    assert nearest_existing(deep, links=True) == tmp_path / "dangling"
    assert nearest_existing(tmp_path / "new" / "x") == nearest_existing(tmp_path / "new" / "x", links=True) == tmp_path
    assert nearest_existing(Path("/")) == Path("/")
    with pytest.raises(LmsbenchError) as err:
        _check_made_in(deep, "the cells", "and cells are left")
    assert str(err.value) == (f"{deep}: the cells cannot be made: {tmp_path / 'dangling'} is not a folder (a file, or "
                              "a link to none), and cells are left; give a folder that can be written")
    _check_made_in(tmp_path / "new" / "x", "the cells", "and cells are left")  # a writable folder above: passes


def test_a_damaged_slam_config_beside_a_slams_outputs_is_named_in_the_refusal(sim, tmp_path, capsys):
    """The same for slam: its config.yaml retyped by hand beside its trajectory.tum is named, with what is wrong."""
    out = tmp_path / "slam"
    out.mkdir()
    (out / "trajectory.tum").write_text("0.0 0 0 0 0 0 0 1\n")
    for text, said in (("input: {}\nslam: {}\n", "its slam: has no preset:"),
                       ("input: {}\nslam: {preset: default}\nnotes: mine\n", "it has notes:, which such a record does not hold"),
                       ("input: [1]\nslam: {preset: default}\n", "its input: holds a list, not a mapping")):
        (out / "config.yaml").write_text(text)
        assert main(["slam", str(sim), "--quiet", "--out", str(out)]) == 2
        assert capsys.readouterr().err == (
            f"lmsbench slam: error: --out {out}: holds config.yaml and trajectory.tum, which this run would replace but "
            f"no earlier lmsbench slam run wrote (its record {out / 'config.yaml'} is not one such a run leaves: {said}); "
            "give a new or empty folder\n")
        assert (out / "config.yaml").read_text() == text
