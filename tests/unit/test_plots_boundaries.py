"""plot-phase draws the located boundaries of a refined table, where they are.

A synthetic refined table (the tilted boundary y_b = 0.3 + 0.01 θ0 of
tests/unit/test_sweep_refine.py, refined along y0 to 0.005 h_obs) goes through the
real figure code; the drawn lines must cross every grid column within one
tolerance plus one map pixel of the truth. A table without refinement runs gets no lines.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.contour import ContourSet

from fibersweep.config import RefineSettings
from fibersweep.plots.phase import phase_figure

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


def _line_vertices(fig) -> np.ndarray:
    """Vertices of every contour line drawn in the first panel, shape (n, 2)."""
    paths = [p for c in fig.axes[0].collections if isinstance(c, ContourSet) for p in c.get_paths()]
    verts = [p.vertices for p in paths if len(p.vertices)]
    return np.concatenate(verts) if verts else np.zeros((0, 2))


def test_refined_table_gets_its_boundary_drawn_at_the_truth():
    runs = _refined_table()
    assert (runs["round"] > 0).any()
    fig = phase_figure(runs, None, "class", col=None)
    v = _line_vertices(fig)
    assert len(v) > 0
    pixel = (runs["y0"].max() - runs["y0"].min()) / 399  # the class map's row spacing
    for t in THETA:
        at = v[np.isclose(v[:, 0], t, atol=0.05)]
        assert len(at), t
        assert np.abs(at[:, 1] - (0.3 + 0.01 * t)).min() <= TOL + pixel, t
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "located boundary" in labels


def test_grid_without_refinement_gets_no_boundary_lines():
    runs = _refined_table()
    runs = runs[runs["round"] == 0]
    fig = phase_figure(runs, None, "class", col=None)
    assert len(_line_vertices(fig)) == 0
    assert "located boundary" not in [t.get_text() for t in fig.legends[0].get_texts()]
