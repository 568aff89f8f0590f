#!/usr/bin/env python3
"""CPU time of fiber runs on a memory-mapped cached field against the same field in memory.

Since the discrepancy workflow's workers map the cached field (issue 31) instead of
receiving it pickled, this checks that a run costs the same on either: the same
starts, alternated batch by batch in one process, CPU time (not wall: the machine is
shared), ratio of the medians printed.

Usage:  python scripts/benchmarks/bench_field_mmap.py [--cache .fibersweep-cache] [--rounds 4]
"""

from __future__ import annotations

import argparse
import statistics
import time

from fibersweep.config.fiber import FiberSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.flow.cache import get_flow_field

#: Arguments of a run of seconds (scripts/benchmarks/run.py --smoke): the script runs
#: end to end, its numbers mean nothing.
SMOKE = ["--rounds", "1", "--cache", "{cache}"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--rounds", type=int, default=4)
    args = ap.parse_args()
    mapped, _ = get_flow_field(FlowSettings(dx=4.0), args.cache, mmap=True)
    loaded, _ = get_flow_field(FlowSettings(dx=4.0), args.cache, mmap=False)
    fiber = FiberSettings()
    starts = [FiberStart(t, y, 1.0) for t in (-8.0, 0.0, 8.0) for y in (0.2, 0.33, 0.4, 0.6)]
    for f in (mapped, loaded):  # compile, and touch every page once
        simulate(f, fiber, starts[0])
    times: dict[str, list[float]] = {"mapped": [], "in memory": []}
    for _ in range(args.rounds):
        for name, f in (("mapped", mapped), ("in memory", loaded)):
            c0 = time.process_time()
            for s in starts:
                simulate(f, fiber, s)
            times[name].append(time.process_time() - c0)
    for name, t in times.items():
        print(f"{name:>10}: CPU s per {len(starts)} runs {[round(x, 3) for x in t]}")
    ratio = statistics.median(times["mapped"]) / statistics.median(times["in memory"])
    print(f"ratio mapped / in memory (median CPU): {ratio:.3f}")


if __name__ == "__main__":
    main()
