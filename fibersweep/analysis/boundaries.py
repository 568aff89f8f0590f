"""Class boundaries of a set of runs: brackets between neighbouring points.

Two runs are neighbours along an axis (``theta0``, ``y0`` or ``length``) when
every other start coordinate and the settings are equal and no run lies between
them on that line. A neighbouring pair whose classes differ brackets a boundary:
the boundary crosses the line somewhere between them. A pair of one class whose
δ differ by more than a threshold brackets a jump of δ (a band the classes do not
name, or one too thin for the points to have seen).

Pure functions of a runs table; shared by the adaptive refinement
(:mod:`fibersweep.sweep.refine`) and the phase figures.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

__all__ = ["COORDS", "BRACKET_COLUMNS", "brackets", "boundary_lines"]

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


def boundary_lines(
    found: pd.DataFrame, x: str = "theta0", y: str = "y0", finest: float | None = None
) -> list[np.ndarray]:
    """Polylines through the boundary points located along ``y``, joined across ``x``.

    For each pair of classes (either order), the bracket midpoints along ``y``
    at each ``x`` value are joined to those at the next ``x`` value that has
    brackets of any pair, rank by rank, when both columns hold the same number
    of brackets of that pair (the boundary is then followed without guessing);
    otherwise the line breaks there and each point stands alone.

    Parameters
    ----------
    found : DataFrame
        :func:`brackets`' table of one panel (one group and one value of the
        third coordinate); only class brackets along ``y`` are used.
    x, y : str
        The panel's horizontal and vertical coordinates.
    finest : float, optional
        Keep only brackets at most this wide on ``y`` (the located ones).

    Returns
    -------
    list of ndarray, each shape (n, 2)
        (x, y) vertices; a single vertex is a boundary point joined to nothing.
    """
    b = found[(found["axis"] == y) & (found["kind"] == "class")]
    if finest is not None:
        b = b[(b["hi"] - b["lo"]) <= finest * (1 + 1e-9)]
    if b.empty:
        return []
    pair = [tuple(sorted(p)) for p in zip(b["class_lo"], b["class_hi"], strict=True)]
    b = b.assign(_pair=pair)
    columns = np.unique(np.round(b[x].to_numpy(dtype=float), _DIGITS))
    lines: list[np.ndarray] = []
    for _, q in b.groupby("_pair", sort=True):
        cols = {
            c: np.sort(q.loc[np.isclose(q[x].astype(float), c, atol=1e-9), y].to_numpy(dtype=float))
            for c in columns
        }
        open_: list[list[tuple[float, float]]] = []
        prev: np.ndarray | None = None
        for c in columns:
            ys = cols[c]
            if prev is not None and len(prev) == len(ys) and len(ys):
                for line, yv in zip(open_, ys, strict=True):
                    line.append((c, yv))
            else:
                lines.extend(np.array(v) for v in open_)
                open_ = [[(c, yv)] for yv in ys]
            prev = ys
        lines.extend(np.array(v) for v in open_)
    return lines
