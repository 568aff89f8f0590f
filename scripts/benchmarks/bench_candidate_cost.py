"""Time of a flexible candidate's runs against rigid runs, measured in one run.

The discrepancy plan's estimate of a model-switch candidate
(``discrepancy.settings.MODEL_COST``): N starts uniform in the box of
configs/quick.yaml's sweep, one core, run rigid, then with the candidate at its
probe (``fiber.young_modulus=1e4..3e7``: E = 5.6e5 Pa, bead-spring with the
``--integrator``, ros2 by default), A B A B; prints the ratio.

    python3 scripts/benchmarks/bench_candidate_cost.py [--n 16] [--integrator ros2] [--cache DIR]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from fibersweep.config import load_config
from fibersweep.discrepancy.declared import parse_candidate
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.flow.cache import get_flow_field

#: a smoke pass (scripts/benchmarks/run.py --smoke): two starts on the tests' field cache
SMOKE = ["--n", "2", "--cache", "{cache}"]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=16)
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--integrator", default="ros2", help="bdf2, ros2 or ros34pw2")
    a = ap.parse_args()
    cfg = load_config("configs/quick.yaml")
    field, _ = get_flow_field(cfg.flow, a.cache)
    cand = parse_candidate(
        f"fiber.model=bead-spring,fiber.integrator={a.integrator},fiber.young_modulus=1e4..3e7",
        cfg.fiber,
        cfg.flow,
    )
    rng = np.random.default_rng(1)
    starts = np.column_stack([rng.uniform(-8, 8, a.n), rng.uniform(0.05, 0.9, a.n),
                              np.ones(a.n)])  # fmt: skip
    seeds = np.arange(a.n)
    times = {"rigid": [], a.integrator: []}
    with Simulator(field, cfg.fiber, workers=1, progress=False, candidates=[cand],
                   flow=cfg.flow) as sim:  # fmt: skip
        sim.run(starts[:2], {cand.name: cand.probes[0]}, seeds[:2])  # compile both
        sim.run(starts[:2], {}, seeds[:2])
        for _ in range(2):
            for name, eff in (("rigid", {}), (a.integrator, {cand.name: cand.probes[0]})):
                t0 = time.perf_counter()
                sim.run(starts, eff, seeds)
                times[name].append(time.perf_counter() - t0)
    r, f = sum(times["rigid"]), sum(times[a.integrator])
    print(f"{a.n} starts x 2 rounds: rigid {r:.1f} s, {a.integrator} (E = "
          f"{cand.setting(cand.probes[0]):.3g} Pa) {f:.1f} s, ratio {f / r:.2f}")


if __name__ == "__main__":
    main()
