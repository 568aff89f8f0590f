"""Cost of keeping the trajectory in every discrepancy run (the track observables need it).

Runs the same fibers (starts uniform in the quick config's box) with
``record.trajectories`` off and on (``TRACK_SAMPLES`` samples) plus the track
derivation, interleaved, and prints the ratio of the total times measured in
this one run.

Usage::

    nice -n 5 python scripts/benchmarks/bench_track_record.py --n 40
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from fibersweep.config import load_config
from fibersweep.discrepancy.simulate import TRACK_SAMPLES, outcome_row
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.flow.cache import get_flow_field

#: Arguments of a run of seconds (scripts/benchmarks/run.py --smoke): the script runs
#: end to end, its numbers mean nothing.
SMOKE = ["--n", "2", "--cache", "{cache}"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="configs/quick.yaml")
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--n", type=int, default=40)
    args = ap.parse_args()
    cfg = load_config(args.config)
    field, _ = get_flow_field(cfg.flow, args.cache)
    off = cfg.fiber.model_copy(
        update={"record": cfg.fiber.record.model_copy(update={"trajectories": False})}
    )
    on = cfg.fiber.model_copy(
        update={"record": cfg.fiber.record.model_copy(
            update={"trajectories": True, "samples": TRACK_SAMPLES})}
    )  # fmt: skip
    rng = np.random.default_rng(0)
    starts = np.column_stack(
        [rng.uniform(-8, 8, args.n), rng.uniform(0.05, 0.9, args.n), np.ones(args.n)]
    )
    simulate(field, off, FiberStart(0.0, 0.3, 1.0))  # compile
    total = {"off": 0.0, "on": 0.0}
    for s in starts:
        st = FiberStart(*map(float, s))
        for name, settings in (("off", off), ("on", on)):
            t0 = time.perf_counter()
            outcome_row(simulate(field, settings, st, rng_seed=1), field.geometry)
            total[name] += time.perf_counter() - t0
    print(f"{args.n} runs: without trajectory {total['off']:.2f} s, with trajectory and track "
          f"observables {total['on']:.2f} s, ratio {total['on'] / total['off']:.3f}")  # fmt: skip


if __name__ == "__main__":
    main()
