"""Sensitivity of the classification to its threshold, rule and trajectory sampling.

Reads a sweep's stored trajectories (fiber.record.trajectories: true) and labels
every ok run again, without simulating, with

* the head-speed rule (the source's) at head_blocked_speed = 0.005 ... 0.05 U_center,
* the pivot and switch rules,
* the head-speed rule on the stored trajectory re-thinned to 100 and 50 samples
  the way the simulation stores it (fibersweep.analysis.observables.thin_indices:
  contact and stop transitions kept, slowest head per time bin), and thinned
  naively to every 2nd sample (shows what the trap rule needs),

and prints, for each variant, the class counts and the fraction of runs whose
label differs from the reference (head-speed at 0.01, full stored sampling),
then lists the runs whose label depends on the variant (the runs to look at:
``fibersweep simulate CONFIG --theta0 .. --y0 .. --length .. --plot f.png``).
With ``--other DIR`` (the same sweep at another resolution) it also prints the
fraction of runs whose reference label differs between the two folders.

Usage: python scripts/studies/fidelity/classify_sensitivity.py RESULTS [--other RESULTS2] [--list \
    30]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

from fibersweep.analysis.classify import RULES, classify
from fibersweep.analysis.observables import take, thin_indices
from fibersweep.analysis.tables import trajectory_from_frame
from fibersweep.config.fiber import ClassifySettings
from fibersweep.config.flow import FlowSettings
from fibersweep.sweep.manifest import read_manifest
from fibersweep.sweep.store import read_runs, read_trajectories

THRESHOLDS = (0.005, 0.01, 0.02, 0.03, 0.05)
SAMPLES = (100, 50)


def labels(out: Path) -> pd.DataFrame:
    """One row per ok run: θ0, y0, L and its label under every variant."""
    man = read_manifest(out)
    flow = FlowSettings.model_validate(man["config"]["flow"])
    geometry = flow.geometry.to_geometry()
    u_center = man.get("u_center_effective") or flow.fluid.u_center
    base = ClassifySettings.model_validate(man["config"]["fiber"]["classify"])
    runs = read_runs(out)
    runs = runs[runs["status"] == "ok"].reset_index(drop=True)
    traj = dict(tuple(read_trajectories(out, list(runs["id"])).groupby("id", sort=False)))
    rows = []
    for _, run in runs.iterrows():
        if run["id"] not in traj:
            continue
        tr = trajectory_from_frame(traj[run["id"]].sort_values("sample"))
        row = {"theta0": run["theta0"], "y0": run["y0"], "length": run["length"]}
        for th in THRESHOLDS:
            s = base.model_copy(update={"head_blocked_speed": th, "rule": "head-speed"})
            row[f"head-speed {th:g}"] = classify(tr, geometry, u_center, s)
        ref = base.model_copy(update={"head_blocked_speed": 0.01, "rule": "head-speed"})
        for name in RULES:
            if name != "head-speed":
                row[name] = classify(tr, geometry, u_center, ref, name)
        for n in SAMPLES:
            idx = thin_indices(tr, n, u_center, ref)
            row[f"{n} samples"] = classify(take(tr, idx), geometry, u_center, ref)
        every2 = np.unique(np.r_[np.arange(0, len(tr.t), 2), len(tr.t) - 1])
        row["every 2nd"] = classify(take(tr, every2), geometry, u_center, ref)
        rows.append(row)
    return pd.DataFrame(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", type=Path)
    ap.add_argument("--other", type=Path, default=None)
    ap.add_argument("--list", type=int, default=30, help="runs listed whose label varies")
    args = ap.parse_args()
    df = labels(args.results)
    ref = "head-speed 0.01"
    variants = [c for c in df.columns if c not in ("theta0", "y0", "length")]
    print(f"{len(df)} runs of {args.results}; reference: {ref}")
    classes = ["Below", "Above", "Pole-vaulting", "Trapping", ""]
    print(f"{'variant':18s} " + " ".join(f"{c or 'undet.':>13s}" for c in classes) + "  changed")
    for v in variants:
        counts = df[v].value_counts()
        changed = float((df[v] != df[ref]).mean())
        print(
            f"{v:18s} "
            + " ".join(f"{int(counts.get(c, 0)):13d}" for c in classes)
            + f"  {changed:7.1%}"
        )
    varies = df[df[variants].nunique(axis=1) > 1]
    print(f"runs whose label depends on the variant: {len(varies)} ({len(varies) / len(df):.1%})")
    with pd.option_context("display.width", 200, "display.max_columns", 20):
        print(varies.head(args.list).to_string(index=False))
    if args.other is not None:
        other = labels(args.other)
        both = df.merge(other, on=["theta0", "y0", "length"], suffixes=("", " other"))
        for v in (ref, "pivot", "switch"):
            diff = both[both[v] != both[f"{v} other"]]
            print(
                f"{v}: {len(diff)} of {len(both)} runs ({len(diff) / max(len(both), 1):.1%}) "
                f"change class between {args.results} and {args.other}"
            )
            if len(diff):
                print(diff[["theta0", "y0", "length", v, f"{v} other"]].to_string(index=False))


if __name__ == "__main__":
    main()
