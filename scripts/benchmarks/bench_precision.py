"""Population precision: AA-kernel rate and solver memory of float32 against float64 in one run.

Kernel rate: one AA stepper per precision on the same channel, the two timed in
alternating rounds (the machine may be shared: alternating spreads the load
over both), best and median round reported with their ratio. Memory: for each
precision a child process runs the fine level of a nested solve (started as the
solver starts it, from the prolonged coarse level, then two convergence checks)
and reports its peak resident memory above the state before that level (Linux:
the peak is reset through /proc/self/clear_refs). Then the full channel at
dx = 1 µm is extrapolated from the measured rates and bytes per cell: an
extrapolation, not a measurement.

Usage: python scripts/benchmarks/bench_precision.py [--dx 2] [--steps 200] [--threads 2]
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

import numba
import numpy as np

from fibersweep.config.flow import FlowSettings
from fibersweep.flow.cuts import pillar_cuts
from fibersweep.flow.initial import duct_guess, velocity_gradient
from fibersweep.flow.lbm import coarser_settings, lattice_of, solve_lattice
from fibersweep.flow.lbm import rates as solve_rates
from fibersweep.flow.prolong import prolong
from fibersweep.flow.steppers import make_stepper

#: Arguments of a run of seconds (scripts/benchmarks/run.py --smoke): the script runs
#: end to end, its numbers mean nothing.
SMOKE = ["--dx", "2", "--steps", "20", "--rounds", "1", "--width", "400", "--length", "800"]

PRECISIONS = ("float32", "float64")
FULL_DX1_CELLS = 2400 * 800 * 20  # full channel, dx = 1 µm, half depth
FULL_DX1_STEPS = (3300, 5200)  # fine-level steps of the dx = 1 µm small-channel solves
QUIET_FLOAT32_MLUPS = 114.7  # AA kernel, 2 threads, quiet machine (scripts/benchmarks/bench_lbm.py)
TARGET_S = 15 * 60


#: Channel size [µm] of the run (--width, --length; default: the full channel).
GEOMETRY: dict[str, float] = {}


def _settings(dx: float, boundary: str, precision: str, **kw) -> FlowSettings:
    return FlowSettings(
        dx=dx, pillar_boundary=boundary, precision=precision, geometry=GEOMETRY, **kw
    )


def _stepper(dx: float, boundary: str, precision: str):
    s = _settings(dx, boundary, precision)
    grid = lattice_of(s)
    cuts = pillar_cuts(grid, s.geometry.to_geometry().vertices, boundary)
    tau, wp, wm, fx = solve_rates(s, grid)
    u0 = duct_guess(grid, fx / ((tau - 0.5) / 3.0))
    rho0 = np.zeros(u0.shape[1:])
    st = make_stepper(
        "aa", grid, u0, rho0, velocity_gradient(u0, grid), fx, wp, wm, cuts=cuts, dtype=precision
    )
    return grid, st


def rates(dx: float, boundary: str, steps: int, rounds: int, threads: int) -> dict:
    """MLUPS of each precision per round, timed alternately on the same grid."""
    numba.set_num_threads(threads)
    steppers = {}
    for p in PRECISIONS:
        grid, st = _stepper(dx, boundary, p)
        st.advance(2)  # compile / warm up
        steppers[p] = st
    per = max(2, (steps // rounds) // 2 * 2)
    out: dict[str, list[float]] = {p: [] for p in PRECISIONS}
    for _ in range(rounds):
        for p in PRECISIONS:
            t0 = time.perf_counter()
            steppers[p].advance(per)
            out[p].append(grid.cells * per / (time.perf_counter() - t0) / 1e6)
    return {"cells": grid.cells, "steps_per_round": per, "mlups": out}


def _vm_kb(field: str) -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1])
    raise RuntimeError(f"{field} not in /proc/self/status")


def child_memory(dx: float, boundary: str, precision: str, threads: int) -> None:
    """(Child process) peak RSS of the fine level of a nested solve, printed as JSON.

    The fine level starts as in :func:`fibersweep.flow.lbm.solve_nested` (from the
    prolonged coarse solution, here an unconverged one: same arrays, no wait) and
    runs two convergence checks. The peak is counted from after the coarse level,
    whose solve also compiles every kernel of this precision.
    """
    numba.set_num_threads(threads)
    s = _settings(dx, boundary, precision, max_steps=200, check_every=100)
    cs = coarser_settings(s)
    if cs is None:
        raise SystemExit(f"dx = {dx:g} µm has no valid coarser grid: choose dx <= 2")
    coarse = solve_lattice(cs.model_copy(update={"max_steps": 2, "check_every": 2}))
    Path("/proc/self/clear_refs").write_text("5")  # reset the peak (VmHWM) to now
    base = _vm_kb("VmRSS")
    fine_grid = lattice_of(s)
    scale = solve_rates(s, fine_grid)[3] / coarse.report.force * (coarse.grid.dx / fine_grid.dx)
    start = list(prolong(coarse.u, coarse.rho, coarse.grid, fine_grid, scale))
    sol = solve_lattice(s, initial=start.pop(0), initial_rho=start.pop(0))
    peak = _vm_kb("VmHWM")
    print(json.dumps({"base_kb": base, "peak_kb": peak, "cells": sol.grid.cells}))


def memory(dx: float, boundary: str, threads: int) -> dict:
    """Peak bytes per cell of each precision, each in its own process."""
    out = {}
    for p in PRECISIONS:
        cmd = [sys.executable, __file__, "--child-memory", p, "--dx", str(dx)]
        cmd += ["--boundary", boundary, "--threads", str(threads)]
        cmd += [a for k, v in GEOMETRY.items() for a in (f"--{k}", str(v))]
        res = subprocess.run(cmd, capture_output=True, text=True, check=True)
        d = json.loads(res.stdout.strip().splitlines()[-1])
        d["bytes_per_cell"] = (d["peak_kb"] - d["base_kb"]) * 1024 / d["cells"]
        out[p] = d
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, default=2.0, help="lattice spacing of the full channel")
    ap.add_argument("--steps", type=int, default=200, help="steps per precision in all")
    ap.add_argument("--rounds", type=int, default=4, help="alternating timing rounds")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--boundary", default="interpolated", help="pillar_boundary")
    ap.add_argument("--width", type=float, default=None, help="channel width [µm] (default full)")
    ap.add_argument("--length", type=float, default=None, help="channel length [µm] (default full)")
    ap.add_argument("--child-memory", choices=PRECISIONS, help=argparse.SUPPRESS)
    args = ap.parse_args()
    threads = min(args.threads, numba.config.NUMBA_NUM_THREADS)
    GEOMETRY.update({k: v for k, v in (("width", args.width), ("length", args.length)) if v})
    if args.child_memory:
        child_memory(args.dx, args.boundary, args.child_memory, threads)
        return
    load0 = os.getloadavg()
    print(f"load average before: {load0[0]:.2f} {load0[1]:.2f} {load0[2]:.2f} "
          f"on {os.cpu_count()} cores; {threads} Numba threads")  # fmt: skip
    r = rates(args.dx, args.boundary, args.steps, args.rounds, threads)
    m = memory(args.dx, args.boundary, threads)
    load1 = os.getloadavg()
    print(
        f"channel {GEOMETRY or 'full'}, dx = {args.dx:g} µm ({args.boundary} pillar): "
        f"{r['cells'] / 1e6:.2f} M cells, {args.rounds} rounds x {r['steps_per_round']} "
        "steps per precision, alternating"
    )
    best, med = {}, {}
    for p in PRECISIONS:
        v = r["mlups"][p]
        best[p], med[p] = max(v), statistics.median(v)
        rounds = " ".join(f"{x:.1f}" for x in v)
        print(f"  {p}: best {best[p]:6.1f} MLUPS, median {med[p]:6.1f} (rounds: {rounds})")
    ratio_best = best["float32"] / best["float64"]
    ratio_med = med["float32"] / med["float64"]
    print(f"  rate ratio float32 / float64: {ratio_best:.2f} (best), {ratio_med:.2f} (median)")
    for p in PRECISIONS:
        d = m[p]
        print(
            f"  {p}: peak memory {d['bytes_per_cell']:.0f} B per cell above the warmed-up "
            f"state ({(d['peak_kb'] - d['base_kb']) / 2**20:.2f} GB; before it "
            f"{d['base_kb'] / 2**20:.2f} GB)"
        )
    print(f"load average after: {load1[0]:.2f} {load1[1]:.2f} {load1[2]:.2f}")
    cells, (s_lo, s_hi) = FULL_DX1_CELLS, FULL_DX1_STEPS
    print(
        f"EXTRAPOLATION (not measured) to the full channel at dx = 1 µm: {cells / 1e6:.1f} M "
        f"cells x {s_lo}-{s_hi} fine-level steps, fine level only:"
    )
    for p in PRECISIONS:
        gb = (m[p]["base_kb"] * 1024 + m[p]["bytes_per_cell"] * cells) / 2**30
        t_lo, t_hi = cells * s_lo / best[p] / 1e6 / 60, cells * s_hi / best[p] / 1e6 / 60
        print(f"  {p}: at this run's best rate {t_lo:.0f}-{t_hi:.0f} min, peak memory {gb:.1f} GB")
    q64 = QUIET_FLOAT32_MLUPS / ratio_best
    for p, rate in (("float32", QUIET_FLOAT32_MLUPS), ("float64", q64)):
        t_lo, t_hi = cells * s_lo / rate / 1e6 / 60, cells * s_hi / rate / 1e6 / 60
        print(f"  {p}: quiet machine ({rate:.1f} MLUPS) {t_lo:.1f}-{t_hi:.1f} min")
    need = cells * s_lo / TARGET_S / 1e6
    print(
        f"  15 min for {s_lo} steps needs {need:.0f} MLUPS on the fine level alone; the default "
        f"float32 storage gives {QUIET_FLOAT32_MLUPS} on a quiet machine: "
        + ("reachable" if QUIET_FLOAT32_MLUPS >= need else "NOT reachable by precision alone")
    )


if __name__ == "__main__":
    main()
