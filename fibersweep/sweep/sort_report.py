"""What a sorter designer reads from an array sweep: migration vs length, critical lengths,
purity and recovery per outlet. Pure functions of the standard results store.

An array sweep is an ordinary ``fibersweep run`` with ``flow.array`` set: its
runs table (``runs/``, one row per run with the array columns), its
trajectories (``trajectories/``) and its manifest (each setting combination's
flow settings and U_center). :func:`load_array_results` reads them; the modes
are re-derived from the stored trajectories (:func:`relabel`), so other
thresholds can be applied without simulating again.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from fibersweep.analysis.modes import MODES, ModeSettings, summarise_rows
from fibersweep.errors import InputError

__all__ = [
    "load_array_results",
    "relabel",
    "migration_table",
    "critical_lengths",
    "refine_lengths",
    "outlet_table",
]


def load_array_results(results: str | Path) -> tuple[pd.DataFrame, list[dict], dict]:
    """The runs, settings and config of an array sweep's results folder.

    Returns
    -------
    runs : DataFrame
        The runs table with ``setting`` (index into ``settings``) and
        ``setting_label`` added, and the thinned trajectory of each run as list
        columns ``traj_t`` [s], ``traj_xc``, ``traj_yc`` [µm], ``traj_th`` [rad],
        ``traj_contact`` (0/1), ``traj_speed`` [µm/s].
    settings : list of dict
        Per setting combination: ``id``, ``label``, ``array`` (the flow.array
        settings), ``flow`` (all flow settings), ``flow_key``, ``u_center`` [µm/s].
    config : dict
        The stored config (JSON).

    Raises
    ------
    InputError
        The folder holds no sweep, or its runs are not pillar-array runs.
    """
    from fibersweep.sweep.manifest import read_manifest
    from fibersweep.sweep.store import read_runs, read_trajectories

    results = Path(results)
    man = read_manifest(results)
    if man is None:
        raise InputError(f"RESULTS: {results} holds no sweep (no manifest.json)")
    runs = read_runs(results)
    if "mode" not in runs or not runs["mode"].notna().any():
        raise InputError(
            f"RESULTS: {results} holds no pillar-array runs (run a config with flow.array)"
        )
    runs = runs[runs["mode"].notna()].copy()
    combos = man.get("combinations") or {}
    settings = []
    sids = sorted(pd.unique(runs["settings"]), key=lambda sid: _order(combos.get(sid, {})))
    for sid in sids:
        entry = combos.get(sid, {})
        flow = entry.get("flow") or man["config"]["flow"]
        values = entry.get("values") or {}
        settings.append(
            {
                "id": sid,
                "label": ", ".join(_value_label(k, v) for k, v in values.items()),
                "array": flow["array"],
                "flow": flow,
                "flow_key": entry.get("flow_key", ""),
                "u_center": entry.get("u_center_effective") or flow["fluid"]["u_center"],
            }
        )
    index = {s["id"]: i for i, s in enumerate(settings)}
    runs["setting"] = runs["settings"].map(index).astype(int)
    runs["setting_label"] = runs["setting"].map(lambda i: settings[i]["label"])
    traj = read_trajectories(results, list(runs["id"]))
    if traj.empty:
        raise InputError(f"RESULTS: {results} holds no trajectories of its array runs")
    by_id = {rid: g for rid, g in traj.groupby("id", sort=False)}
    cols = {"traj_t": "t", "traj_xc": "x", "traj_yc": "y", "traj_speed": "com_speed"}
    for name, c in cols.items():
        runs[name] = [by_id[r][c].to_numpy(np.float64) for r in runs["id"]]
    runs["traj_th"] = [np.radians(by_id[r]["theta"].to_numpy(np.float64)) for r in runs["id"]]
    runs["traj_contact"] = [by_id[r]["contact"].to_numpy(np.float64) for r in runs["id"]]
    if "beads" in traj.columns:  # bead-spring runs with fiber.record.all_beads
        runs["traj_beads"] = [_beads(by_id[r]["beads"]) for r in runs["id"]]
    return runs.reset_index(drop=True), settings, man["config"]


def _order(entry: dict) -> tuple:
    """Sort key of a setting combination: its swept values (numbers by value)."""
    vals = (entry.get("values") or {}).values()
    return tuple(
        (0, float(v), "") if isinstance(v, int | float) else (1, 0.0, str(v)) for v in vals
    )


def _value_label(key: str, value) -> str:
    """'young_modulus = 1e+06 Pa': the setting's last part, its value and unit."""
    from fibersweep.config import setting_column

    unit = setting_column(key)[1]
    text = f"{value:g}" if isinstance(value, int | float) else str(value)
    return f"{key.rsplit('.', 1)[-1]} = {text}{' ' + unit if unit else ''}"


def _beads(column: pd.Series) -> np.ndarray | None:
    """Stored bead positions of one run as (samples, n_beads, 2) [µm], or None."""
    rows = [np.asarray(v, dtype=np.float64) for v in column if v is not None]
    if len(rows) != len(column) or not rows or rows[0].size < 4:
        return None
    return np.stack(rows).reshape(len(rows), -1, 2)


