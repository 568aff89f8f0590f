"""plot-phase draws the located boundaries of a refined table, where they are.

A synthetic refined table (the tilted boundary y_b = 0.3 + 0.01 θ0 of
tests/unit/test_sweep_refine.py, refined along y0 to 0.005 h_obs) goes through the
real figure code; each grid column gets one boundary tick, at the midpoint of a
bracket no wider than the tolerance, so within half a tolerance of the truth.
A table without refinement runs gets no ticks.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.collections import LineCollection

from fibersweep.config import RefineSettings
from fibersweep.plots.phase import BOUNDARY_LABEL, phase_figure

TOL = 0.005
THETA = np.arange(-10.0, 10.001, 2.0)


def _refined_table() -> pd.DataFrame:
    from fibersweep.sweep.refine import propose

    t, y = np.meshgrid(THETA, np.round(np.arange(0.0, 1.0001, 0.1), 12), indexing="ij")
    pts = pd.DataFrame({"theta0": t.ravel(), "y0": y.ravel(), "length": 0.8, "round": 0})
    refine = RefineSettings(axes=["y0"], tolerance={"y0": TOL}, max_runs=10_000)

    def label(p):
        above = p["y0"] > 0.3 + 0.01 * p["theta0"]
        return p.assign(status="ok", **{"class": np.where(above, "Above", "Below")}, delta=0.0)

    pts = label(pts)
    for rnd in range(1, 20):
        new = propose(pts, refine, 10_000).new
        if new.empty:
            break
        pts = pd.concat([pts, label(new.drop(columns="group").assign(round=rnd))])
    return pts.assign(id=[f"r{i}" for i in range(len(pts))], settings="s").reset_index(drop=True)


def _ticks(fig) -> np.ndarray:
    """Boundary ticks drawn in the first panel (the top layer of lines), shape (n, 2, 2)."""
    lines = [c for c in fig.axes[0].collections if isinstance(c, LineCollection)]
    segs = [np.asarray(s) for c in lines if c.get_zorder() == 4 for s in c.get_segments()]
    return np.asarray(segs) if segs else np.zeros((0, 2, 2))


def test_refined_table_gets_its_boundary_drawn_at_the_truth():
    runs = _refined_table()
    assert (runs["round"] > 0).any()
    fig = phase_figure(runs, None, "class", col=None)
    ticks = _ticks(fig)
    assert len(ticks) == len(THETA)  # one boundary per column, nothing between columns
    for t in THETA:
        at = ticks[np.isclose(ticks[:, :, 0].mean(axis=1), t, atol=1e-9)]
        assert len(at) == 1, t
        assert at[0, 0, 1] == at[0, 1, 1]  # horizontal, across the column only
        assert np.ptp(at[0, :, 0]) < np.diff(THETA).min()
        assert abs(at[0, 0, 1] - (0.3 + 0.01 * t)) <= TOL / 2 + 1e-12, t
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert BOUNDARY_LABEL in labels


def test_grid_without_refinement_gets_no_boundary_lines():
    runs = _refined_table()
    runs = runs[runs["round"] == 0]
    fig = phase_figure(runs, None, "class", col=None)
    assert len(_ticks(fig)) == 0
    assert BOUNDARY_LABEL not in [t.get_text() for t in fig.legends[0].get_texts()]
