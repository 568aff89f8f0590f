"""What a phase panel can honestly draw: supported boundaries and dense columns.

Two drawings the markers of :mod:`fibersweep.plots.phase` cannot give:

* the class boundaries of a refined sweep, drawn only where two neighbouring
  runs of different class bracket one (:func:`boundary_segments`): a short
  tick across the run's column at the bracket's midpoint, and the bracket
  itself as a thin line, never a line between columns where no run was made;
* a dense column (e.g. 80 y0 values per θ0) as a strip of cells, one per run,
  each reaching half-way to its neighbours (:func:`column_cells`): the class
  map of the column, in which a band one run thick still shows, where markers
  would be squashed into each other.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from fibersweep.analysis.boundaries import _DIGITS, brackets

__all__ = [
    "DENSE_DIAMETER_PT",
    "boundary_segments",
    "column_cells",
    "is_dense",
    "refined_axes",
]

#: Marker diameter [pt] below which a panel is drawn as cells instead of markers.
DENSE_DIAMETER_PT = 4.0

#: Half-width of a boundary tick and of a column of cells, in grid spacings.
TICK_HALF = 0.2
CELL_HALF = 0.35


def _grid(panel: pd.DataFrame) -> pd.DataFrame:
    """Round-0 runs (the sweep's grid) of a panel; the panel itself if it has no rounds."""
    if "round" not in panel:
        return panel
    g = panel[panel["round"].fillna(0) == 0]
    return g if len(g) else panel


def _distinct(values: pd.Series | np.ndarray) -> np.ndarray:
    return np.unique(np.round(np.asarray(values, dtype=float), _DIGITS))


def _spacing(values: np.ndarray, default: float = 1.0) -> float:
    """Smallest gap between distinct values (``default`` for a single value)."""
    u = _distinct(values)
    return float(np.diff(u).min()) if u.size > 1 else default


def refined_axes(panel: pd.DataFrame) -> list[str]:
    """Start axes (``theta0``, ``y0``) along which refinement runs left the grid.

    A refinement round bisects brackets along its axes only, so its runs take
    new values on those axes and grid values on the others.
    """
    if "round" not in panel:
        return []
    new = panel[panel["round"].fillna(0) > 0]
    grid = _grid(panel)
    out = []
    for axis in ("theta0", "y0"):
        known = set(_distinct(grid[axis]).tolist())
        if len(new) and not set(_distinct(new[axis]).tolist()) <= known:
            out.append(axis)
    return out


def boundary_segments(panel: pd.DataFrame) -> tuple[np.ndarray, np.ndarray, pd.DataFrame]:
    """Ticks and bracket lines of the class boundaries the runs of a panel support.

    Every pair of neighbouring classified runs of different class along a
    refined axis (:func:`refined_axes`; neighbours as in
    :func:`fibersweep.analysis.boundaries.brackets`, within one settings id
    and length) gives one tick, across the pair's line at the bracket's
    midpoint, ``TICK_HALF`` grid spacings to either side, and one bracket line
    from one run to the other.

    Parameters
    ----------
    panel : DataFrame
        Runs of one panel (``theta0``, ``y0``, ``length``, ``class``, ``status``,
        ``round``, optionally ``settings``).

    Returns
    -------
    ticks : ndarray, shape (n, 2, 2)
        Tick end points (θ0 [deg], y0/h_obs).
    spans : ndarray, shape (n, 2, 2)
        Bracket end points (the two runs' coordinates).
    table : DataFrame
        The brackets drawn (:data:`fibersweep.analysis.boundaries.BRACKET_COLUMNS`).
    """
    axes = refined_axes(panel)
    empty = np.zeros((0, 2, 2))
    if not axes:
        return empty, empty, brackets(panel.iloc[:0], ["y0"])
    b = brackets(panel, axes)
    b = b[b["kind"] == "class"].reset_index(drop=True)
    if b.empty:
        return empty, empty, b
    grid = _grid(panel)
    half = {
        "theta0": TICK_HALF * _spacing(grid["theta0"], 2.0),
        "y0": TICK_HALF * _spacing(grid["y0"], 0.1),
    }
    ticks, spans = [], []
    for r in b.itertuples(index=False):
        mid = 0.5 * (r.lo + r.hi)
        if r.axis == "y0":
            ticks.append([[r.theta0 - half["theta0"], mid], [r.theta0 + half["theta0"], mid]])
            spans.append([[r.theta0, r.lo], [r.theta0, r.hi]])
        else:
            ticks.append([[mid, r.y0 - half["y0"]], [mid, r.y0 + half["y0"]]])
            spans.append([[r.lo, r.y0], [r.hi, r.y0]])
    return np.asarray(ticks, float), np.asarray(spans, float), b


def is_dense(panel: pd.DataFrame, diameter_pt: float) -> bool:
    """Whether markers of ``diameter_pt`` [pt] are too small to tell the classes apart.

    A refined panel keeps its markers: its grid is coarse, and its extra runs
    are drawn small on purpose.
    """
    return diameter_pt < DENSE_DIAMETER_PT and not refined_axes(panel)


def column_cells(panel: pd.DataFrame) -> tuple[np.ndarray, pd.DataFrame]:
    """One rectangle per run: its θ0 column's strip, half-way to its y0 neighbours.

    Columns are ``2 * CELL_HALF`` grid spacings wide, so the gaps between
    them stay empty (nothing was run there). Along y0 each run's cell reaches
    half-way to the next run of its column, or half a spacing past the last.

    Parameters
    ----------
    panel : DataFrame
        Runs of one panel, with ``theta0``, ``y0`` (and ``settings``/``length``:
        columns of different settings or lengths in one panel share a strip,
        drawn in the table's order).

    Returns
    -------
    rects : ndarray, shape (n, 4, 2)
        Corners of each run's cell (θ0 [deg], y0/h_obs), in the order of ``runs``.
    runs : DataFrame
        ``panel`` sorted by column and y0.
    """
    if panel.empty:
        return np.zeros((0, 4, 2)), panel
    runs = panel.sort_values(["theta0", "y0"], kind="stable")
    w = CELL_HALF * _spacing(runs["theta0"], 2.0)
    rects = []
    for _, col in runs.groupby(runs["theta0"].round(_DIGITS), sort=False):
        y = col["y0"].to_numpy(dtype=float)
        t = col["theta0"].to_numpy(dtype=float)
        u = _distinct(y)
        dy = float(np.diff(u).min()) if u.size > 1 else 0.05
        edges = np.concatenate([[u[0] - 0.5 * dy], 0.5 * (u[1:] + u[:-1]), [u[-1] + 0.5 * dy]])
        k = np.searchsorted(u, np.round(y, _DIGITS))
        for tk, lo, hi in zip(t, edges[k], edges[k + 1], strict=True):
            rects.append([[tk - w, lo], [tk + w, lo], [tk + w, hi], [tk - w, hi]])
    return np.asarray(rects, float), runs