def relabel(
    runs: pd.DataFrame, settings_meta: list[dict], modes: ModeSettings, trap_speed: float
) -> pd.DataFrame:
    """Runs with ``mode``, ``fraction``, ``shift_per_row``, ``migration_angle`` recomputed.

    ``trap_speed``: ``fiber.classify.trap_speed`` (a fraction of each setting's U_center).
    """
    import dataclasses

    out = runs.copy()
    for i, row in out.iterrows():
        meta = settings_meta[int(row["setting"])]
        arr = meta["array"]
        rule = dataclasses.replace(modes, trap_speed=trap_speed * meta["u_center"])
        traj = {
            c: np.asarray(row[f"traj_{c}"]) for c in ("t", "xc", "yc", "th", "contact", "speed")
        }
        summ = summarise_rows(traj, arr["period_x"], arr["shift"] * arr["period_y"], rule)
        out.at[i, "mode"] = summ.mode
        out.at[i, "fraction"] = summ.fraction
        out.at[i, "shift_per_row"] = summ.shift_per_row
        out.at[i, "migration_angle"] = summ.angle_deg
    return out


def migration_table(runs: pd.DataFrame) -> pd.DataFrame:
    """Per (setting, length): runs, mean and standard deviation of the migration angle [deg]
    and of the fraction, and the fraction of runs in each mode."""
    rows = []
    for (s, L), g in runs.groupby(["setting", "length"], sort=True):
        moving = g[g["mode"] != "trapped"]
        r = {
            "setting": s,
            "setting_label": g["setting_label"].iloc[0],
            "length": L,
            "runs": len(g),
            "angle_mean": float(moving["migration_angle"].mean()),
            "angle_std": float(moving["migration_angle"].std(ddof=1)) if len(moving) > 1 else 0.0,
            "fraction_mean": float(moving["fraction"].mean()),
            "fraction_std": float(moving["fraction"].std(ddof=1)) if len(moving) > 1 else 0.0,
        }
        for m in MODES:
            r[m] = float((g["mode"] == m).mean())
        rows.append(r)
    return pd.DataFrame(rows)


def critical_lengths(table: pd.DataFrame, level: float = 0.5) -> dict[int, list[float]]:
    """Per setting, the lengths [µm] where the mean fraction crosses ``level`` (linear in L)."""
    out: dict[int, list[float]] = {}
    for s, g in table.groupby("setting"):
        g = g.sort_values("length")
        L = g["length"].to_numpy()
        f = g["fraction_mean"].to_numpy() - level
        found = []
        for k in range(len(L) - 1):
            if np.isfinite(f[k]) and np.isfinite(f[k + 1]) and f[k] * f[k + 1] < 0:
                found.append(float(L[k] - f[k] * (L[k + 1] - L[k]) / (f[k + 1] - f[k])))
        out[int(s)] = found
    return out


def refine_lengths(table: pd.DataFrame, level: float = 0.5) -> dict[int, list[float]]:
    """Per setting, the midpoints [µm] of neighbouring lengths whose mean fraction brackets
    ``level``: the lengths to add to ``sweep.length`` to bisect the critical length.

    A pure function of :func:`migration_table` (trapped runs are out of its means).
    Running the same config with them added into the same folder runs only them: the
    draws of a length depend on it alone, so the other runs keep their ids.
    """
    out: dict[int, list[float]] = {}
    for s, g in table.groupby("setting"):
        g = g.sort_values("length")
        L = g["length"].to_numpy()
        d = g["fraction_mean"].to_numpy() - level
        out[int(s)] = [
            float(0.5 * (L[k] + L[k + 1]))
            for k in range(len(L) - 1)
            if np.isfinite(d[k] * d[k + 1]) and d[k] * d[k + 1] < 0
        ]
    return out


def outlet_table(runs: pd.DataFrame, settings_meta: list[dict], rows: int,
                 edges: list[float]) -> pd.DataFrame:  # fmt: skip
    """Purity and recovery per outlet of a device of ``rows`` rows, for each length.

    Every fiber enters at one point; it leaves at the lateral position
    rows × (its shift per row) (a trapped fiber leaves nowhere). Outlets are
    the intervals between ``edges``, given as fractions of the displacement
    mode's exit rows ε λy (0: straight on, 1: fully displaced). Recovery of a
    length in an outlet: the share of that length's fibers that leave there;
    purity: the share of that outlet's fibers that have that length (equal
    numbers of each length fed).
    """
    bounds = [-math.inf, *sorted(edges), math.inf]
    out = []
    for s, g in runs.groupby("setting"):
        arr = settings_meta[int(s)]["array"]
        full = rows * arr["shift"] * arr["period_y"]
        exit_frac = rows * g["shift_per_row"] / full
        ok = g["mode"] != "trapped"
        counts = {}
        for L, gl in g.groupby("length"):
            e = exit_frac[gl.index][ok[gl.index]]
            counts[L] = [int(((e >= bounds[k]) & (e < bounds[k + 1])).sum())
                         for k in range(len(bounds) - 1)]  # fmt: skip
            counts[L].append(len(gl))
        for k in range(len(bounds) - 1):
            tot = sum(c[k] / c[-1] for c in counts.values())
            for L, c in counts.items():
                rec = c[k] / c[-1]
                pur = rec / tot if tot > 0 else math.nan
                out.append(
                    {"setting": int(s), "outlet": k, "from": bounds[k], "to": bounds[k + 1],
                     "length": L, "recovery": rec, "purity": pur}
                )  # fmt: skip
    return pd.DataFrame(out)
