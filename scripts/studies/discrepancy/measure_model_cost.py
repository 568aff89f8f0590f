"""Time of a soft bead-spring run against a rigid run, across the stiffness range.

The discrepancy plan multiplies the runs of a candidate that switches the fiber
model by ``settings.MODEL_COST`` of its integrator. The benchmark behind that
figure (scripts/benchmarks/bench_candidate_cost.py) times one stiffness, the
candidate's probe; a fit of ``fiber.young_modulus=1e4..3e7`` evaluates softer
fibers too, whose runs take longer. This script times, on configs/quick.yaml's
field and sweep box (one worker, the same starts and seeds for every model),
rigid runs and bead-spring runs (``--integrator``, ros2 by default) at each
``--moduli`` value, rigid and flexible alternating over ``--rounds`` rounds, and
prints each stiffness's seconds per run and its ratio to rigid::

    python scripts/studies/discrepancy/measure_model_cost.py --n 8 --rounds 2 \\
        --moduli 1e4 3e4 1e5 3e5 1e6 3e6 3e7 --cache .fibersweep-cache
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.optimize import brentq

from fibersweep.config import load_config
from fibersweep.discrepancy.declared import parse_candidate
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.flow.cache import get_flow_field


def coordinate(cand, modulus: float) -> float:
    """The candidate's fitted coordinate of a Young's modulus [Pa] (``cand.setting``'s inverse)."""
    lo = cand.lo + 1e-9 * (cand.hi - cand.lo)  # the rigid scale is infinite at 0
    return float(brentq(lambda u: cand.setting(u) - modulus, lo, cand.hi))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=8, help="starts (runs per model and round)")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--moduli", type=float, nargs="+",
                    default=[1e4, 3e4, 1e5, 3e5, 1e6, 3e6, 3e7])  # fmt: skip
    ap.add_argument("--integrator", default="ros2", help="bdf2, ros2 or ros34pw2")
    ap.add_argument("--cache", default=".fibersweep-cache")
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
    models = {"rigid": {}} | {f"{e:.0e}": {cand.name: coordinate(cand, e)} for e in a.moduli}
    times = {m: 0.0 for m in models}
    with Simulator(field, cfg.fiber, workers=1, progress=False, candidates=[cand],
                   flow=cfg.flow) as sim:  # fmt: skip
        sim.run(starts[:1], models[f"{a.moduli[0]:.0e}"], seeds[:1])  # compile both models
        sim.run(starts[:1], {}, seeds[:1])
        for _ in range(a.rounds):
            for m, eff in models.items():
                # rigid between every stiffness: a change of the machine's load shows
                t0 = time.perf_counter()
                sim.run(starts, eff, seeds)
                times[m] += time.perf_counter() - t0
    runs = a.n * a.rounds
    rigid = times["rigid"] / runs
    print(f"{a.n} starts x {a.rounds} rounds, {a.integrator}; rigid {rigid:.3f} s per run")
    print("| E [Pa] | s per run | ratio to rigid |")
    print("|---|---|---|")
    for m in models:
        if m != "rigid":
            print(f"| {float(m):.0e} | {times[m] / runs:.3f} | {times[m] / runs / rigid:.2f} |")


if __name__ == "__main__":
    main()
