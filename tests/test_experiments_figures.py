"""Figures drawn from tables, the evaluation tables behind them, and the report formatting.

The extractor runs here use exact synthetic rooms (``experiments.synthetic``) so that the pooled
scores can be checked against ``features.scoring.score_scan`` called directly.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from experiments.compare import Source, compare, summarise
from experiments.figures import draw
from experiments.figures.make import PAPER_FIGURES, draw_figures, draw_sweep
from experiments.figures.tables import ad_reference, feature_panels, map_table, pick_evenly, trajectory_table
from experiments.report import fmt, markdown_table, markdown_to_html
from experiments.style import label_of
from experiments.synthetic import L_ROOM, room_scan
from lms200 import Record

METHODS = ["split_merge", "iepf"]


@pytest.fixture(scope="module")
def synthetic_run():
    """Eight noisy scans of the L-shaped room with their exact truths and true poses."""
    records, truths = [], []
    for i in range(8):
        pose = (0.3 + 0.2 * i, 0.1 * i, 0.15 * i)
        scan, truth = room_scan(L_ROOM, pose, sigma=0.005, seed=i)
        records.append(Record(scan.__class__(scan.ranges, scan.angle_min, scan.angle_increment, scan.range_min,
                                             scan.range_max, stamp=0.1 * i), truth=pose))
        truths.append(truth)
    return records, truths


def test_comparison_of_given_records_pools_score_scan_by_hand(synthetic_run):
    from features import extract
    from features.scoring import score_scan

    records, truths = synthetic_run
    per_scan = compare([Source.from_records(records, truths)], METHODS)
    summary = summarise(per_scan).set_index("method")
    for method in METHODS:
        scores = [score_scan(extract(r.scan, method=method), t) for r, t in zip(records, truths)]
        tp = sum(s.tp for s in scores)
        fp = sum(s.fp for s in scores)
        fn = sum(s.fn for s in scores)
        assert summary.loc[method, "tp"] == tp and summary.loc[method, "fp"] == fp
        assert summary.loc[method, "f1"] == pytest.approx(2 * tp / (2 * tp + fp + fn))
        rho = np.concatenate([s.rho_errors for s in scores])
        assert summary.loc[method, "rho_rms_mm"] == pytest.approx(1e3 * np.sqrt(np.mean(rho**2)))
        ctp = sum(s.corner_tp for s in scores)
        assert summary.loc[method, "corner_recall"] == pytest.approx(ctp / (ctp + sum(s.corner_fn for s in scores)))
        times = per_scan.loc[per_scan["method"] == method, "time_ms"]
        assert summary.loc[method, "time_ms_median"] == pytest.approx(times.median())
        assert summary.loc[method, "time_ms_p05"] <= summary.loc[method, "time_ms_median"] <= summary.loc[method, "time_ms_p95"]
    assert (per_scan["time_ms"] > 0).all() and len(per_scan) == len(METHODS) * len(records)


@pytest.mark.slow
def test_every_figure_is_drawn_from_its_tables_with_the_data_beside_it(tmp_path, synthetic_run):
    from features import extract

    records, truths = synthetic_run
    per_scan = compare([Source.from_records(records, truths)], METHODS)
    fsets = [extract(r.scan, method="split_merge") for r in records[:3]]
    pts, lns, crs = feature_panels([r.scan for r in records[:3]], ["a", "b", "c"], fsets)
    assert len(lns) == sum(len(f.lines) for f in fsets) and len(crs) == sum(len(f.corners) for f in fsets)
    scan = records[0].scan
    signals = pd.DataFrame({"beam": np.arange(361), "bearing_deg": np.degrees(scan.angles), "range_m": scan.ranges,
                            "ad": np.full(361, ad_reference(10, scan.angle_increment)),
                            "theta_deg": np.zeros(361), "psi_deg": np.zeros(361)})
    trajectory = trajectory_table(np.array([[0.1 * i, *r.truth] for i, r in enumerate(records)]), records)
    tables = {"signals": signals, "timing": per_scan, "summary": summarise(per_scan),
              "office_points": pts, "office_lines": lns, "office_corners": crs,
              "intel_points": pts, "intel_lines": lns, "intel_corners": crs,
              "trajectory": trajectory, "map": map_table(L_ROOM[:3], L_ROOM)}
    written = draw_figures(tables, tmp_path)
    assert set(written) == set(PAPER_FIGURES)
    for name in PAPER_FIGURES:
        assert (tmp_path / f"{name}.png").stat().st_size > 1000
        assert (tmp_path / f"{name}.pdf").read_bytes()[:5] == b"%PDF-"
    back = pd.read_csv(tmp_path / "fig7_timing.csv")
    np.testing.assert_allclose(back["time_ms"], per_scan["time_ms"])
    back_lines = pd.read_csv(tmp_path / "fig9_office_lines.csv")
    np.testing.assert_allclose(back_lines[["x1", "y1", "x2", "y2"]], lns[["x1", "y1", "x2", "y2"]])
    assert set(pd.read_csv(tmp_path / "fig10_slam_trajectory.csv")["source"]) == {"slam", "truth"}
    from experiments.options import FIGURE_PART_FILES  # the tables by name a rerun removes (Owner.remove_earlier)

    parts = {p.name for p in tmp_path.glob("*_*.csv") if not any(p.name == f"{n}.csv" for n in PAPER_FIGURES)}
    assert parts == set(FIGURE_PART_FILES)


def test_ad_reference_is_the_straight_line_value():
    # k = 1, D = 60 deg: 1 + 2 cos(60 deg) = 2
    assert ad_reference(1, np.pi / 3) == pytest.approx(2.0)
    assert ad_reference(10, np.deg2rad(0.5)) == pytest.approx(1 + 2 * sum(np.cos(np.deg2rad(0.5) * j) for j in range(1, 11)))


def test_sweep_plot_averages_over_seeds(tmp_path):
    rows = [{"x": x, "method": m, "seed": s, "f1": x + (m == "b") + 0.1 * s, "status": "ok"}
            for x in (1, 2) for m in ("a", "b") for s in (0, 1)]
    rows.append({"x": 1, "method": "a", "seed": 2, "f1": np.nan, "status": "error"})
    folder = tmp_path / "sw"
    folder.mkdir()
    pd.DataFrame(rows).to_parquet(folder / "results.parquet")
    (folder / "sweep.yaml").write_text("name: sw\nkind: extract\ngrid:\n  x: [1, 2]\n  method: [a, b]\nseeds: [0, 1]\n")
    written = draw_sweep(folder, tmp_path / "figs")
    assert list(written) == ["sweep_sw_f1"]
    stats = pd.read_csv(tmp_path / "figs" / "sweep_sw_f1.csv")
    got = stats.set_index(["method", "x"])["mean"]
    assert got[("a", 1)] == pytest.approx(1.05) and got[("b", 2)] == pytest.approx(3.05)
    assert (stats["count"] == 2).all()  # the failed cell is left out


def test_pick_evenly_spreads_indices_away_from_the_ends():
    assert pick_evenly(100, 4) == [20, 40, 59, 79]
    assert pick_evenly(3, 5) == [0, 1, 2]
    assert pick_evenly(0, 4) == []


def test_report_tables_and_html():
    table = pd.DataFrame({"method": ["a", "b"], "ms": [1.23456, 12.0], "f1": [0.98765, float("nan")]})
    md = markdown_table(table)
    assert md.splitlines() == ["| method | ms | f1 |", "|---|---|---|", "| a | 1.23 | 0.988 |", "| b | 12 | – |"]
    assert fmt(123456.7) == "123457" and fmt(0.000123) == "0.000123"
    html = markdown_to_html("# T\n\n" + md + "\n\n![cap](figures/x.png)\n\n- item `code`\n", "T")
    assert "<h1>T</h1>" in html and html.count("<tr>") == 3 and "<img src='figures/x.png' alt='cap'>" in html
    assert "<li>item <code>code</code></li>" in html


def test_fig_signal_draws_the_reference_line(tmp_path, monkeypatch):
    k, delta = 10, np.deg2rad(0.5)
    reference = 1 + 2 * sum(np.cos(j * delta) for j in range(1, k + 1))  # AD on a straight line, by hand
    assert reference == pytest.approx(21.0, abs=0.05)
    figures = []
    save = draw.save_figure

    def keep(fig, *args, **kwargs):
        figures.append([(list(line.get_xdata()), list(line.get_ydata()), line.get_linestyle())
                        for ax in fig.axes for line in ax.get_lines()])
        return save(fig, *args, **kwargs)

    monkeypatch.setattr(draw, "save_figure", keep)
    sig = pd.DataFrame({"beam": np.arange(5), "ad": np.linspace(20, 21, 5)})
    paths = draw.fig_signal(sig, "ad", "AD", "t", tmp_path / "s", reference=ad_reference(k, delta))
    assert [p.suffix for p in paths] == [".png", ".pdf", ".csv"]
    (lines,) = figures
    dashed = [y for _, y, style in lines if style == "--"]
    assert len(dashed) == 1 and dashed[0] == pytest.approx([reference, reference])
    signal = [y for _, y, style in lines if style != "--"]
    assert len(signal) == 1 and signal[0] == pytest.approx(list(sig["ad"]))
    saved = pd.read_csv(tmp_path / "s.csv")
    np.testing.assert_allclose(saved["ad"], sig["ad"])
    np.testing.assert_allclose(saved["reference"], reference, rtol=1e-12)


def test_sweep_plot_with_three_parameters_has_a_panel_per_value_of_the_third(tmp_path):
    rows = [{"noise": n, "k": k, "tau": t, "seed": s, "f1": n * 10 + k + t + s, "status": "ok"}
            for n in (0.01, 0.02) for k in (3, 5) for t in (2.0, 4.0) for s in (0, 1)]
    folder = tmp_path / "sw3"
    folder.mkdir()
    pd.DataFrame(rows).to_parquet(folder / "results.parquet")
    (folder / "sweep.yaml").write_text("name: sw3\nkind: extract\ngrid:\n  noise: [0.01, 0.02]\n  k: [3, 5]\n"
                                       "  tau: [2.0, 4.0]\nseeds: [0, 1]\n")
    draw_sweep(folder, tmp_path / "figs")
    stats = pd.read_csv(tmp_path / "figs" / "sweep_sw3_f1.csv")
    assert list(stats.columns[:3]) == ["tau", "k", "noise"] and len(stats) == 8
    row = stats[(stats["tau"] == 4.0) & (stats["k"] == 5) & (stats["noise"] == 0.02)].iloc[0]
    assert row["mean"] == pytest.approx(0.2 + 5 + 4 + 0.5) and row["count"] == 2


def test_random_search_plots_every_cell_against_each_sampled_parameter(tmp_path):
    rng = np.random.default_rng(0)
    table = pd.DataFrame({"a": rng.uniform(0, 1, 6), "b": rng.integers(3, 9, 6), "seed": 0, "status": "ok"})
    table["f1"] = table["a"] / 2
    table.loc[5, "status"] = "error"
    folder = tmp_path / "rs"
    folder.mkdir()
    table.to_parquet(folder / "results.parquet")
    (folder / "sweep.yaml").write_text("name: rs\nkind: extract\nrandom:\n  a: {uniform: [0, 1]}\n"
                                       "  b: {int: [3, 8]}\nsamples: 6\nseeds: [0]\n")
    assert list(draw_sweep(folder, tmp_path / "figs")) == ["sweep_rs_f1"]
    data = pd.read_csv(tmp_path / "figs" / "sweep_rs_f1.csv")
    assert list(data.columns) == ["a", "b", "f1"] and len(data) == 5
    np.testing.assert_allclose(data["f1"], table["a"][:5] / 2)


def test_sweep_of_a_user_kind_plots_its_own_metrics(tmp_path):
    """A sweep of a user's kind (``package.module:function`` returning its own metric names) drew no
    plot at all with `figures --sweep`, silently: only the built-in kinds' metrics were looked for
    (found with docs/experiments.md's "Any function fn(params) -> dict"). Its numeric metrics are
    plotted; its parameters and the runner's columns are not."""
    rows = [{"a": a, "gain": 0.5, "seed": s, "score": 2 * a + s, "hits": a, "f1": 0.9, "status": "ok", "error": None,
             "elapsed_s": 0.01, "cell": f"c{a}{s}"} for a in (1, 2, 3) for s in (0, 1)]
    folder = tmp_path / "custom"
    folder.mkdir()
    pd.DataFrame(rows).to_parquet(folder / "results.parquet")
    (folder / "sweep.yaml").write_text("name: custom\nkind: mykind:cell\nfixed: {gain: 0.5}\ngrid:\n  a: [1, 2, 3]\n"
                                       "seeds: [0, 1]\n")
    # its own "f1" beside them (a built-in metric's name) drew that alone (review)
    assert list(draw_sweep(folder, tmp_path / "figs")) == ["sweep_custom_score", "sweep_custom_hits", "sweep_custom_f1"]
    stats = pd.read_csv(tmp_path / "figs" / "sweep_custom_score.csv").set_index("a")
    assert stats["mean"].to_dict() == {1: 2.5, 2: 4.5, 3: 6.5}


def captured_axes(monkeypatch) -> list:
    """The axes of every figure ``draw`` saves from now on (the figures are saved as before)."""
    axes_seen: list = []
    real_save = draw.save_figure
    monkeypatch.setattr(draw, "save_figure", lambda fig, stem, data=None: (axes_seen.extend(fig.axes),
                                                                           real_save(fig, stem, data=data))[1])
    return axes_seen


def test_sweep_plot_puts_a_numeric_parameter_on_x_when_the_first_grid_key_is_text(tmp_path, monkeypatch):
    """A researcher's sweep over logs (first grid key: three log paths) then psi_split drew the
    paths, overlapping, as x values joined by lines, in alphabetical order."""
    logs = ["/data/zeta/mit.clf.gz", "/data/alpha/intel.log.gz", "/data/aces.log.gz"]
    rows = [{"log": g, "psi": p, "seed": 0, "f1": i + p, "status": "ok"}
            for i, g in enumerate(logs) for p in (0.2, 0.35, 0.5)]
    folder = tmp_path / "real"
    folder.mkdir()
    pd.DataFrame(rows).to_parquet(folder / "results.parquet")
    (folder / "sweep.yaml").write_text("name: real\nkind: x:y\ngrid:\n  log: [" + ", ".join(logs) + "]\n"
                                       "  psi: [0.2, 0.35, 0.5]\nseeds: [0]\n")
    axes_seen = captured_axes(monkeypatch)
    draw_sweep(folder, tmp_path / "figs")
    ax = axes_seen[0]
    assert ax.get_xlabel() == label_of("psi")
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["mit.clf.gz", "intel.log.gz", "aces.log.gz"]


def test_sweep_plot_of_text_values_alone_draws_categories_in_the_grid_order(tmp_path, monkeypatch):
    rows = [{"world": w, "seed": s, "f1": i + 0.1 * s, "status": "ok"}
            for i, w in enumerate(["office", "corridor", "atrium"]) for s in (0, 1)]
    axes_seen = captured_axes(monkeypatch)
    draw.fig_sweep(pd.DataFrame(rows), "world", "f1", tmp_path / "w")
    ax = axes_seen[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["office", "corridor", "atrium"]
    (line,) = [c for c in ax.containers]  # one errorbar: its points at 0, 1, 2 with the grid's means
    np.testing.assert_allclose(np.asarray(line.lines[0].get_xdata(), float), [0, 1, 2])
    np.testing.assert_allclose(np.asarray(line.lines[0].get_ydata(), float), [0.05, 1.05, 2.05])
    assert line.lines[0].get_linestyle() == "None"  # categories are not joined by lines


def test_accuracy_speed_names_each_point_in_its_own_colour(tmp_path, monkeypatch):
    """hough and ransac run at nearly one speed: their names, placed alternately above and below,
    stood each beside the other's point. Each name now has its point's colour."""
    from matplotlib.colors import to_rgba

    from experiments.style import method_color

    captured = []
    save = draw.save_figure

    def keep(fig, *args, **kwargs):
        captured.extend((t.get_text(), to_rgba(t.get_color())) for ax in fig.axes for t in ax.texts)
        return save(fig, *args, **kwargs)

    monkeypatch.setattr(draw, "save_figure", keep)
    methods = ["sensor", "split_merge", "iepf", "hough", "ransac"]
    summary = pd.DataFrame({"method": methods, "f1": [0.976, 0.990, 0.991, 0.990, 0.984],
                            "rho_rms_mm": [6.3, 8.5, 11.3, 9.0, 9.5],
                            "time_ms_median": [0.06, 0.03, 0.03, 2.43, 2.28],
                            "time_ms_p25": [0.05, 0.02, 0.02, 2.3, 2.1], "time_ms_p75": [0.07, 0.04, 0.04, 2.6, 2.4]})
    draw.fig_accuracy_speed(summary, tmp_path / "a")
    assert sorted(name for name, _ in captured) == sorted(methods * 2)  # both panels
    assert all(colour == to_rgba(method_color(name)) for name, colour in captured)


def test_a_boolean_parameter_is_a_category_not_the_numeric_x_axis(tmp_path, monkeypatch):
    """A sweep over `alignment.deskew: [true, false]` then k drew deskew as the x axis, at 0 and 1
    joined by lines, and k as the legend: a bool is an int to pandas. Booleans are categories, as
    text: k is the x axis and deskew the lines, in the grid's order."""
    rows = [{"alignment.deskew": d, "k": k, "seed": 0, "f1": k / 10 + (0.5 if d else 0.0), "status": "ok"}
            for d in (True, False) for k in (3, 5, 7)]
    folder = tmp_path / "dk"
    folder.mkdir()
    pd.DataFrame(rows).to_parquet(folder / "results.parquet")
    (folder / "sweep.yaml").write_text("name: dk\nkind: x:y\ngrid:\n  alignment.deskew: [true, false]\n"
                                       "  k: [3, 5, 7]\nseeds: [0]\n")
    axes_seen = captured_axes(monkeypatch)
    draw_sweep(folder, tmp_path / "figs")
    ax = axes_seen[0]
    assert ax.get_xlabel() == label_of("k")  # old: label_of("alignment.deskew")
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["True", "False"]  # old: 3, 5, 7
    xs = [np.asarray(c.lines[0].get_xdata(), float) for c in ax.containers]
    ys = [np.asarray(c.lines[0].get_ydata(), float) for c in ax.containers]
    np.testing.assert_allclose(xs, [[3, 5, 7], [3, 5, 7]])
    np.testing.assert_allclose(ys, [[0.8, 1.0, 1.2], [0.3, 0.5, 0.7]])


def test_a_boolean_parameter_alone_draws_two_labelled_categories(tmp_path, monkeypatch):
    rows = [{"alignment.deskew": d, "seed": s, "f1": (0.9 if d else 0.7) + 0.01 * s, "status": "ok"}
            for d in (True, False) for s in (0, 1)]
    axes_seen = captured_axes(monkeypatch)
    draw.fig_sweep(pd.DataFrame(rows), "alignment.deskew", "f1", tmp_path / "d")
    ax = axes_seen[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["True", "False"]  # old: numeric ticks 0.0 ... 1.0
    (line,) = ax.containers
    np.testing.assert_allclose(np.asarray(line.lines[0].get_xdata(), float), [0, 1])
    np.testing.assert_allclose(np.asarray(line.lines[0].get_ydata(), float), [0.905, 0.705])
    assert line.lines[0].get_linestyle() == "None"  # old: "-", a line from "false" to "true"


def test_a_random_choice_of_booleans_is_drawn_as_two_categories(tmp_path, monkeypatch):
    table = pd.DataFrame({"deskew": [True, False, True, False], "seed": 0, "status": "ok", "f1": [0.9, 0.7, 0.8, 0.6]})
    axes_seen = captured_axes(monkeypatch)
    draw.fig_sweep_scatter(table, ["deskew"], "f1", tmp_path / "r")
    fig = axes_seen[0].figure
    fig.canvas.draw()
    assert [t.get_text() for t in axes_seen[0].get_xticklabels()] == ["True", "False"]


def test_segments_drawn_as_one_collection_look_as_one_line_each():
    """Fig. 9's lines and Fig. 10's walls and map lines were one Line2D a segment (Fig. 10 of a 40 s run:
    2.8-4.0 s, 1.1-1.2 s now; its legends' "best" testing every wall was 40 % of it in a profile); ``draw.add_segments`` draws them as one
    LineCollection with the same pixels: caps, widths, colours and order as ``ax.plot``."""
    from experiments.style import new_figure

    table = pd.DataFrame({"x1": [0.0, 0.0, 1.0, 0.2], "y1": [0.0, 0.0, 0.0, 0.9],
                          "x2": [2.0, 0.0, 1.7, 1.9], "y2": [0.0, 1.5, 1.2, 0.3]})
    pixels = []
    for one_artist in (False, True):
        fig, ax = new_figure(width=3.0, height=2.5)
        ax.plot([0.5, 1.5], [-0.2, 1.4], "-", lw=1.4, color="k")  # drawn below the segments, as before
        if one_artist:
            draw.add_segments(ax, table, 3.0, "#d0d0d0", label="true walls")
            assert len(ax.collections) == 1 and len(ax.lines) == 2  # the line above and the empty legend proxy
        else:
            for i, row in enumerate(table.itertuples()):
                ax.plot([row.x1, row.x2], [row.y1, row.y2], "-", lw=3.0, color="#d0d0d0",
                        label="true walls" if i == 0 else None)
        ax.plot([0.1, 1.8], [1.4, 0.1], "--", lw=1.4, color="#1f77b4")  # and this one above them
        ax.legend(loc="upper right")
        fig.canvas.draw()
        pixels.append(np.asarray(fig.canvas.buffer_rgba()).copy())
        draw.plt.close(fig)
    assert pixels[0].shape == pixels[1].shape
    assert np.count_nonzero((pixels[0] != pixels[1]).any(axis=-1)) == 0


def test_fig_slam_draws_each_map_as_one_collection_with_one_legend_below(tmp_path, monkeypatch):
    """Each panel's walls and map lines are one LineCollection each; the legend is one, below the
    panels (a map fills its panel: "best" inside it covered walls), each entry once, start last."""
    captured = []
    save = draw.save_figure

    def keep(fig, *args, **kwargs):
        captured.append(([[(c.get_segments(), c.get_linewidths()[0]) for c in ax.collections] for ax in fig.axes],
                         [ax.get_legend() for ax in fig.axes],
                         [[t.get_text() for t in legend.get_texts()] for legend in fig.legends]))
        return save(fig, *args, **kwargs)

    monkeypatch.setattr(draw, "save_figure", keep)
    walls = pd.DataFrame({"source": "truth", "x1": [0.0, 4.0, 0.0], "y1": [0.0, 0.0, 3.0],
                          "x2": [4.0, 4.0, 4.0], "y2": [0.0, 3.0, 3.0]})
    slam_lines = pd.DataFrame({"source": ["slam", "slam", "paper preset"], "x1": [0.1, 3.9, 0.2],
                               "y1": [0.0, 0.1, 2.9], "x2": [3.8, 3.9, 3.7], "y2": [0.1, 2.8, 3.0]})
    t = np.linspace(0, 1, 5)
    trajectory = pd.concat([pd.DataFrame({"source": s, "t": t, "x": 1 + t, "y": 1 + d * t, "theta": 0.0})
                            for s, d in (("truth", 0.0), ("slam", 0.01), ("paper preset", 0.05))])
    paths = draw.fig_slam(trajectory, pd.concat([walls, slam_lines]), tmp_path / "fig10_slam", "t")
    assert sorted(p.name for p in paths) == ["fig10_slam.pdf", "fig10_slam.png", "fig10_slam_map.csv",
                                             "fig10_slam_trajectory.csv"]
    ((collections, axes_legends, legends),) = captured
    wall_segments = walls[["x1", "y1", "x2", "y2"]].to_numpy().reshape(-1, 2, 2)
    for panel, mine in zip(collections, (slam_lines.iloc[[2]], slam_lines.iloc[:2])):  # paper preset, then slam
        (drawn_walls, wall_width), (drawn_lines, line_width) = panel
        np.testing.assert_array_equal(np.array(drawn_walls), wall_segments)
        np.testing.assert_array_equal(np.array(drawn_lines), mine[["x1", "y1", "x2", "y2"]].to_numpy().reshape(-1, 2, 2))
        assert (wall_width, line_width) == (3.0, 1.2)
    assert axes_legends == [None, None]
    assert legends == [["true walls", "SLAM map lines", "true trajectory", "paper preset trajectory",
                        "slam trajectory", "start"]]


def test_a_dot_in_a_figures_name_is_no_suffix(tmp_path):
    """save_figure took a dot in the stem for a suffix: a sweep's metrics acc.5 and acc.6 drew into one
    sweep_NAME_acc.png (their CSVs apart), and a sweep named k.v put every plot in sweep_k.png (final read of
    round 10)."""
    import matplotlib.pyplot as plt

    from experiments.style import save_figure

    for metric in ("acc.5", "acc.6"):
        fig, _ = plt.subplots()
        save_figure(fig, tmp_path / f"sweep_k.v_{metric}", data=pd.DataFrame({"a": [1]}))
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        f"sweep_k.v_acc.{n}.{end}" for n in (5, 6) for end in ("csv", "pdf", "png")]


def test_figures_reads_each_sweep_table_once(tmp_path, monkeypatch, capsys):
    """`figures --sweep DIR` read DIR/results.parquet four times (its checks, the plots' names, figures.yaml's
    list of them, the drawing), and parsed DIR/sweep.yaml as often; now its checks' reads are passed on
    (options.read_sweep_results)."""
    import experiments.figures.study as study
    import experiments.provenance as provenance
    import lms200.yamlio as yamlio
    from experiments.cli import main
    from experiments.figures.study import StudyConfig, save_tables

    sweep = tmp_path / "sw"
    sweep.mkdir()
    pd.DataFrame({"x": [1, 2], "status": ["ok", "ok"], "error": ["", ""], "cell": ["a", "b"], "seed": [0, 0],
                  "f1": [0.5, 0.6]}).to_parquet(sweep / "results.parquet")
    (sweep / "sweep.yaml").write_text("name: one\nkind: extract\ngrid:\n  x: [1, 2]\n")
    save_tables({"summary": pd.DataFrame({"method": ["a"]})}, StudyConfig(), [], tmp_path / "tables")
    reads = []
    real = provenance.read_parquet

    def counted(path, **kwargs):
        reads.append(str(path))
        return real(path, **kwargs)

    parsed = []
    parse = yamlio.yaml.load

    def counted_yaml(text, **kwargs):
        parsed.append(text)
        return parse(text, **kwargs)

    monkeypatch.setattr(provenance, "read_parquet", counted)
    monkeypatch.setattr(study, "read_parquet", counted)
    monkeypatch.setattr(yamlio.yaml, "load", counted_yaml)
    assert main(["figures", "--tables", str(tmp_path / "tables"), "--sweep", str(sweep), "--out", str(tmp_path / "o")]) == 0
    assert "sweep_one_f1" in capsys.readouterr().out and (tmp_path / "o" / "sweep_one_f1.png").is_file()
    assert [r for r in reads if r.endswith("results.parquet")] == [str(sweep / "results.parquet")]
    assert parsed.count((sweep / "sweep.yaml").read_text()) == 1, len(parsed)
