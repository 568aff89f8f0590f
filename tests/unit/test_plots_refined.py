"""plot-phase on a real refined folder draws only boundaries its runs support.

A small refined sweep (tests/unit/_results_folder.py: configs/quick.yaml, three
angles, two lengths, refined along y0) goes through ``plot-phase``. Every
boundary drawn must be a bracket of two neighbouring runs of different class
in one column: the tick sits at the bracket's midpoint and stays inside its
column, and every such bracket is drawn. This is the defect of issue 29, where
contour lines of a class map crossed a column between two runs of one class.
"""

from __future__ import annotations

import numpy as np
import pytest
from _results_folder import refined_folder
from matplotlib.collections import LineCollection
from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.plots.density import TICK_HALF, boundary_segments
from fibersweep.plots.phase import phase_figure
from fibersweep.sweep.store import read_runs


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    return read_runs(refined_folder(tmp_path_factory.mktemp("sweep")))


def _neighbours(col, y):
    """Classified runs of one column just below and just above ``y``."""
    ok = col[col["status"].eq("ok")].sort_values("y0")
    below, above = ok[ok["y0"] < y], ok[ok["y0"] > y]
    return below.iloc[-1], above.iloc[0]


def test_every_drawn_boundary_is_a_bracket_of_neighbours_of_different_class(runs):
    assert (runs["round"] > 0).any(), "the sweep was meant to refine"
    fig = phase_figure(runs, None, "class", col="length")
    n_checked = 0
    for ax, (length, panel) in zip(fig.axes, runs.groupby("length"), strict=False):
        ticks = [np.asarray(s) for c in ax.collections if isinstance(c, LineCollection)
                 and c.get_zorder() == 4 for s in c.get_segments()]  # fmt: skip
        expected, _, table = boundary_segments(panel)
        assert len(ticks) == len(expected) == len(table)
        thetas = np.unique(panel["theta0"])
        for seg in ticks:
            (x0, y0), (x1, y1) = seg
            assert y0 == y1  # across a column, along θ0
            centre = 0.5 * (x0 + x1)
            assert np.isclose(thetas, centre).any()
            # inside its own column: never reaches a neighbouring column
            assert (x1 - x0) / 2 <= TICK_HALF * np.diff(thetas).min() + 1e-9
            col = panel[np.isclose(panel["theta0"], centre)]
            lo, hi = _neighbours(col, y0)
            assert lo["class"] != hi["class"], (length, centre, y0)
            assert np.isclose(y0, 0.5 * (lo["y0"] + hi["y0"]))
            n_checked += 1
        # and every change of class along a column is drawn
        for t in thetas:
            col = panel[np.isclose(panel["theta0"], t) & panel["status"].eq("ok")]
            cls = col.sort_values("y0")["class"].to_numpy()
            changes = int((cls[1:] != cls[:-1]).sum())
            drawn = sum(np.isclose(0.5 * (s[0, 0] + s[1, 0]), t) for s in ticks)
            assert drawn == changes, (length, t)
    assert n_checked >= 6


def test_plot_phase_command_on_the_refined_folder(tmp_path_factory, tmp_path):
    folder = refined_folder(tmp_path_factory.mktemp("sweep"))
    r = CliRunner().invoke(app, ["plot-phase", str(folder), "-o", str(tmp_path)])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "phase.png").stat().st_size > 10_000
