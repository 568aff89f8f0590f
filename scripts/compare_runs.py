"""Compare two sweep result folders run by run (same ids): classes and δ, or bit for bit.

Used to show that a refactor leaves results unchanged, or to count what a change
of resolution or model moves.

* default: class changes and the largest |δ_A - δ_B|;
* ``--exact``: every physical column of every run and every trajectory sample must
  be equal bit for bit (NaN equal to NaN; the columns that record when, where and
  how long a run ran are left out, and columns only one side has are listed);
  exit status 1 on any difference;
* ``--snapshot``: A and B are folders of ``scripts/snapshot_discrepancy.py``
  (the discrepancy workflow's every simulated batch, the synthesised tables and
  the verdict), compared bit for bit the same way;
* ``--by-start``: match runs on their start (θ0, y0, length) and swept settings
  instead of their id, for two fields whose keys differ (a change of the flow
  solver changes every run id); with array runs also the transport mode and the
  displaced fraction f, run by run and averaged per length.

Usage:  python scripts/compare_runs.py RESULTS_A RESULTS_B [--exact | --snapshot | --by-start]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from fibersweep.sweep.store import read_runs, read_trajectories

#: Columns that say when, where and how long a run ran: not results.
VOLATILE = ("wall_time", "cpu_time", "worker", "finished_at", "attempts")


def _same(a: pd.Series, b: pd.Series) -> np.ndarray:
    """Element-wise equality, bit for bit for floats (NaN equal to NaN)."""
    va, vb = a.to_numpy(), b.to_numpy()
    if va.dtype.kind == "f" and vb.dtype.kind == "f":
        return (va.view(np.int64) == vb.view(np.int64)) | (np.isnan(va) & np.isnan(vb))
    eq = []
    for x, y in zip(va, vb, strict=True):
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            eq.append(np.array_equal(np.asarray(x), np.asarray(y), equal_nan=True))
        else:
            eq.append(x == y or (pd.isna(x) and pd.isna(y)))
    return np.array(eq, dtype=bool)


def diff_tables(a: pd.DataFrame, b: pd.DataFrame, key: list[str], what: str) -> int:
    """Print every column that differs between ``a`` and ``b`` (rows matched on ``key``)."""
    bad = 0
    only = sorted(set(a.columns) ^ set(b.columns))
    if only:
        print(f"{what}: columns in one side only: {only}")
    if len(a) != len(b):
        print(f"{what}: {len(a)} rows in A, {len(b)} in B")
        return 1
    a = a.sort_values(key, kind="stable").reset_index(drop=True)
    b = b.sort_values(key, kind="stable").reset_index(drop=True)
    for col in [c for c in a.columns if c in b.columns]:
        same = _same(a[col], b[col])
        if not same.all():
            bad += 1
            k = int(np.flatnonzero(~same)[0])
            where, va, vb = a.loc[k, key].tolist(), a.loc[k, col], b.loc[k, col]
            print(f"{what}: column {col!r} differs in {int((~same).sum())} of {len(a)} rows, "
                  f"e.g. {where}: {va!r} vs {vb!r}")  # fmt: skip
    print(f"{what}: {len(a)} rows, {len(a.columns)} columns: "
          f"{'identical' if not bad else f'{bad} columns differ'}")  # fmt: skip
    return bad


def exact(a: str, b: str) -> int:
    """Bit-for-bit comparison of two results folders; number of differing tables/columns."""
    ra = read_runs(a).drop(columns=list(VOLATILE), errors="ignore")
    rb = read_runs(b).drop(columns=list(VOLATILE), errors="ignore")
    bad = diff_tables(ra, rb, ["id"], "runs")
    ta, tb = read_trajectories(a), read_trajectories(b)
    return bad + diff_tables(ta, tb, ["id", "sample"], "trajectories")


def snapshot(a: str, b: str) -> int:
    """Bit-for-bit comparison of two discrepancy snapshots (scripts/snapshot_discrepancy.py)."""
    bad = 0
    for name, key in (("measured", ["fiber_id"]), ("tracks", ["fiber_id", "t"]),
                      ("batches", ["batch"])):  # fmt: skip
        da = pd.read_parquet(Path(a) / f"{name}.parquet")
        db = pd.read_parquet(Path(b) / f"{name}.parquet")
        if name == "batches":  # rows in batch order, then position in the batch
            da["pos"] = da.groupby("batch").cumcount()
            db["pos"] = db.groupby("batch").cumcount()
            key = ["batch", "pos"]
        bad += diff_tables(da, db, key, name)
    va = json.loads((Path(a) / "verdict.json").read_text())
    vb = json.loads((Path(b) / "verdict.json").read_text())
    print(f"verdict: A {va['kind']} {va['effects']}, B {vb['kind']} {vb['effects']}: "
          f"{'identical' if va == vb else 'DIFFERENT'}")  # fmt: skip
    return bad + (va != vb)


def _start_key(runs: pd.DataFrame) -> list[str]:
    """Columns that say which run it is: the start and every swept setting."""
    return ["theta0", "y0", "length", *sorted(c for c in runs.columns if "." in c)]


def summary(a_dir: str, b_dir: str, by_start: bool = False) -> None:
    """Class (and mode) changes and the largest δ (and f) difference of matching runs."""
    a, b = read_runs(a_dir), read_runs(b_dir)
    key = _start_key(a) if by_start else ["id"]
    m = a.merge(b, on=key, suffixes=("_a", "_b"))
    same = "start" if by_start else "id"
    print(f"runs: {len(a)} in A, {len(b)} in B, {len(m)} with the same {same}")
    changed = m[m["class_a"] != m["class_b"]]
    print(f"class changed: {len(changed)} of {len(m)}")
    if len(changed):
        cols = ["theta0", "y0", "length"] if by_start else ["theta0_a", "y0_a", "length_a"]
        print(changed[[*cols, "class_a", "class_b"]].to_string(index=False))
    da, db = m["delta_a"].to_numpy(float), m["delta_b"].to_numpy(float)
    both = np.isfinite(da) & np.isfinite(db)
    nan_mismatch = int((np.isfinite(da) != np.isfinite(db)).sum())
    dmax = float(np.max(np.abs(da[both] - db[both]))) if both.any() else 0.0
    print(f"delta: max |A - B| = {dmax:.3g} h_obs over {int(both.sum())} runs; "
          f"NaN in one only: {nan_mismatch}")  # fmt: skip
    if "mode_a" in m:
        moved = m[m["mode_a"] != m["mode_b"]]
        print(f"mode changed: {len(moved)} of {len(m)}")
        if len(moved):
            cols = [*key, "mode_a", "mode_b", "fraction_a", "fraction_b"]
            print(moved[cols].to_string(index=False))
        fa, fb = m["fraction_a"].to_numpy(float), m["fraction_b"].to_numpy(float)
        ok = np.isfinite(fa) & np.isfinite(fb)
        worst = float(np.max(np.abs(fa[ok] - fb[ok]))) if ok.any() else 0.0
        print(f"f: max |A - B| = {worst:.3g} over {int(ok.sum())} runs")
        group = [c for c in key if c not in ("theta0", "y0")]
        per = m.groupby(group)[["fraction_a", "fraction_b"]].mean()
        per["|A - B|"] = (per["fraction_a"] - per["fraction_b"]).abs()
        print("mean f per length (and setting):")
        print(per.to_string())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a")
    ap.add_argument("b")
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--exact", action="store_true", help="every column, bit for bit")
    mode.add_argument("--snapshot", action="store_true", help="two discrepancy snapshots")
    mode.add_argument("--by-start", action="store_true",
                      help="match runs on start and swept settings, not id")  # fmt: skip
    args = ap.parse_args()
    if args.exact:
        sys.exit(1 if exact(args.a, args.b) else 0)
    if args.snapshot:
        sys.exit(1 if snapshot(args.a, args.b) else 0)
    summary(args.a, args.b, by_start=args.by_start)


if __name__ == "__main__":
    main()
