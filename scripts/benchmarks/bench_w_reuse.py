"""Reusing W = M J over steps, and a PI step controller, in the adaptive bead-spring model.

Usage: python scripts/benchmarks/bench_w_reuse.py [--moduli 26e6] [--lengths 1.0] [--tolerances \
    1e-4 1e-6]

For each (E, L) of the grid, from θ0 = 0, y0/h = 0.45 at dx = 4 µm, runs
``bead-spring-ros2`` with ``fiber.step.rosenbrock`` ros2 and ros34pw2, every
``fiber.step.jacobian_reuse`` of REUSES and both ``fiber.step.controller``s, at each
tolerance; prints the best of two wall times, the accepted steps, δ, and per method
and tolerance the wall-time ratio to the default (a fresh W every step, integral
controller), measured in the same run after the kernels are compiled.
"""

from __future__ import annotations

import argparse
import time

from fibersweep.config.fiber import FiberSettings, StepSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.flow.cache import get_flow_field

#: Arguments of a run of seconds (scripts/benchmarks/run.py --smoke): the script runs
#: end to end, its numbers mean nothing.
SMOKE = ["--lengths", "0.5", "--tolerances", "1e-2", "--cache", "{cache}"]

REUSES = (1, 3, 10, 30)
"""Values of ``fiber.step.jacobian_reuse`` timed (1: the default)."""


def _best(field, st, start, repeat=2):
    best, r = float("inf"), None
    for _ in range(repeat):
        t0 = time.perf_counter()
        r = simulate(field, st, start)
        best = min(best, time.perf_counter() - t0)
    return best, r


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, default=4.0)
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--moduli", type=float, nargs="+", default=[26e6])
    ap.add_argument("--lengths", type=float, nargs="+", default=[1.0])
    ap.add_argument("--tolerances", type=float, nargs="+", default=[1e-4, 1e-6])
    args = ap.parse_args()
    field, _ = get_flow_field(FlowSettings(dx=args.dx), args.cache)
    warm = FiberStart(0.0, 0.8, 0.5)
    simulate(field, FiberSettings(model="bead-spring-ros2", step=StepSettings(
        rosenbrock="ros34pw2", jacobian_reuse=3, controller="pi")), warm)  # fmt: skip
    for E in args.moduli:
        for L in args.lengths:
            start = FiberStart(0.0, 0.45, L)
            print(f"E = {E / 1e6:g} MPa, L/l = {L:g}")
            for tol in args.tolerances:
                for method in ("ros2", "ros34pw2"):
                    base = None
                    for reuse in REUSES:
                        for ctl in ("i", "pi"):
                            step = StepSettings(rosenbrock=method, tolerance=tol,
                                                jacobian_reuse=reuse, controller=ctl)  # fmt: skip
                            st = FiberSettings(model="bead-spring-ros2", young_modulus=E,
                                               step=step)  # fmt: skip
                            wall, r = _best(field, st, start)
                            base = base or wall
                            print(f"  {method:8s} tol {tol:g} reuse {reuse:3d} {ctl:2s} "
                                  f"{wall:7.3f} s  x{base / wall:5.2f}  steps {r.n_steps:6d}  "
                                  f"delta {r.delta:+.7f}", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
