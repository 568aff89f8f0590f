"""Cost of the ``near_wall`` effect: rigid runs with it on against off, in one process.

    python3 scripts/benchmarks/bench_near_wall.py [--cache DIR] [--rounds 5] [--repeat 5]

Cases: the channel's rigid fiber (dx = 4 µm, L = l_obs, 22 beads) passing without
contact and with contact at the pillar's apex; a sphere (one bead, a = 6 µm)
through 20 rows of the circle array of ``array_dc.py`` at ε = 0.1
(every pillar image within reach is visited). Numba is compiled before timing.
On and off alternate ``--rounds`` times (off, on, off, on, ...) so a loaded
machine slows both alike; each round takes the minimum of ``--repeat`` runs.
Times are the process's CPU time (the runs are single-threaded): on a machine
shared by many processes the wall time mostly measures the others.
Printed per case: the median over rounds of each, the ratio on/off of the run
time and of the time per step (the effect changes the path, hence the number
of steps), and the steps of each.
"""

from __future__ import annotations

import argparse
import statistics
import time

from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.fiber.settings import FiberSettings
from fibersweep.flow.cache import get_flow_field
from fibersweep.flow.settings import FlowSettings

# One round of one run per case, on the tests' cached fields (scripts/benchmarks/run.py --smoke).
SMOKE = ["--rounds", "1", "--repeat", "1", "--cache", "{cache}"]


def _cases(cache: str):
    """(label, field, settings without the effect, start) of each case."""
    channel, _ = get_flow_field(FlowSettings(dx=4.0), cache)
    cell, _ = get_flow_field(
        FlowSettings.model_validate({"dx": 2.0, "array": {"pillar_shape": "circle", "shift": 0.1}}),
        cache,
    )
    rigid = FiberSettings()
    sphere = FiberSettings(bead_radius=6.0, array_rows=20)
    return [
        ("channel, no contact (y0/h 0.8)", channel, rigid, FiberStart(0.0, 0.8, 1.0)),
        ("channel, contact at the apex (y0/h 0.45)", channel, rigid, FiberStart(0.0, 0.45, 1.0)),
        ("array eps 0.1, sphere a = 6 µm, 20 rows", cell, sphere, FiberStart(0.0, 0.37, 12.0)),
    ]


def _best(field, settings, start, repeat):
    """Minimum CPU time [s] of ``repeat`` runs and the run's steps."""
    best = float("inf")
    steps = 0
    for _ in range(repeat):
        t0 = time.process_time()
        res = simulate(field, settings, start)
        best = min(best, time.process_time() - t0)
        steps = res.n_steps
    return best, steps


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--value", type=float, default=1.0, help="near_wall k")
    args = ap.parse_args()
    print(f"near_wall = {args.value:g} on against off; {args.rounds} rounds alternating, "
          f"each the minimum of {args.repeat} runs; medians over rounds")  # fmt: skip
    for label, field, off, start in _cases(args.cache):
        on = off.model_copy(update={"effects": {"near_wall": args.value}})
        simulate(field, off, start)  # compile both
        simulate(field, on, start)
        times: dict[str, list[float]] = {"off": [], "on": []}
        steps: dict[str, int] = {}
        for _ in range(args.rounds):
            for name, st in (("off", off), ("on", on)):
                t, n = _best(field, st, start, args.repeat)
                times[name].append(t)
                steps[name] = n
        t_off = statistics.median(times["off"])
        t_on = statistics.median(times["on"])
        per = (t_on / steps["on"]) / (t_off / steps["off"])
        print(f"{label}\n  off {t_off * 1e3:8.2f} ms {steps['off']:6d} steps   "
              f"on {t_on * 1e3:8.2f} ms {steps['on']:6d} steps   "
              f"ratio per run {t_on / t_off:.3f}, per step {per:.3f}", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
