"""Compare two sweep result folders run by run (same ids): classes and δ.

Used to show that a refactor leaves results unchanged, or to count what a change
of resolution or model moves.

Usage:  python scripts/compare_runs.py RESULTS_A RESULTS_B
"""

from __future__ import annotations

import argparse

import numpy as np

from fibersweep.sweep.store import read_runs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a")
    ap.add_argument("b")
    args = ap.parse_args()
    a, b = read_runs(args.a), read_runs(args.b)
    m = a.merge(b, on="id", suffixes=("_a", "_b"))
    print(f"runs: {len(a)} in A, {len(b)} in B, {len(m)} with the same id")
    changed = m[m["class_a"] != m["class_b"]]
    print(f"class changed: {len(changed)} of {len(m)}")
    if len(changed):
        cols = ["theta0_a", "y0_a", "length_a", "class_a", "class_b"]
        print(changed[cols].to_string(index=False))
    da, db = m["delta_a"].to_numpy(float), m["delta_b"].to_numpy(float)
    both = np.isfinite(da) & np.isfinite(db)
    nan_mismatch = int((np.isfinite(da) != np.isfinite(db)).sum())
    dmax = float(np.max(np.abs(da[both] - db[both]))) if both.any() else 0.0
    print(f"delta: max |A - B| = {dmax:.3g} h_obs over {int(both.sum())} runs; "
          f"NaN in one only: {nan_mismatch}")  # fmt: skip


if __name__ == "__main__":
    main()
