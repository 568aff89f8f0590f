"""Cost of the explicit and the implicit step while a fiber is stopped on the pillar.

Runs the same fibers with ``fiber.step.stopped_implicit`` on (the default) and off,
interleaved in one process, and prints the ratio of the total times, for all
runs and for the trapping runs alone, with the step counts and whether every
run got the same class. The starts are uniform in a box: ``quick`` (θ0 in
[-8, 8]°, y0/h in [0.05, 0.9], L/l_obs in [0.75, 1.25]) or ``study``, the box
the discrepancy study draws its fibers from (θ0 in [-10, 10]°, y0/h in
[0.15, 0.65], L/l_obs in [0.5, 1.4]), where more fibers are trapped.
``--effects`` adds effects to both (e.g. ``friction=0.3``).

Usage::

    nice -n 5 python scripts/benchmarks/bench_stopped_step.py --n 80
    nice -n 5 python scripts/benchmarks/bench_stopped_step.py --n 80 --box study --effects \
        friction=0.5
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from fibersweep.config import load_config
from fibersweep.discrepancy.synth import STUDY_BOX
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.flow.cache import get_flow_field

#: Arguments of a run of seconds (scripts/benchmarks/run.py --smoke): the script runs
#: end to end, its numbers mean nothing.
SMOKE = ["--n", "2", "--cache", "{cache}"]

BOXES = {
    "quick": ((-8.0, 8.0), (0.05, 0.9), (0.75, 1.25)),
    "study": tuple(STUDY_BOX[c] for c in ("theta0", "y0", "length")),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="configs/quick.yaml")
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--n", type=int, default=80)
    ap.add_argument("--box", choices=list(BOXES), default="quick")
    ap.add_argument("--effects", nargs="*", default=[], help="name=value ...")
    args = ap.parse_args()
    cfg = load_config(args.config)
    field, _ = get_flow_field(cfg.flow, args.cache)
    effects = {k: float(v) for k, v in (e.split("=") for e in args.effects)}
    imp = cfg.fiber.model_copy(update={"effects": effects})
    exp = imp.model_copy(update={"step": imp.step.model_copy(update={"stopped_implicit": False})})
    rng = np.random.default_rng(0)
    starts = np.column_stack([rng.uniform(*r, args.n) for r in BOXES[args.box]])
    for st in (imp, exp):
        simulate(field, st, FiberStart(0.0, 0.3, 1.0))  # compile
    wall = {"implicit": [], "explicit": []}
    steps = {"implicit": [], "explicit": []}
    classes = {"implicit": [], "explicit": []}
    for s in starts:
        start = FiberStart(*map(float, s))
        for name, settings in (("implicit", imp), ("explicit", exp)):
            t0 = time.perf_counter()
            res = simulate(field, settings, start)
            wall[name].append(time.perf_counter() - t0)
            steps[name].append(res.n_steps)
            classes[name].append(res.cls)
    trap = np.array([c == "Trapping" for c in classes["explicit"]])
    w = {k: np.array(v) for k, v in wall.items()}
    n = {k: np.array(v) for k, v in steps.items()}
    same = sum(a == b for a, b in zip(classes["implicit"], classes["explicit"], strict=True))
    print(f"{args.n} runs in the {args.box} box, effects {effects or 'none'}; "
          f"{trap.sum()} trapping (explicit)")  # fmt: skip
    print(f"same class: {same} of {args.n}")
    for label, m in (("all runs", np.ones_like(trap)), ("trapping runs", trap)):
        if not m.any():
            continue
        te, ti = w["explicit"][m].sum(), w["implicit"][m].sum()
        print(f"{label:14s}: explicit {te:7.2f} s ({n['explicit'][m].sum():9d} steps), "
              f"implicit {ti:7.2f} s ({n['implicit'][m].sum():9d} steps), "
              f"explicit / implicit = {te / ti:.2f}")  # fmt: skip
    share = w["explicit"][trap].sum() / w["explicit"].sum()
    share_i = w["implicit"][trap].sum() / w["implicit"].sum()
    print(f"trapping share of the time: explicit {share:.0%}, implicit {share_i:.0%}")


if __name__ == "__main__":
    main()
