"""The shared figure style: files written, equal axes on maps, stable colours."""

from __future__ import annotations

import numpy as np
import pandas as pd

from experiments.style import equal_axes, method_color, new_figure, save_figure


def test_save_figure_writes_png_pdf_and_the_data(tmp_path):
    fig, ax = new_figure()
    x = np.linspace(0, 1, 11)
    ax.plot(x, x**2)
    table = pd.DataFrame({"x": x, "y": x**2})
    written = save_figure(fig, tmp_path / "sub" / "fig_test", data=table)
    names = sorted(p.name for p in written)
    assert names == ["fig_test.csv", "fig_test.pdf", "fig_test.png"]
    assert (tmp_path / "sub" / "fig_test.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (tmp_path / "sub" / "fig_test.pdf").read_bytes()[:5] == b"%PDF-"
    back = pd.read_csv(tmp_path / "sub" / "fig_test.csv")
    np.testing.assert_allclose(back["y"].to_numpy(), x**2)


def test_equal_axes_gives_one_metre_the_same_length_on_both_axes(tmp_path):
    fig, ax = new_figure()
    ax.plot([0, 10], [0, 2])
    equal_axes(ax)
    fig.canvas.draw()
    bbox = ax.get_window_extent()
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    px_per_m_x = bbox.width / (x1 - x0)
    px_per_m_y = bbox.height / (y1 - y0)
    assert abs(px_per_m_x / px_per_m_y - 1.0) < 1e-6
    save_figure(fig, tmp_path / "map")


def test_method_colours_are_stable_and_distinct_for_the_extractors():
    names = ["sensor", "split_merge", "iepf", "hough", "ransac"]
    colours = [method_color(n) for n in names]
    assert len(set(colours)) == len(names)
    assert method_color("something_new") == method_color("something_new")
