"""Transport modes of pillar-array runs: counts per mode, and re-labelling from trajectories.

An array run's mode and migration (:mod:`fibersweep.analysis.modes`) are a pure
function of its stored trajectory, its array and the trap rule
(``fiber.classify.trap_speed`` × the setting's U_center), so ``fibersweep
classify`` re-derives them without simulating (:func:`relabel_modes`); the store
is read and rewritten by :mod:`fibersweep.sweep.reclassify`.
"""

from __future__ import annotations

import logging

import numpy as np
import pandas as pd

from fibersweep.analysis.modes import MODES, summarise_trajectory
from fibersweep.analysis.tables import per_combination, trajectory_from_frame
from fibersweep.config.array import ArraySettings
from fibersweep.config.fiber import ClassifySettings

__all__ = ["is_array_table", "mode_counts", "pick_run", "relabel_modes"]

log = logging.getLogger(__name__)

#: Columns re-derived from the trajectory.
RELABELLED = ("rows", "shift_per_row", "migration_angle", "fraction", "mode", "wraps")


def is_array_table(runs: pd.DataFrame) -> bool:
    """Whether a runs table holds pillar-array runs (a ``mode`` column with values)."""
    return "mode" in runs and bool(runs["mode"].notna().any())


def mode_counts(runs: pd.DataFrame, by: list[str] | None = None) -> pd.DataFrame:
    """Runs per mode (ok runs) and failures, with fractions; one block per swept combination."""
    by = [k for k in (by or []) if k in runs]
    if by:
        return per_combination(runs, by, mode_counts)
    ok = runs[runs["status"] == "ok"]
    rows = [(m, int((ok["mode"] == m).sum())) for m in MODES]
    rows.append(("failed", int((runs["status"] != "ok").sum())))
    df = pd.DataFrame(rows, columns=["mode", "runs"])
    df["fraction"] = (df["runs"] / max(1, int(df["runs"].sum()))).round(4)
    return df


def pick_run(runs: pd.DataFrame, mode: str) -> dict | None:
    """A run that shows ``mode`` (for a chronophotograph), or None when no run is in it.

    At the length where the mode is most common: a wrap-and-jump run with the most wraps,
    any other the run whose ``fraction`` is nearest the median of that length's.
    """
    m = runs[runs["mode"] == mode]
    if m.empty:
        return None
    L = m["length"].value_counts().sort_index().idxmax()
    g = m[m["length"] == L]
    if mode == "wrap-and-jump" and "wraps" in g:
        return g.sort_values("wraps", ascending=False).iloc[0].to_dict()
    f = g["fraction"].to_numpy(float)
    return (
        g.iloc[int(np.nanargmin(np.abs(f - np.nanmedian(f))))].to_dict()
        if np.isfinite(f).any()
        else g.iloc[0].to_dict()
    )


def relabel_modes(
    runs: pd.DataFrame, traj: pd.DataFrame, man: dict, thresholds: ClassifySettings
) -> tuple[pd.DataFrame, int]:
    """Re-label every array run that has a stored trajectory.

    Parameters
    ----------
    runs : DataFrame
        The runs table (one row per run, ``id``, ``settings``, ``mode`` ...).
    traj : DataFrame
        The stored trajectory samples of those runs (``id``, ``sample``, ``t`` ...).
    man : dict
        The sweep's manifest (each setting's flow and effective U_center).
    thresholds : ClassifySettings
        The trap rule's thresholds (``trap_speed`` × U_center stops a run).

    Returns
    -------
    runs : DataFrame
        A copy with the columns of :data:`RELABELLED` re-derived.
    changed : int
        Runs whose mode changed.
    """
    combos = man.get("combinations") or {}
    base_flow = man["config"]["flow"]

    def context(sid: str):
        entry = combos.get(sid) or {}
        flow = entry.get("flow") or base_flow
        u = entry.get("u_center_effective") or flow["fluid"]["u_center"]
        return ArraySettings.model_validate(flow["array"]).to_array(), float(u)

    contexts: dict[str, tuple] = {}
    groups = dict(tuple(traj.groupby("id", sort=False)))
    runs = runs.copy()
    old_mode = runs["mode"].copy()
    for i in range(len(runs)):
        rid = runs.at[i, "id"]
        if rid not in groups or pd.isna(runs.at[i, "mode"]):
            continue
        sid = runs.at[i, "settings"]
        if sid not in contexts:
            contexts[sid] = context(sid)
        array, u = contexts[sid]
        summ = summarise_trajectory(
            trajectory_from_frame(groups[rid].sort_values("sample")),
            array,
            thresholds.trap_speed * u,
        )
        for col, value in zip(
            RELABELLED,
            (summ.rows, summ.shift_per_row, summ.angle_deg, summ.fraction, summ.mode, summ.wraps),
            strict=True,
        ):
            runs.at[i, col] = value
    return runs, int((runs["mode"] != old_mode).sum())
