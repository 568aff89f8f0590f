"""What a sorter designer reads from an array sweep: migration vs length, critical lengths,
purity and recovery per outlet. Pure functions of the stored runs (``runs.parquet``).

Modes are re-derived from the stored trajectories (:func:`relabel`), so other
thresholds can be applied without simulating again.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from fibersweep.analysis.modes import MODES, ModeSettings, summarise_rows

__all__ = ["relabel", "migration_table", "critical_lengths", "outlet_table"]


def relabel(runs: pd.DataFrame, settings_meta: list[dict], modes: ModeSettings) -> pd.DataFrame:
    """Runs with ``mode``, ``fraction``, ``shift_per_row``, ``migration_angle`` recomputed."""
    out = runs.copy()
    for i, row in out.iterrows():
        arr = settings_meta[int(row["setting"])]["array"]
        traj = {
            c: np.asarray(row[f"traj_{c}"]) for c in ("t", "xc", "yc", "th", "contact", "speed")
        }
        s = summarise_rows(traj, arr["period_x"], arr["shift"] * arr["period_y"], modes)
        out.at[i, "mode"] = s.mode
        out.at[i, "fraction"] = s.fraction
        out.at[i, "shift_per_row"] = s.shift_per_row
        out.at[i, "migration_angle"] = s.angle_deg
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
