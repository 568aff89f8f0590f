"""Speed of the pillar-array pieces against the issue's targets (prints ratios).

1. Unit-cell field at dx = 2 µm (100 µm periods, 40 µm deep, triangle 50 µm, ε = 0.1):
   target under 60 s on 2 cores (Numba compiled beforehand on a coarse cell);
   scripts/bench_cell.py times it against another checkout.
2. One rigid fiber (L = 80 µm) through 50 rows: target under 2 s (compiled beforehand).
3. A sweep of --starts starts over 10 lengths on 2 workers, rows 20, field included
   (``fibersweep run`` with ``flow.array`` and ``sweep.random``), extrapolated to 1000
   starts from the runs' own wall times: target under 600 s.

    python3 scripts/bench_array.py [--starts 40]
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import tempfile
import time

import numba
import numpy as np

from fibersweep.config import parse_config
from fibersweep.fiber.array_run import array_run_kernel, n_beads_of, start_clear, start_x
from fibersweep.fiber.rows import array_pillar, run_array_fiber
from fibersweep.flow.cell import field_of, solve_cell
from fibersweep.sweep.runner import run_sweep
from fibersweep.sweep.store import read_runs

ARRAY = {"pillar_size": 50.0, "period_x": 100.0, "period_y": 100.0, "shift": 0.1, "depth": 40.0}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--starts", type=int, default=40, help="starts of the reduced sweep")
    args = ap.parse_args()
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cpus, "
          f"numba threads {numba.get_num_threads()}")  # fmt: skip
    cfg = parse_config({
        "flow": {"dx": 2.0, "array": ARRAY}, "fiber": {"array_rows": 50},
        "sweep": {"length": [80.0], "theta0": [-10.0, 10.0], "y0": [0.0, 1.0],
                  "random": {"count": 1}},
    })  # fmt: skip
    arr = cfg.flow.array.to_array()
    solve_cell(cfg.flow.model_copy(update={"dx": 5.0, "tolerance": 1e-3}))  # compile the kernels
    t0 = time.perf_counter()
    sol = solve_cell(cfg.flow)
    t_field = time.perf_counter() - t0
    g = sol.grid
    print(f"1. unit cell {g.nx}x{g.ny}x{g.nz} (half depth), {sol.steps} steps (both solves), "
          f"{t_field:.1f} s -> {t_field / 60.0:.2f} of the 60 s target")  # fmt: skip
    field = field_of(cfg.flow, sol)
    x0 = start_x(arr)
    warm = array_run_kernel(field, cfg.fiber, 80.0, x_end=x0 + 100.0)
    run_array_fiber(warm, "rigid", x0, 0.0, 0.0)  # compile
    k = array_run_kernel(field, cfg.fiber, 80.0)  # 50 rows (fiber.array_rows)
    times = []
    pillar = array_pillar(arr, cfg.fiber, field.viscosity, field.u_center)
    n = n_beads_of(80.0, 2.0)
    clear = [y for y in np.linspace(0.0, arr.period_y, 41)[:-1]
             if start_clear(arr, pillar, n, 2.0, y / arr.period_y, 3.0)]  # fmt: skip
    for y0 in [clear[int(i)] for i in np.linspace(0, len(clear) - 1, 5)]:  # 5 clear starts
        t0 = time.perf_counter()
        rec, code = run_array_fiber(k, "rigid", x0, y0, math.radians(3.0))
        times.append(time.perf_counter() - t0)
        print(f"   y0 = {y0:4.0f} µm: {rec.shape[0]} steps, code {code}, {times[-1]:.2f} s")
    worst = max(times)
    print(f"2. 50 rows, L = 80 µm: worst {worst:.2f} s, mean {sum(times) / len(times):.2f} s "
          f"-> {worst / 2.0:.2f} of the 2 s target")  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        lengths = [8.0 * k for k in range(1, 11)]
        per = max(1, args.starts // 10)
        sweep = parse_config({
            "flow": {"dx": 2.0, "array": ARRAY},
            "sweep": {"length": lengths, "theta0": [-10.0, 10.0], "y0": [0.0, 1.0],
                      "random": {"count": per, "seed": 0}},
            "run": {"output": tmp, "cache_dir": tmp, "workers": 2},
        })  # fmt: skip
        t0 = time.perf_counter()
        summary = run_sweep(sweep)
        t_sweep = time.perf_counter() - t0
        runs = read_runs(tmp)
    n = summary.ran
    # the sweep's own field solve is inside t_sweep: extrapolate from the runs' wall times
    per_run = float(runs["wall_time"].sum()) / n
    est = t_field + per_run * 1000.0 / 2.0
    print(
        f"3. {n} starts over 10 lengths, 2 workers, field included: {t_sweep:.1f} s "
        f"(runs {per_run:.2f} s each in their worker); 1000 starts extrapolated: field "
        f"{t_field:.0f} s + 1000 x {per_run:.2f} s / 2 workers = {est:.0f} s -> "
        f"{est / 600.0:.2f} of the 600 s target"
    )

if __name__ == "__main__":
    main()
