"""Time one fiber run (L = l_obs, start to far downstream) in both models; print the ratio.

Usage: python scripts/benchmarks/bench_fiber.py [--dx 4] [--cache .fibersweep-cache] [--repeat 5]

Timings on a shared machine are noisy, so the script reports the ratio of the
two models measured in the same process, after a warm-up that compiles the
Numba kernels (compilation is excluded; it is paid once per process), and for
the rigid model both the median and the minimum over ``--repeat`` runs (the
minimum is the steadier figure on a loaded machine). The rigid model is also
timed with the dynamic effects on (``--effects``), each set compiled before timing.

With ``--against TREE`` (a checkout of another version, e.g. the commit before a
change), it times the rigid runs (the starts below, and with each effect set)
in this tree and in TREE alternately, ``--rounds`` times each in fresh
processes (Numba compiled beforehand in each), so the machine's load hits both
alike, and prints the ratio this/other of the median over rounds of each
round's minimum run time.

Usage: python scripts/benchmarks/bench_fiber.py --against /tmp/before [--rounds 5] [--repeat 20]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

from fibersweep.config.fiber import FiberSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.flow.cache import get_flow_field

#: Arguments of a run of seconds (scripts/benchmarks/run.py --smoke): the script runs
#: end to end, its numbers mean nothing.
SMOKE = ["--repeat", "1", "--no-effects", "--cache", "{cache}"]

STARTS = {
    "no contact (theta0 = 0, y0/h = 0.8)": FiberStart(0.0, 0.8, 1.0),
    "contact at the apex (theta0 = 0, y0/h = 0.45)": FiberStart(0.0, 0.45, 1.0),
}


EFFECT_SETS = {
    "friction 0.3": {"friction": 0.3},
    "pillar_hydro 1": {"pillar_hydro": 1.0},
    "off_midplane 0.2": {"off_midplane": 0.2},
}


def _time(field, settings, start, repeat):
    """(median, minimum) wall time [s] of ``repeat`` runs, and the last result."""
    out = []
    res = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = simulate(field, settings, start)
        out.append(time.perf_counter() - t0)
    return statistics.median(out), min(out), res


def child(args: argparse.Namespace) -> None:
    """Rigid timings of the tree on PYTHONPATH, as JSON {case: minimum seconds}."""
    field, _ = get_flow_field(FlowSettings(dx=args.dx), args.cache)
    warm = FiberStart(0.0, 0.8, 0.5)
    out = {}
    for name, eff in {"no effect": {}, **EFFECT_SETS}.items():
        st = FiberSettings().model_copy(update={"effects": eff})
        simulate(field, st, warm)  # compile this effect set
        for label, start in STARTS.items():
            _, t_min, res = _time(field, st, start, args.repeat)
            out[f"{name}, {label.split(' (')[0]}"] = (t_min, res.n_steps)
    print(json.dumps(out))


def against(args: argparse.Namespace) -> None:
    """This tree and ``args.against``, alternately in fresh processes: ratios this/other."""
    here = Path(__file__).resolve().parents[2]  # the repository
    trees = {"this": here, "other": args.against.resolve()}
    cache = str(Path(args.cache).resolve())
    argv = [sys.executable, str(Path(__file__).resolve()), "--child", "--dx", str(args.dx),
            "--cache", cache, "--repeat", str(args.repeat)]  # fmt: skip
    times: dict[tuple[str, str], list[float]] = {}
    steps: dict[tuple[str, str], int] = {}
    for rnd in range(args.rounds):
        for name, tree in trees.items():
            env = {**os.environ, "PYTHONPATH": str(tree)}
            run = subprocess.run(argv, cwd=tree, env=env, capture_output=True, text=True)
            if run.returncode != 0:
                raise SystemExit(f"{tree}: {run.stderr}")
            for case, (t, n) in json.loads(run.stdout.strip().splitlines()[-1]).items():
                times.setdefault((case, name), []).append(t)
                steps[(case, name)] = n
            print(f"round {rnd} {name} done", flush=True)
    print(f"this: {trees['this']}\nother: {trees['other']}\n{args.rounds} rounds, "
          f"each the minimum of {args.repeat} runs; ratio of the medians over rounds")  # fmt: skip
    for case in dict.fromkeys(c for c, _ in times):
        a = statistics.median(times[(case, "this")])
        b = statistics.median(times[(case, "other")])
        same = "same" if steps[(case, "this")] == steps[(case, "other")] else "DIFFERENT"
        print(f"  {case:<48} this {a * 1e3:8.2f} ms  other {b * 1e3:8.2f} ms  "
              f"ratio {a / b:.3f}  ({same} steps)")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, default=4.0)
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--repeat", type=int, default=20, help="rigid repetitions (median, min)")
    ap.add_argument("--no-effects", action="store_true", help="skip the rigid runs with effects on")
    ap.add_argument("--against", type=Path, help="another checkout: before/after ratios")
    ap.add_argument("--rounds", type=int, default=5, help="rounds per tree (--against)")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args)
        return
    if args.against is not None:
        against(args)
        return
    field, _ = get_flow_field(FlowSettings(dx=args.dx), args.cache)
    rigid = FiberSettings()
    beads = FiberSettings(model="bead-spring")
    warm = FiberStart(0.0, 0.8, 0.5)
    simulate(field, rigid, warm)
    simulate(field, beads.model_copy(update={"x0": 1100.0}), warm)
    print(f"flow field dx = {args.dx} µm; fiber L = l_obs; Numba compiled before timing")
    for label, start in STARTS.items():
        tr, tr_min, rr = _time(field, rigid, start, args.repeat)
        tb, _, rb = _time(field, beads, start, 1)
        print(f"\n{label}")
        print(f"  rigid       : {tr:8.4f} s (min {tr_min:.4f})  {rr.n_steps:7d} steps  "
              f"class {rr.cls}  delta {rr.delta:+.4f}")  # fmt: skip
        print(f"  bead-spring : {tb:8.3f} s  (dt = 5e-5 s)       class {rb.cls}  "
              f"delta {rb.delta:+.4f}")  # fmt: skip
        print(f"  ratio bead-spring / rigid = {tb / tr:.0f}")
        src_steps = rr.t_end / 1e-7
        print(f"  the source's scheme (dt = 1e-7 s) would need {src_steps:.1e} steps")
        if args.no_effects:
            continue
        for name, eff in EFFECT_SETS.items():
            st = rigid.model_copy(update={"effects": eff})
            simulate(field, st, warm)  # compile this effect set
            te, te_min, re_ = _time(field, st, start, args.repeat)
            print(f"  rigid + {name:17s}: {te:8.4f} s (min {te_min:.4f})  "
                  f"{re_.n_steps:7d} steps  class {re_.cls}")  # fmt: skip


if __name__ == "__main__":
    main()
