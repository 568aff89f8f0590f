"""Adaptive refinement of the critical length of a pillar-array sweep with random starts.

A sweep with ``sweep.random`` has no neighbouring points to bracket (every length
draws its own starts), so its refinement works on what a sorter designer reads:
per setting combination, the mean displacement fraction of each length (runs
that were not trapped, :mod:`fibersweep.analysis.modes`). Every pair of
neighbouring lengths whose means lie on either side of :data:`LEVEL` (the
critical length's definition, as in ``sort-report``) is bisected: the midpoint
length gets the sweep's ``random.count`` seeded starts, drawn as if it had been
in the grid (:func:`fibersweep.sweep.draws.start_points`), until the bracket is
at most ``refine.tolerance['length']`` wide, the budget ``max_runs`` is spent or
``rounds`` rounds have run. Like the channel's refinement, the new lengths are a
function of the stored runs alone, so an interrupted refinement resumes without
duplicates.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pandas as pd

from fibersweep.analysis.boundaries import BRACKET_COLUMNS, COORDS
from fibersweep.analysis.proposal import Proposal

__all__ = ["LEVEL", "length_brackets", "propose_lengths"]

#: Mean displacement fraction that defines the critical length.
LEVEL = 0.5

_DIGITS = 12  # midpoints rounded like axis values (stable ids)


def length_brackets(points: pd.DataFrame, group: str = "settings") -> pd.DataFrame:
    """Neighbouring lengths whose mean fraction lies on either side of :data:`LEVEL`.

    Parameters
    ----------
    points : DataFrame
        Every point so far: ``length`` [µm], ``status``, ``mode``, ``fraction`` (missing
        for runs not stored) and the ``group`` column.

    Returns
    -------
    DataFrame
        :data:`~fibersweep.analysis.boundaries.BRACKET_COLUMNS`: ``axis`` 'length',
        ``length`` the midpoint, ``lo``/``hi`` the two lengths, ``class_lo``/``class_hi``
        their mean fractions as text, ``kind`` 'fraction'.
    """
    rows = []
    if "fraction" not in points or "mode" not in points:
        return pd.DataFrame(columns=BRACKET_COLUMNS)
    moving = points[points["status"].eq("ok") & points["mode"].ne("trapped")]
    moving = moving[np.isfinite(moving["fraction"].astype(float))]
    for gid, g in moving.groupby(group, sort=True):
        f = g.groupby("length")["fraction"].mean().sort_index()
        L, d = f.index.to_numpy(float), f.to_numpy(float) - LEVEL
        for k in range(len(L) - 1):
            if d[k] * d[k + 1] < 0:
                rows.append({
                    "group": str(gid), "axis": "length", "theta0": np.nan, "y0": np.nan,
                    "length": round(0.5 * (L[k] + L[k + 1]), _DIGITS), "lo": L[k],
                    "hi": L[k + 1], "class_lo": f"{f.iloc[k]:.3f}",
                    "class_hi": f"{f.iloc[k + 1]:.3f}", "kind": "fraction",
                })  # fmt: skip
    return pd.DataFrame(rows, columns=BRACKET_COLUMNS)


def propose_lengths(
    points: pd.DataFrame,
    tolerance: float,
    budget: int,
    draw: Callable[[str, float], tuple[np.ndarray, np.ndarray]],
    group: str = "settings",
):
    """The next lengths to run and their starts, within the budget.

    Parameters
    ----------
    points : DataFrame
        As for :func:`length_brackets`, every task of the sweep so far.
    tolerance : float
        Widest bracket [µm] that counts as located.
    budget : int
        Most new runs; a length is added with all its starts or not at all.
    draw : callable
        ``draw(group, L)`` -> (theta0 [deg], y0) arrays of that length's seeded starts.

    Returns
    -------
    Proposal
        ``new``: columns group, theta0, y0, length; ``brackets`` with their state
        ('located', 'open' or 'stuck': the midpoint was run and has no mean, every
        run of it trapped or failed).
    """
    b = length_brackets(points, group)
    empty = pd.DataFrame({c: pd.Series(dtype=float) for c in ("group", *COORDS)})
    if b.empty:
        return Proposal(empty, b.assign(state=pd.Series(dtype=str)))
    known = {
        (str(gid), round(float(L), 9))
        for gid, L in zip(points[group], points["length"], strict=True)
    }
    width = (b["hi"] - b["lo"]).astype(float)
    wide = width > tolerance * (1.0 + 1e-9)
    ran = [(g, round(float(L), 9)) in known for g, L in zip(b["group"], b["length"], strict=True)]
    stuck = wide & np.array(ran, dtype=bool)
    b = b.assign(state=np.where(~wide, "located", np.where(stuck, "stuck", "open")))
    todo = b.assign(_rel=width / tolerance)  # before filtering: an empty frame takes no column
    todo = todo[todo["state"] == "open"]
    todo = todo.sort_values(["_rel", "group", "length"], ascending=[False, True, True])
    parts, left = [], int(budget)
    for row in todo.itertuples():
        t, y = draw(row.group, float(row.length))
        if len(t) > left:
            continue
        left -= len(t)
        parts.append(pd.DataFrame({"group": row.group, "theta0": t, "y0": y,
                                   "length": float(row.length)}))  # fmt: skip
    new = pd.concat(parts, ignore_index=True) if parts else empty
    return Proposal(new, b)
