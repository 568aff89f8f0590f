#!/usr/bin/env python3
"""Discrepancy wall time of two source trees, measured alternately in one run, as a ratio.

Runs each tree's own snapshot script (``scripts/tools/snapshot_discrepancy.py``, or
``scripts/snapshot_discrepancy.py`` in a tree of the former layout; its API may differ)
with ``PYTHONPATH`` set to that tree, A B A B ..., on the same flow-field cache, and
reads the workflow's wall time from each snapshot's ``timing.json``. Prints every
time, the ratio B / A of each pair and their median, and whether the two trees
simulated the same batches and reached the same verdict (bit for bit).

Usage:  python scripts/benchmarks/bench_discrepancy_ab.py [OLD_TREE [NEW_TREE]] [--n 20]
            [--pairs 3] [--cache DIR] [--out DIR]

A tree not given is this repository (the smoke pass compares it with itself).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

import pandas as pd

REPO = Path(__file__).resolve().parents[2]

#: a smoke pass (scripts/benchmarks/run.py --smoke): this tree against itself, 8 fibers
SMOKE = ["--n", "8", "--pairs", "1", "--cache", "{cache}", "--out", "{tmp}"]


def snapshot(tree: Path, out: Path, n: int, cache: Path) -> float:
    """Run ``tree``'s snapshot script into ``out``; the workflow's wall time [s]."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    script = tree / "scripts" / "tools" / "snapshot_discrepancy.py"
    if not script.exists():
        script = tree / "scripts" / "snapshot_discrepancy.py"
    cmd = [sys.executable, str(script), str(out),
           "--n", str(n), "--cache", str(cache)]  # fmt: skip
    subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL)
    return float(json.loads((out / "timing.json").read_text())["discrepancy_s"])


def same(a: Path, b: Path) -> bool:
    """The two snapshots simulated the same batches and reached the same verdict."""
    ba, bb = (pd.read_parquet(p / "batches.parquet") for p in (a, b))
    va, vb = (json.loads((p / "verdict.json").read_text()) for p in (a, b))
    return ba.equals(bb) and va == vb


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old", type=Path, nargs="?", default=REPO)
    ap.add_argument("new", type=Path, nargs="?", default=REPO)
    ap.add_argument("--n", type=int, default=20, help="measured fibers of each check")
    ap.add_argument("--pairs", type=int, default=3, help="A B pairs")
    ap.add_argument("--cache", type=Path, default=Path(".fibersweep-cache"))
    ap.add_argument("--out", type=Path, default=Path("results/bench_discrepancy_ab"))
    args = ap.parse_args()
    ratios = []
    for k in range(args.pairs):
        ta = snapshot(args.old.resolve(), args.out / f"a{k}", args.n, args.cache)
        tb = snapshot(args.new.resolve(), args.out / f"b{k}", args.n, args.cache)
        ratios.append(tb / ta)
        print(f"pair {k}: old {ta:.1f} s, new {tb:.1f} s, new/old {tb / ta:.3f}", flush=True)
    identical = all(same(args.out / f"a{k}", args.out / f"b{k}") for k in range(args.pairs))
    print(f"median new/old {statistics.median(ratios):.3f} over {args.pairs} pairs "
          f"(min {min(ratios):.3f}, max {max(ratios):.3f}); identical batches and "
          f"verdicts: {identical}")  # fmt: skip


if __name__ == "__main__":
    main()
