#!/usr/bin/env python3
"""Discrepancy on N measured array fibers with 3 candidates against a plain sweep of its runs.

Synthesises ``--n`` rigid fibers through ``--rows`` rows of ``configs/array.yaml``
(at ``--dx``) with ``--effect`` hidden (default friction=0.5), then times

- ``discrepancy``: the whole workflow (default plan unless ``--copies``), with three
  candidates: the library effects friction and pillar_hydro and the fabrication
  alternative ``flow.array.shift=--shift`` (its unit-cell field solved or read from
  the cache before the clock starts, as the plan's line says);
- ``sweep``: the same number of runs as the workflow made, at the measured starts
  repeated, through the same executor and workers, without any effect: what
  simulating those fibers costs with no analysis around it.

Prints both times, the runs, and the ratio discrepancy / sweep (the analysis'
overhead on top of its simulations; above 1 also because an effect's runs can cost
more than the baseline's). The issue's target: 200 fibers, three candidates,
under 15 minutes on two quiet cores.

Usage:  python scripts/benchmarks/bench_discrepancy_array.py [--n 200] [--rows 20]
            [--dx 2] [--workers 2] [--cache DIR] [--copies K] [--seed S]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]

#: a smoke pass (scripts/benchmarks/run.py --smoke): 10 fibers, 2 rows, coarse grid
SMOKE = ["--n", "8", "--rows", "2", "--dx", "4", "--shift", "0.15", "--copies", "2",
         "--workers", "1", "--cache", "{cache}"]  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200, help="measured fibers")
    ap.add_argument("--rows", type=int, default=20, help="rows each fiber crosses")
    ap.add_argument("--dx", type=float, default=2.0, help="lattice spacing [µm]")
    ap.add_argument(
        "--shift",
        type=float,
        default=0.125,
        help="the shift alternative (a whole number of dx per row)",
    )
    ap.add_argument("--effect", default="friction=0.5", help="hidden effect NAME=VALUE")
    ap.add_argument("--copies", type=int, default=None, help="baseline copies [default plan]")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--cache", type=Path, default=REPO / ".fibersweep-cache")
    args = ap.parse_args(argv)

    from fibersweep.api.compare import declared_candidates, sweep_box
    from fibersweep.config import load_config
    from fibersweep.discrepancy.array_schema import array_measured_data
    from fibersweep.discrepancy.array_synth import synthesize_array
    from fibersweep.discrepancy.array_workflow import array_effect_names, field_plan
    from fibersweep.discrepancy.copies import array_noise
    from fibersweep.discrepancy.simulate import Simulator
    from fibersweep.discrepancy.synth import parse_effects
    from fibersweep.discrepancy.workflow import DiscrepancySettings, run_discrepancy
    from fibersweep.flow.cache import get_flow_field

    cfg = load_config(REPO / "configs" / "array.yaml",
                      [f"flow.dx={args.dx:g}", f"fiber.array_rows={args.rows}"])  # fmt: skip
    field, _ = get_flow_field(cfg.flow, args.cache)
    declared = declared_candidates(cfg, [f"flow.array.shift={args.shift:g}"])
    for line in field_plan(declared, cfg.fiber, cfg.flow, args.cache, field.meta):
        print(line.strip())
    shifted = load_config(REPO / "configs" / "array.yaml",
                          [f"flow.dx={args.dx:g}", f"flow.array.shift={args.shift:g}"])  # fmt: skip
    get_flow_field(shifted.flow, args.cache)  # solved here, not inside the timed workflow
    table, _ = synthesize_array(field, cfg.fiber, sweep_box(cfg), args.n,
                                parse_effects([args.effect]), seed=args.seed,
                                workers=args.workers, progress=False)  # fmt: skip
    data = array_measured_data(table)
    plan = {} if args.copies is None else {"copies": args.copies}
    s = DiscrepancySettings(seed=args.seed, workers=args.workers, noise=array_noise(cfg.fiber),
                            effects=array_effect_names(("friction", "pillar_hydro"), cfg.fiber),
                            declared=declared, **plan)  # fmt: skip
    t0 = time.perf_counter()
    res = run_discrepancy(data, field, cfg.fiber, s, progress=False, flow=cfg.flow,
                          cache_dir=args.cache)  # fmt: skip
    t_disc = time.perf_counter() - t0
    runs = res.simulations
    starts = np.resize(data.starts, (runs, 3))  # the measured starts, repeated to as many runs
    t0 = time.perf_counter()
    with Simulator(field, cfg.fiber, workers=args.workers, progress=False) as sim:
        sim.run(starts, None, np.arange(runs), desc="sweep")
    t_sweep = time.perf_counter() - t0
    print(f"fibers {len(data)} (of {args.n}), rows {args.rows}, dx {args.dx:g} µm, "
          f"workers {args.workers}")  # fmt: skip
    print(f"verdict: {res.verdict.kind}: {res.verdict.text}")
    print(f"discrepancy: {t_disc:.1f} s for {runs} runs ({res.failed_runs} failed); runs by "
          f"stage {res.extra.get('runs_by_stage')}")  # fmt: skip
    print(f"plain sweep of {runs} runs: {t_sweep:.1f} s")
    print(f"ratio discrepancy / sweep: {t_disc / t_sweep:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
