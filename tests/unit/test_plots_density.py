"""Dense sweeps and the smaller figure fixes of issue 29.

* A dense column (80 y0 values) is drawn as one cell per run, so a band one run
  thick (Pole-vaulting) and one of two runs (Trapping) keep their colour and
  their true height; a sparse grid keeps its markers.
* chronophotograph: the colour bar is no taller than the (equal-aspect) axes.
* delta_hist: the bars use the height of the axes (the legend sits above).
* contact map: the "base line" names sit outside the axes, where no marker goes.
* faceted phase figures keep L/l_obs (and any other fixed setting) in a title.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.collections import PathCollection, PolyCollection
from matplotlib.colors import to_hex

from fibersweep.plots import phase
from fibersweep.plots.style import CLASS_STYLE, paper_style

Y = np.round(np.linspace(0.01, 0.8, 80), 6)


def _dense(thetas=(-8.0, -4.0, 0.0, 4.0, 8.0), ys=Y):
    rows = []
    for t in thetas:
        for k, y in enumerate(ys):
            cls = (
                "Below"
                if k < 40
                else "Trapping"
                if k < 42
                else "Pole-vaulting"
                if k == 42
                else "Above"
            )
            rows.append({"id": f"{t}-{k}", "theta0": t, "y0": y, "length": 1.0, "status": "ok",
                         "class": cls, "delta": np.nan if cls == "Trapping" else 0.01 * k,
                         "contact": False, "theta_c": np.nan, "y_c": np.nan, "settings": "s",
                         "round": 0})  # fmt: skip
    return pd.DataFrame(rows)


def _cells(fig):
    return [c for c in fig.axes[0].collections if isinstance(c, PolyCollection)]


def test_dense_columns_are_drawn_as_cells_that_keep_thin_bands():
    with paper_style():
        fig = phase.phase_figure(_dense(), None, "class", col=None)
    (cells,) = _cells(fig)
    colors = [to_hex(c) for c in cells.get_facecolor()]
    assert len(colors) == 5 * 80  # one cell per run
    for cls, n in (("Pole-vaulting", 5), ("Trapping", 10)):
        assert colors.count(CLASS_STYLE[cls]["color"].lower()) == n, cls
    heights = [np.ptp(p.vertices[:, 1]) for p in cells.get_paths()]
    assert np.allclose(heights, np.diff(Y).min(), rtol=1e-6)  # a one-run band: one spacing
    widths = [np.ptp(p.vertices[:, 0]) for p in cells.get_paths()]
    assert max(widths) < 4.0  # columns 4° apart keep a gap between them
    assert not [c for c in fig.axes[0].collections if isinstance(c, PathCollection)]


def test_dense_delta_map_marks_runs_without_delta():
    with paper_style():
        fig = phase.phase_figure(_dense(), None, "delta", col=None)
    cells = _cells(fig)
    assert sum(len(c.get_paths()) for c in cells) == 400
    assert "Trapping (no δ)" in [t.get_text() for t in fig.legends[0].get_texts()]


def test_sparse_grid_keeps_markers():
    with paper_style():
        fig = phase.phase_figure(_dense(ys=Y[::8]), None, "class", col=None)
    assert not _cells(fig)
    assert [c for c in fig.axes[0].collections if isinstance(c, PathCollection)]


def test_delta_hist_uses_the_height_of_its_axes():
    runs = _dense()
    runs["contact"] = runs["y0"] > 0.4
    with paper_style():
        fig = phase.delta_hist_figure(runs)
    ax = fig.axes[0]
    lo, hi = np.log(ax.get_ylim())
    tallest = max(np.log(max(p.get_path().vertices[:, 1].max(), 1)) for p in ax.patches)
    assert (tallest - lo) / (hi - lo) > 0.8


def test_contact_map_names_its_lines_outside_the_axes():
    runs = _dense()
    runs["contact"] = True
    runs["theta_c"] = np.linspace(-30, 60, len(runs))
    runs["y_c"] = np.where(runs["y0"] > 0.5, 1.0, 0.0)  # markers on both lines, up to the edge
    with paper_style():
        fig = phase.contact_figure(runs)
    fig.canvas.draw()
    ax = fig.axes[0]
    box = ax.get_window_extent()
    names = [t for t in ax.texts if "base line" in t.get_text()]
    assert len(names) == 2
    for t in names:
        assert t.get_window_extent().x0 >= box.x1  # in the margin, not over the markers


def test_facets_keep_the_length_in_a_title():
    runs = _dense(ys=Y[::8])
    runs = pd.concat([runs.assign(**{"fiber.effects.friction": f}) for f in (0.0, 0.3)])
    with paper_style():
        fig = phase.phase_figure(runs, None, "class", col="fiber.effects.friction")
    title = fig.legends[0].get_title().get_text()
    assert "L/l" in title and "= 1" in title
    assert all("friction" in a.get_title() for a in fig.axes if a.get_visible())


def test_chronophotograph_colour_bar_no_taller_than_its_axes(coarse_field):
    from fibersweep.config.fiber import FiberSettings
    from fibersweep.fiber.result import FiberStart
    from fibersweep.fiber.run import simulate
    from fibersweep.plots.chrono import chrono_figure

    fiber = FiberSettings(record={"trajectories": True, "samples": 300})
    res = simulate(coarse_field, fiber, FiberStart(theta0=-8.0, y0=0.39, length=1.0))
    with paper_style():
        fig = chrono_figure(res, coarse_field.geometry)
        fig.canvas.draw()
    ax = fig.axes[0]
    (cax,) = ax.child_axes
    a, c = ax.get_window_extent(), cax.get_window_extent()
    assert c.height <= a.height + 1.0 and c.y0 >= a.y0 - 1.0  # pixels
