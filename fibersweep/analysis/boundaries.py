"""Class boundaries of a set of runs: brackets between neighbouring points.

Two runs are neighbours along an axis (``theta0``, ``y0`` or ``length``) when
every other start coordinate and the settings are equal and no run lies between
them on that line. A neighbouring pair whose classes differ brackets a boundary:
the boundary crosses the line somewhere between them. A pair of one class whose
δ differ by more than a threshold brackets a jump of δ (a band the classes do not
name, or one too thin for the points to have seen).

Pure functions of a runs table: :func:`brackets` drives the adaptive refinement
(:mod:`fibersweep.sweep.refine`), :func:`class_map` gives the phase figures their
boundary lines.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

__all__ = ["COORDS", "BRACKET_COLUMNS", "brackets", "class_map"]

#: The start coordinates of a run: θ0 [deg], y0/h_obs, L/l_obs.
COORDS = ("theta0", "y0", "length")

#: Columns of :func:`brackets`' table.
BRACKET_COLUMNS = [
    "group", "axis", "theta0", "y0", "length", "lo", "hi", "class_lo", "class_hi", "kind",
]  # fmt: skip

_DIGITS = 9  # coordinates equal to this many decimals lie on one line


def _classified(points: pd.DataFrame) -> pd.DataFrame:
    """The runs with a class: status ok and a non-empty class."""
    ok = points["status"].eq("ok") if "status" in points else pd.Series(True, points.index)
    cls = points["class"]
    return points[ok & cls.notna() & cls.astype(str).ne("")]


def brackets(
    points: pd.DataFrame,
    axes: Sequence[str],
    *,
    delta_jump: float | None = None,
    group: str = "settings",
) -> pd.DataFrame:
    """Every neighbouring pair of classified runs that brackets a boundary.

    Parameters
    ----------
    points : DataFrame
        Runs: columns ``theta0``, ``y0``, ``length``, ``class``, and optionally
        ``status`` (only ``ok`` runs count), ``delta`` (needed for
        ``delta_jump``) and the ``group`` column (runs of different groups are
        never neighbours). Failed or unclassified runs are left out, so their
        neighbours on either side become neighbours.
    axes : sequence of str
        Axes along which neighbours are looked for (each of :data:`COORDS`).
    delta_jump : float, optional
        Also bracket pairs of one class whose finite δ differ by more than this
        [h_obs].
    group : str
        Column that splits the runs into independent sets (e.g. ``settings``);
        ignored when absent.

    Returns
    -------
    DataFrame
        One row per bracket, columns :data:`BRACKET_COLUMNS`: ``group``, the
        ``axis``, the start coordinates of the bracket's line (the axis's own
        coordinate is the midpoint), ``lo`` < ``hi`` on the axis, the classes at
        each end, and ``kind`` ('class' or 'delta').
    """
    ok = _classified(points)
    frames = []
    for axis in axes:
        if axis not in COORDS:
            raise ValueError(f"unknown axis {axis!r}; valid: {', '.join(COORDS)}")
        others = [c for c in COORDS if c != axis]
        d = pd.DataFrame(
            {
                "group": ok[group].astype(str) if group in ok else "",
                **{c: ok[c].astype(float) for c in COORDS},
                "class": ok["class"].astype(str),
                "delta": ok["delta"].astype(float) if "delta" in ok else np.nan,
            }
        )
        keys = ["group", *[f"_{c}" for c in others]]
        for c in others:
            d[f"_{c}"] = d[c].round(_DIGITS)
        d = d.sort_values([*keys, axis], kind="stable")
        nxt = d.groupby(keys, sort=False)[[axis, "class", "delta"]].shift(-1)
        has = nxt[axis].notna() & (nxt[axis] > d[axis])
        differ = has & (nxt["class"] != d["class"])
        jump = pd.Series(False, index=d.index)
        if delta_jump is not None:
            gap = (nxt["delta"] - d["delta"]).abs()
            jump = has & ~differ & (gap > delta_jump)  # NaN gaps compare False
        for mask, kind in ((differ, "class"), (jump, "delta")):
            if not mask.any():
                continue
            lo, hi = d.loc[mask], nxt.loc[mask]
            b = pd.DataFrame(
                {
                    "group": lo["group"],
                    "axis": axis,
                    **{c: lo[c] for c in others},
                    axis: 0.5 * (lo[axis] + hi[axis]),
                    "lo": lo[axis],
                    "hi": hi[axis],
                    "class_lo": lo["class"],
                    "class_hi": hi["class"],
                    "kind": kind,
                }
            )
            frames.append(b[BRACKET_COLUMNS])
    if not frames:
        return pd.DataFrame({c: pd.Series(dtype=object) for c in BRACKET_COLUMNS})
    return pd.concat(frames, ignore_index=True)


def _spacing(values: np.ndarray) -> float:
    """Median spacing of the distinct values (1.0 when there is one)."""
    u = np.unique(np.round(values, _DIGITS))
    return float(np.median(np.diff(u))) if u.size > 1 else 1.0


def class_map(
    points: pd.DataFrame,
    x: str = "theta0",
    y: str = "y0",
    shape: tuple[int, int] = (400, 300),
    scale: tuple[float, float] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """Nearest-neighbour class map of the classified runs over their (x, y) extent.

    Each pixel takes the class of the nearest classified run, distances measured
    in units of ``scale`` (default: the median spacing of the grid's values on
    each axis, so a refined column does not claim the space between columns):
    where runs are dense (a refined boundary) the map's boundary follows them
    to their resolution, between them it steps half-way.

    Parameters
    ----------
    points : DataFrame
        Runs of one panel (columns ``x``, ``y``, ``class``, optionally ``status``
        and ``round``: the spacing is taken from round 0 when present).
    x, y : str
        Coordinates.
    shape : (int, int)
        Pixels along y and x.
    scale : (float, float), optional
        Distance units along x and y.

    Returns
    -------
    xs : ndarray, shape (nx,)
        Pixel centres along x.
    ys : ndarray, shape (ny,)
        Pixel centres along y.
    labels : ndarray of int, shape (ny, nx)
        Index into ``names``; -1 where there is no classified run at all.
    names : list of str
    """
    from scipy.spatial import cKDTree

    ok = _classified(points)
    ny, nx = shape
    if ok.empty:
        return np.zeros(nx), np.zeros(ny), np.full((ny, nx), -1), []
    px, py = ok[x].to_numpy(dtype=float), ok[y].to_numpy(dtype=float)
    if scale is None:
        grid = ok[ok["round"].fillna(0) == 0] if "round" in ok else ok
        grid = grid if len(grid) else ok
        scale = (_spacing(grid[x].to_numpy(float)), _spacing(grid[y].to_numpy(float)))
    xs = np.linspace(px.min(), px.max(), nx)
    ys = np.linspace(py.min(), py.max(), ny)
    names = sorted(ok["class"].astype(str).unique())
    code = {c: i for i, c in enumerate(names)}
    tree = cKDTree(np.column_stack([px / scale[0], py / scale[1]]))
    gx, gy = np.meshgrid(xs / scale[0], ys / scale[1])
    _, idx = tree.query(np.column_stack([gx.ravel(), gy.ravel()]))
    labels = np.array([code[c] for c in ok["class"].astype(str)])[idx].reshape(ny, nx)
    return xs, ys, labels, names
