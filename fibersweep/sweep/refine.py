"""Adaptive refinement of class boundaries: which points to run next.

A refinement round bisects every bracket (:func:`fibersweep.analysis.boundaries.brackets`)
of the points known so far that is wider than its axis's tolerance. The new
points are a function of the known points and their stored outcomes alone, so a
refinement derives the same rounds again from the stored runs: an interrupted
refinement resumes without duplicates, and running the command again continues
where it stopped (:func:`fibersweep.sweep.runner.run_sweep` loops plan -> run ->
read classes -> :func:`propose`).

Termination: a bracket is bisected only while it is wider than the tolerance,
and a bracket whose midpoint is already known (a failed run, or one not stored)
is left alone (``stuck``), so a failed run never spawns further points. The
budget caps the total.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from fibersweep.analysis.boundaries import COORDS, brackets
from fibersweep.analysis.proposal import Proposal
from fibersweep.config import RefineSettings
from fibersweep.sorting.lengths import propose_lengths
from fibersweep.sweep.ids import run_ids
from fibersweep.sweep.plan import Setting
from fibersweep.sweep.worker import SweepTask

__all__ = [
    "next_round",
    "propose",
    "refinement_points",
    "refinement_summary",
    "refinement_tasks",
    "stored_rounds",
]

_DIGITS = 12  # midpoints rounded like axis values (stable ids)


def _key(frame: pd.DataFrame) -> pd.Series:
    """Group and rounded coordinates as one hashable key per row."""
    parts = [frame["group"].astype(str)]
    parts += [frame[c].astype(float).round(9).astype(str) for c in COORDS]
    return pd.Series(list(zip(*parts, strict=True)), index=frame.index, dtype=object)


def propose(
    points: pd.DataFrame,
    refine: RefineSettings,
    budget: int,
    *,
    group: str = "settings",
) -> Proposal:
    """Midpoints of every bracket wider than its tolerance, within the budget.

    Parameters
    ----------
    points : DataFrame
        Every point known so far (grid and earlier rounds): ``theta0``, ``y0``,
        ``length``, ``status``, ``class``, ``delta`` (NaN / empty for points
        not run or failed), and ``group`` if present.
    refine : RefineSettings
        Axes, tolerances and the δ-jump threshold.
    budget : int
        Most new points (>= 0).
    group : str
        Column of independent point sets (settings ids).

    Returns
    -------
    Proposal
    """
    b = brackets(points, refine.axes, delta_jump=refine.delta_jump, group=group)
    known = points.assign(group=points[group].astype(str) if group in points else "")
    known_keys = set(_key(known)) if len(known) else set()
    if b.empty:
        empty = pd.DataFrame({c: pd.Series(dtype=float) for c in ("group", *COORDS)})
        return Proposal(empty, b.assign(state=pd.Series(dtype=str)))
    tol = b["axis"].map(dict(refine.tolerance)).astype(float)
    width = (b["hi"] - b["lo"]).astype(float)
    b = b.copy()
    for axis in refine.axes:  # the exact midpoint, rounded as an axis value is
        on = b["axis"] == axis
        b.loc[on, axis] = np.round(0.5 * (b.loc[on, "lo"] + b.loc[on, "hi"]), _DIGITS)
    wide = width > tol * (1.0 + 1e-9)
    keys = _key(b)
    stuck = wide & keys.isin(known_keys)
    b["state"] = np.where(~wide, "located", np.where(stuck, "stuck", "open"))
    cand = b[wide & ~stuck].assign(_rel=(width / tol)[wide & ~stuck], _key=keys[wide & ~stuck])
    order = {a: i for i, a in enumerate(COORDS)}
    cand = cand.assign(_axis=cand["axis"].map(order))
    cand = cand.sort_values(
        ["_rel", "group", "_axis", *COORDS], ascending=[False, True, True, True, True, True],
        kind="stable",
    )  # fmt: skip
    cand = cand.drop_duplicates("_key").head(max(0, int(budget)))
    new = cand[["group", *COORDS]].reset_index(drop=True)
    return Proposal(new, b)


def refinement_summary(found: pd.DataFrame, rounds: int, runs: int, reason: str) -> dict[str, Any]:
    """What a refinement reached, for the manifest and the command line.

    Parameters
    ----------
    found : DataFrame
        :attr:`Proposal.brackets` of the last round.
    rounds, runs : int
        Refinement rounds and runs known so far (the grid excluded).
    reason : str
        Why it stopped: 'located' (every bracket within tolerance), 'stuck' (the
        others' midpoints failed or were not run), 'budget', 'rounds',
        'running' (a next round is known), 'interrupted', 'retry-failed'.
    """
    states: Mapping[str, int] = (
        found["state"].value_counts().to_dict() if "state" in found and len(found) else {}
    )
    return {
        "rounds": int(rounds),
        "runs": int(runs),
        "located": int(states.get("located", 0)),
        "open": int(states.get("open", 0)),
        "stuck": int(states.get("stuck", 0)),
        "stopped": reason,
    }


def refinement_points(tasks: Sequence[SweepTask], stored: pd.DataFrame) -> pd.DataFrame:
    """Points of a sweep with their stored outcomes, as :func:`propose` takes them.

    Returns
    -------
    DataFrame
        ``id``, ``settings``, ``theta0``, ``y0``, ``length``, ``round``, and from the
        store ``status``, ``class``, ``delta`` (missing for runs not stored).
    """
    pts = pd.DataFrame(
        {
            "id": [t.key for t in tasks],
            "settings": [t.settings for t in tasks],
            "theta0": [t.theta0 for t in tasks],
            "y0": [t.y0 for t in tasks],
            "length": [t.length for t in tasks],
            "round": [t.round for t in tasks],
        }
    )
    cols = ["id", "status", "class", "delta"]
    cols += [c for c in ("mode", "fraction") if c in stored]  # pillar-array runs
    have = stored[cols] if len(stored) else pd.DataFrame(columns=cols)
    return pts.merge(have, on="id", how="left")


def refinement_tasks(
    settings: Sequence[Setting], tasks: Sequence[SweepTask], new: pd.DataFrame, rnd: int
) -> list[SweepTask]:
    """Tasks of a refinement round's points (``group`` = settings id), with content ids.

    Each carries the swept values of its setting (taken from ``tasks``) and ``rnd``.
    """
    by_id = {st.id: st for st in settings}
    values = {t.settings: t.values for t in tasks}
    out: list[SweepTask] = []
    for sid, q in new.groupby("group", sort=False):
        st = by_id[str(sid)]
        t, y, L = (q[c].astype(float).tolist() for c in COORDS)
        ids = run_ids(t, y, L, st.config.fiber, st.flow_key)
        out += [
            SweepTask(rid, ti, yi, Li, st.id, st.flow_key, values.get(st.id, ()), rnd)
            for rid, ti, yi, Li in zip(ids, t, y, L, strict=True)
        ]
    return out


def next_round(
    refine: RefineSettings,
    settings: Sequence[Setting],
    tasks: Sequence[SweepTask],
    stored: pd.DataFrame,
    rnd: int,
) -> tuple[list[SweepTask], dict[str, Any]]:
    """Refinement round ``rnd + 1``: its tasks, from the stored outcomes of ``tasks``.

    Parameters
    ----------
    refine : RefineSettings
    settings : sequence of Setting
        The sweep's setting combinations (:attr:`SweepPlan.settings`).
    tasks : sequence of SweepTask
        Every point so far: the grid, then rounds 1 .. ``rnd``.
    stored : DataFrame
        The runs table (:func:`fibersweep.sweep.store.read_runs`).
    rnd : int
        The last round in ``tasks`` (0: the grid alone).

    Returns
    -------
    new : list of SweepTask
        Empty when the refinement is over.
    summary : dict
        :func:`refinement_summary` of the points so far.
    """
    pts = refinement_points(tasks, stored)
    used = int((pts["round"] > 0).sum())
    if _random_starts(settings):  # a pillar array's critical length (refine_lengths)
        prop = propose_lengths(pts, float(refine.tolerance["length"]),
                               refine.max_runs - used, _drawer(settings))  # fmt: skip
    else:
        prop = propose(pts, refine, refine.max_runs - used)
    states = prop.brackets.get("state", pd.Series(dtype=str))
    open_, stuck = int((states == "open").sum()), int((states == "stuck").sum())
    done = "stuck" if stuck else "located"
    if rnd >= refine.rounds:
        reason, new = ("rounds" if open_ else done), []
    else:
        new = refinement_tasks(settings, tasks, prop.new, rnd + 1)
        reason = "budget" if open_ > len(new) else "running" if new else done
    return new, refinement_summary(prop.brackets, rnd, used, reason)


def _random_starts(settings: Sequence[Setting]) -> bool:
    return bool(settings) and settings[0].config.sweep.random is not None


def _drawer(settings: Sequence[Setting]):
    """(settings id, L) -> that length's seeded starts (theta0, y0), as the grid draws them."""
    from fibersweep.sweep.draws import start_points

    by_id = {st.id: st for st in settings}

    def draw(sid: str, length: float) -> tuple[np.ndarray, np.ndarray]:
        cfg = by_id[str(sid)].config
        one = cfg.sweep.model_copy(update={"length": [float(length)], "refine": None})
        t, y, _ = start_points(cfg.model_copy(update={"sweep": one}))
        return t, y

    return draw


def stored_rounds(
    refine: RefineSettings,
    settings: Sequence[Setting],
    tasks: Sequence[SweepTask],
    stored: pd.DataFrame,
) -> tuple[list[SweepTask], int, dict[str, Any] | None]:
    """The refinement rounds the stored runs already determine.

    Round ``k + 1`` is determined once every point of rounds 0 .. k is stored
    (ok or failed); the walk stops at the first round with a point not stored
    (it is returned, to be run) or when the refinement is over.

    Returns
    -------
    extra : list of SweepTask
        Points of rounds 1 .. ``rnd`` (the last may be partly stored).
    rnd : int
        The last round in ``extra`` (0: none).
    summary : dict or None
        :func:`refinement_summary` after the last complete round (None when the
        grid is not complete).
    """
    have = set(stored["id"]) if len(stored) else set()
    tasks = list(tasks)
    if any(t.key not in have for t in tasks):
        return [], 0, None
    extra: list[SweepTask] = []
    rnd = 0
    while True:
        new, info = next_round(refine, settings, [*tasks, *extra], stored, rnd)
        if not new:
            return extra, rnd, info
        rnd += 1
        extra += new
        if any(t.key not in have for t in new):
            return extra, rnd, info
