"""Check a paper-style sweep against the source's qualitative observations.

Prints, for a results folder: class counts; the fraction of runs with contact
below y0/h = 0.2 and above 0.55 (the source: none); the largest |δ| of runs
without contact (source: < 0.07); the mean δ per fiber length in the window
0.3 ≤ y0/h ≤ 0.55 (source: grows with L); the fraction of positive δ (source:
most); and where pole-vaulting and trapping occur (θ0 sign, y0 range).

Usage: python scripts/studies/fidelity/source_checks.py RESULTS
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from fibersweep.sweep.store import read_runs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", type=Path)
    args = ap.parse_args()
    runs = read_runs(args.results)
    ok = runs[runs["status"] == "ok"]
    print(f"{len(ok)} ok runs; classes: {ok['class'].value_counts().to_dict()}")
    contact = ok["contact"].astype(bool)
    for name, sel in (
        ("y0/h < 0.2", ok["y0"] < 0.2 - 1e-9),
        ("y0/h > 0.55", ok["y0"] > 0.55 + 1e-9),
    ):
        print(f"contact for {name}: {int(contact[sel].sum())} of {int(sel.sum())} runs")
    free = ok[~contact & ok["delta"].notna()]
    print(f"largest |delta| without contact: {np.abs(free['delta']).max():.3f} ({len(free)} runs)")
    window = ok[(ok["y0"] >= 0.3 - 1e-9) & (ok["y0"] <= 0.55 + 1e-9) & ok["delta"].notna()]
    means = window.groupby("length")["delta"].mean()
    print("mean delta in 0.3 <= y0/h <= 0.55 by L/l_obs: " + ", ".join(
        f"{L:g}: {d:.3f}" for L, d in means.items()))  # fmt: skip
    d = ok["delta"].dropna()
    print(f"positive delta: {(d > 0).mean():.1%} of {len(d)}; negative: {int((d < 0).sum())}, "
          f"of which theta0 < 0: {int((ok.loc[d.index[d < 0], 'theta0'] < 0).sum())}")  # fmt: skip
    for cls in ("Pole-vaulting", "Trapping"):
        sub = ok[ok["class"] == cls]
        if sub.empty:
            print(f"{cls}: none")
            continue
        print(
            f"{cls}: {len(sub)} runs; theta0 < 0: {int((sub['theta0'] < 0).sum())}, "
            f"theta0 > 0: {int((sub['theta0'] > 0).sum())}; y0/h in "
            f"[{sub['y0'].min():.2f}, {sub['y0'].max():.2f}]"
        )


if __name__ == "__main__":
    main()
