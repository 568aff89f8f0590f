"""Cost of the ``near_wall`` effect: rigid runs with it on against off, in one process.

    python3 scripts/benchmarks/bench_near_wall.py [--cache DIR] [--rounds 5] [--repeat 5] [--sweep]

Cases: the channel's rigid fiber (dx = 4 µm, L = l_obs, 22 beads) passing without
contact and with contact at the pillar's apex; a sphere (one bead, a = 6 µm)
through 20 rows of the circle array of ``array_dc.py`` at ε = 0.1
(every pillar image within reach is visited); and with ``--sweep``, the 50 starts of
``configs/quick.yaml`` (the separatrix region) summed, each run once per round.
Numba is compiled before timing.
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

from fibersweep.config.fiber import FiberSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.flow.cache import get_flow_field

# One round of one run per case, on the tests' cached fields (scripts/benchmarks/run.py --smoke).
SMOKE = ["--rounds", "1", "--repeat", "1", "--cache", "{cache}", "--sweep", "--sweep-points", "4"]


def cases(cache: str):
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


def _sweep_case(cache: str, points: int):
    """The quick config's field, fiber settings and (the first ``points`` of) its starts."""
    from pathlib import Path

    from fibersweep.config.loading import load_config
    from fibersweep.sweep.draws import start_points

    cfg = load_config(Path(__file__).resolve().parents[2] / "configs" / "quick.yaml")
    field, _ = get_flow_field(cfg.flow, cache)
    t, y, L = start_points(cfg)
    starts = [FiberStart(float(a), float(b), float(c)) for a, b, c in zip(t, y, L, strict=True)]
    return field, cfg.fiber, starts[:points]


def _sweep_time(field, settings, starts):
    """Summed CPU time [s] and steps of one run per start."""
    total = 0.0
    steps = 0
    for start in starts:
        t0 = time.process_time()
        res = simulate(field, settings, start)
        total += time.process_time() - t0
        steps += res.n_steps
    return total, steps


def best(field, settings, start, repeat):
    """Minimum CPU time [s] of ``repeat`` runs and the run's steps."""
    best = float("inf")
    steps = 0
    for _ in range(repeat):
        t0 = time.process_time()
        res = simulate(field, settings, start)
        best = min(best, time.process_time() - t0)
        steps = res.n_steps
    return best, steps


def compare(label, field, off, on, start, rounds, repeat) -> None:
    """Print one case's medians of ``off`` and ``on`` settings, alternated ``rounds`` times."""
    simulate(field, off, start)  # compile both
    simulate(field, on, start)
    times: dict[str, list[float]] = {"off": [], "on": []}
    steps: dict[str, int] = {}
    for _ in range(rounds):
        for name, st in (("off", off), ("on", on)):
            t, n = best(field, st, start, repeat)
            times[name].append(t)
            steps[name] = n
    t_off = statistics.median(times["off"])
    t_on = statistics.median(times["on"])
    per = (t_on / steps["on"]) / (t_off / steps["off"])
    print(f"{label}\n  off {t_off * 1e3:8.2f} ms {steps['off']:6d} steps   "
          f"on {t_on * 1e3:8.2f} ms {steps['on']:6d} steps   "
          f"ratio per run {t_on / t_off:.3f}, per step {per:.3f}", flush=True)  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--value", type=float, default=1.0, help="near_wall k")
    ap.add_argument("--sweep", action="store_true", help="also the quick config's sweep")
    ap.add_argument("--sweep-points", type=int, default=50, help="starts of the sweep case")
    args = ap.parse_args()
    print(f"near_wall = {args.value:g} on against off; {args.rounds} rounds alternating, "
          f"each the minimum of {args.repeat} runs; medians over rounds")  # fmt: skip
    steps: dict[str, int] = {}
    for label, field, off, start in cases(args.cache):
        on = off.model_copy(update={"effects": {"near_wall": args.value}})
        compare(label, field, off, on, start, args.rounds, args.repeat)
    if args.sweep:
        field, off, starts = _sweep_case(args.cache, args.sweep_points)
        on = off.model_copy(update={"effects": {**off.effects, "near_wall": args.value}})
        totals: dict[str, list[float]] = {"off": [], "on": []}
        for _ in range(args.rounds):
            for name, st in (("off", off), ("on", on)):
                t, n = _sweep_time(field, st, starts)
                totals[name].append(t)
                steps[name] = n
        t_off = statistics.median(totals["off"])
        t_on = statistics.median(totals["on"])
        print(f"configs/quick.yaml, {len(starts)} runs summed\n"
              f"  off {t_off:8.2f} s  {steps['off']:7d} steps   on {t_on:8.2f} s  "
              f"{steps['on']:7d} steps   ratio {t_on / t_off:.3f}", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
