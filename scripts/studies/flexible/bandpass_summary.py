"""Per stiffness and length of a flexible array sweep: migration, modes, deformation, failures.

The numbers of docs/validation/flexible.md, "Array: the band-pass filter":

    python3 scripts/studies/flexible/bandpass_summary.py results/array-flexible
    python3 scripts/studies/flexible/bandpass_summary.py results/array-bandpass-600

Modes are re-derived from the stored trajectories with the default rule (as
``fibersweep sort-report`` does). Per (E, L) it prints the runs, the mean
fraction f of the full displacement over the runs not trapped, the mode counts,
the failed runs and why, the median and largest ``max_curvature`` [1/µm] and
``max_wrap`` [deg], the median ``min_end_to_end``, the median ``max_tension`` [nN],
and, where bead positions were kept (``fiber.record.all_beads``), the smallest
distance between beads far enough apart along the chain to repel (|i − j| at least
the chain's exclusion gap: 2 at spacing 2a, 4 at a, 8 at a/2) over the stored
samples [µm] (the kernel's own steps are denser, so this is an upper bound of the
true smallest distance).
"""

from __future__ import annotations

import argparse
import logging
from collections import Counter

import numpy as np
import pandas as pd

from fibersweep.analysis.modes import ModeSettings
from fibersweep.fiber.models.exclusion import min_self_distance
from fibersweep.fiber.models.spacing import exclusion_gap
from fibersweep.results import load_array_results
from fibersweep.sorting import report as sr

log = logging.getLogger(__name__)

ABBREV = {
    "displacement": "D",
    "zigzag": "Z",
    "wrap-and-jump": "W",
    "trapped": "T",
    "mixed": "M",
}


def summary(results: str) -> pd.DataFrame:
    """One row per (setting, length) of the sweep in ``results`` (see the module docstring)."""
    runs, settings, cfg = load_array_results(results)
    runs = sr.relabel(runs, settings, ModeSettings(), cfg["fiber"]["classify"]["trap_speed"])
    has_beads = "traj_beads" in runs
    fiber_spacing = cfg["fiber"].get("bead_spacing", 1.0)
    rows = []
    for (s, length), g in runs.groupby(["setting", "length"], sort=True):
        moving = g[g["mode"] != "trapped"]
        modes = Counter(g["mode"])
        failed = Counter(g.loc[g["status"] == "failed", "reason"])
        row = {
            "setting": settings[s]["label"],
            "L": length,
            "runs": len(g),
            "f": float(moving["fraction"].mean()),
            "modes": ", ".join(f"{c} {ABBREV.get(m, m)}" for m, c in modes.most_common()),
            "failed": ", ".join(f"{c} {r}" for r, c in failed.items()),
            "curv_med": float(g["max_curvature"].median()),
            "curv_max": float(g["max_curvature"].max()),
            "wrap_med": float(g["max_wrap"].median()),
            "wrap_max": float(g["max_wrap"].max()),
            "e2e_med": float(g["min_end_to_end"].median()),
            "tension_med_nN": float(g["max_tension"].median()) / 1e3,
        }
        if has_beads:
            spacing = settings[s]["values"].get("fiber.bead_spacing", fiber_spacing)
            gap = exclusion_gap(float(spacing))
            d = [min_self_distance(b, gap) for b in g["traj_beads"] if b is not None]
            row["self_min"] = float(np.min(d)) if d else np.nan
        rows.append(row)
    return pd.DataFrame(rows)


def tension_by_mode(results: str) -> pd.DataFrame:
    """Median ``max_tension`` [nN] and runs per (setting, mode)."""
    runs, settings, cfg = load_array_results(results)
    runs = sr.relabel(runs, settings, ModeSettings(), cfg["fiber"]["classify"]["trap_speed"])
    runs["label"] = runs["setting"].map(lambda i: settings[i]["label"])
    g = runs.groupby(["label", "mode"])["max_tension"]
    return pd.DataFrame({"runs": g.size(), "tension_med_nN": g.median() / 1e3}).reset_index()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", help="output folder of a flexible array sweep")
    args = ap.parse_args()
    pd.set_option("display.width", 200)
    pd.set_option("display.max_columns", 30)
    print(summary(args.results).round(3).to_string(index=False))
    print(tension_by_mode(args.results).round(1).to_string(index=False))


if __name__ == "__main__":
    main()
