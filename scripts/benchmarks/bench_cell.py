"""The array's unit-cell flow solve: this tree against another checkout, in one run.

Each solve runs in its own subprocess with ``PYTHONPATH`` set to its tree,
alternating old, new, old, new, ...; the kernels are compiled (or loaded from
Numba's cache) beforehand in the same process on a coarse cell, and only the
solve of the cell is timed. The cell is that of configs/array.yaml (triangle
40 µm, 80 µm periods, ε = 0.1, 40 µm deep, the mean flow held along x: two
solves) at ``--dx``. Printed: each time, the ratio old/new of each pair and
their median.

``--threads N`` runs both with N Numba threads (the same footing: the stepper
against the stepper); by default each tree uses the threads it would choose.
``--pull`` times this tree's pull stepper as "old" (the AA stepper against the
pull stepper, everything else equal) instead of another checkout.

    python3 scripts/benchmarks/bench_cell.py (--old OLD_CHECKOUT | --pull) [--dx 2] [--pairs 3]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ARRAY = {"pillar_shape": "triangle", "pillar_size": 40.0, "period_x": 80.0, "period_y": 80.0,
         "shift": 0.1, "depth": 40.0}  # fmt: skip
#: a smoke pass (scripts/benchmarks/run.py --smoke): this tree's pull stepper against its AA
#: stepper on a coarse cell, one pair
SMOKE = ["--pull", "--dx", "4", "--pairs", "1"]


def child(dx: float, kernel: str) -> None:
    """Solve the cell in this process's tree (new API: with ``kernel``); print one JSON line."""
    import numba

    from fibersweep.config.flow import FlowSettings
    from fibersweep.flow import cell

    coarse = FlowSettings.model_validate({"dx": 4.0, "tolerance": 1e-3, "array": ARRAY})
    settings = FlowSettings.model_validate({"dx": dx, "array": ARRAY})
    if hasattr(cell, "cell_solution"):  # one solver for channel and cell
        cell.solve_cell(coarse, kernel=kernel)
        t0 = time.perf_counter()
        sol = cell.solve_cell(settings, kernel=kernel)
    else:  # the cell's own solver: (array, dx, options)
        array = settings.array.to_array()
        cell.solve_cell(array, 4.0, tolerance=1e-3)
        t0 = time.perf_counter()
        sol = cell.solve_cell(array, dx)
    seconds = time.perf_counter() - t0
    g = sol.grid
    reports = getattr(sol, "reports", ())  # the threads the time loop chose, if it reports them
    threads = max((r.threads for r in reports), default=numba.get_num_threads())
    print(json.dumps({"seconds": seconds, "steps": sol.steps, "cells": g.nx * g.ny * g.nz,
                      "threads": threads, "version": cell.CELL_SOLVER_VERSION}))  # fmt: skip


def run(tree: Path, dx: float, threads: int | None, kernel: str = "aa") -> dict:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    if threads:
        env["NUMBA_NUM_THREADS"] = str(threads)
    cmd = [sys.executable, __file__, "--child", "--dx", str(dx), "--kernel", kernel]
    out = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True).stdout
    result = json.loads(out.strip().splitlines()[-1])
    result["version"] += "" if kernel == "aa" else f" {kernel}"
    return result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", type=Path, help="checkout of the tree to compare against")
    ap.add_argument("--pull", action="store_true", help="old: this tree's pull stepper")
    ap.add_argument("--kernel", default="aa", help=argparse.SUPPRESS)
    ap.add_argument("--dx", type=float, default=2.0, help="lattice spacing [µm]")
    ap.add_argument("--pairs", type=int, default=3, help="old/new pairs")
    ap.add_argument("--threads", type=int, help="Numba threads of both (default: their own)")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args.dx, args.kernel)
        return
    if (args.old is None) == (not args.pull):
        ap.error("give one of --old PATH and --pull")
    new = Path(__file__).resolve().parents[2]
    print(f"cell of configs/array.yaml at dx = {args.dx} µm; {os.cpu_count()} cpus; threads "
          f"{args.threads or 'each tree its own'}")  # fmt: skip
    ratios = []
    for k in range(args.pairs):
        if args.pull:
            a = run(new, args.dx, args.threads, kernel="pull")
        else:
            a = run(args.old.resolve(), args.dx, args.threads)
        b = run(new, args.dx, args.threads)
        ratios.append(a["seconds"] / b["seconds"])
        for name, r in (("old", a), ("new", b)):
            mlups = r["cells"] * r["steps"] / r["seconds"] / 1e6
            print(f"  pair {k + 1} {name} ({r['version']}, {r['threads']} threads): "
                  f"{r['seconds']:.2f} s, {r['steps']} steps, {mlups:.1f} MLUPS")  # fmt: skip
        print(f"  pair {k + 1}: old/new = {ratios[-1]:.2f}")
    print(f"old/new time ratio: median {statistics.median(ratios):.2f} "
          f"(pairs: {', '.join(f'{r:.2f}' for r in ratios)})")  # fmt: skip


if __name__ == "__main__":
    main()
