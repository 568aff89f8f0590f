#!/usr/bin/env python3
"""Sweep throughput, measured in one run so the numbers compare (the machine is shared).

Reports, for the same tasks on the same cached flow field:
  * local pool, 1 worker and 2 workers: runs/s in steady state and the 1 -> 2 speed-up;
  * Dask LocalCluster, 2 workers: runs/s and its overhead per run against the local pool;
  * start-up cost (spawn + open the field + Numba warm-up) of each executor;
  * an estimate of configs/paper.yaml (flow field excluded) from the measured per-run
    times of a random sample of the paper's own sweep points.

Usage:  python scripts/bench_sweep.py [--config configs/quick.yaml] [--paper-sample 60]
"""

from __future__ import annotations

import argparse
import logging
import os
import random
import statistics
import time
from dataclasses import replace
from pathlib import Path

from fibersweep.config import load_config
from fibersweep.sweep.executors import make_executor
from fibersweep.sweep.plan import make_tasks
from fibersweep.sweep.runner import flow_field_for
from fibersweep.sweep.worker import WorkerSpec, init_worker, run_task

log = logging.getLogger("bench_sweep")


def measure(name: str, workers: int, tasks, spec) -> dict:
    """Run ``tasks``; steady throughput is measured from the first to the last result."""
    ex = make_executor(name, workers)
    t0 = time.perf_counter()
    stamps, run_s, cpu_s = [], [], []
    for oc in ex.run(run_task, tasks, init_worker, (spec, name == "local")):
        stamps.append(time.perf_counter())
        row = oc.value["row"] if oc.value else {}
        run_s.append(float(row.get("wall_time") or 0.0))
        cpu_s.append(float(row.get("cpu_time") or 0.0))
        if oc.error or row.get("status") != "ok":
            log.warning("%s: %s", oc.key, oc.error or row.get("reason"))
    total = time.perf_counter() - t0
    steady = (len(stamps) - 1) / (stamps[-1] - stamps[0]) if len(stamps) > 1 else float("nan")
    return {
        "name": f"{name} x{workers}",
        "workers": workers,
        "n": len(stamps),
        "total_s": total,
        "startup_s": stamps[0] - t0 - run_s[0],
        "steady_rps": steady,
        "mean_run_s": statistics.fmean(run_s),
        "mean_cpu_s": statistics.fmean(cpu_s),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="configs/quick.yaml")
    ap.add_argument("--paper", default="configs/paper.yaml")
    ap.add_argument("--repeat", type=int, default=2, help="copies of the sweep's tasks")
    ap.add_argument("--paper-sample", type=int, default=60)
    ap.add_argument("--skip-dask", action="store_true")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)

    cfg = load_config(args.config)
    field, info = flow_field_for(cfg)
    spec = WorkerSpec(
        flow_json=cfg.flow.model_dump_json(),
        field_path=str(Path(info.path).resolve()),
        flow_key=info.key,
        fiber_json=cfg.fiber.model_dump_json(),
    )
    base = make_tasks(cfg, info.key)
    # Copies with distinct keys (Dask keys must be unique); same physics.
    tasks = [replace(t, key=f"{t.key}-{k}") for k in range(args.repeat) for t in base]
    print(f"{args.config}: {len(tasks)} runs per executor, field dx = {cfg.flow.dx} µm")

    results = [measure("local", 1, tasks, spec), measure("local", 2, tasks, spec)]
    if not args.skip_dask:
        results.append(measure("dask", 2, tasks, spec))
    print(f"load average before: {os.getloadavg()[0]:.2f} (2 cores; > 2 means a shared machine)")
    print(
        f"{'executor':<10}{'runs':>6}{'total s':>10}{'start-up s':>12}{'runs/s':>9}"
        f"{'wall/run':>10}{'cpu/run':>9}{'cpu use':>9}"
    )
    for r in results:
        # cpu use: fraction of each worker's time spent computing runs (1.0 = a free core each)
        use = r["steady_rps"] * r["mean_cpu_s"] / r["workers"]
        print(
            f"{r['name']:<10}{r['n']:>6}{r['total_s']:>10.2f}{r['startup_s']:>12.2f}"
            f"{r['steady_rps']:>9.2f}{r['mean_run_s']:>10.3f}{r['mean_cpu_s']:>9.3f}{use:>9.2f}"
        )
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    l1, l2 = results[0], results[1]
    print(
        f"scaling 1 -> 2 workers (steady runs/s ratio): {l2['steady_rps'] / l1['steady_rps']:.2f}"
    )
    if not args.skip_dask:
        d = results[2]
        per_run_local = 1.0 / l2["steady_rps"]
        per_run_dask = 1.0 / d["steady_rps"]
        print(
            "Dask overhead per run vs local pool (2 workers, steady state): "
            f"{100 * (per_run_dask - per_run_local) / per_run_local:+.1f} % "
            f"({1e3 * (per_run_dask - per_run_local):+.1f} ms per run)"
        )

    # configs/paper.yaml: time a random sample of its own points with 2 workers.
    paper = load_config(args.paper)
    starts = paper.sweep.starts()
    rng = random.Random(0)
    sample = rng.sample(make_tasks(paper, info.key), min(args.paper_sample, len(starts)))
    pspec = replace(spec, fiber_json=paper.fiber.model_dump_json())
    p = measure("local", 2, sample, pspec)
    est = len(starts) / p["steady_rps"]
    ideal = len(starts) * p["mean_cpu_s"] / 2.0
    print(
        f"{args.paper}: {len(starts)} runs; sample of {p['n']} at dx = {cfg.flow.dx} µm: "
        f"{p['mean_run_s']:.3f} s wall, {p['mean_cpu_s']:.3f} s CPU per run, "
        f"{p['steady_rps']:.2f} runs/s on 2 workers -> estimate {est / 60:.1f} min here, "
        f"{ideal / 60:.1f} min on 2 free cores (+ {p['startup_s']:.0f} s start-up), field excluded"
    )
    if paper.flow.dx != cfg.flow.dx:
        print(
            f"  (measured on the dx = {cfg.flow.dx} µm field; paper.yaml uses dx = "
            f"{paper.flow.dx} µm: the per-step cost of a rigid fiber does not depend on dx)"
        )


if __name__ == "__main__":
    main()
