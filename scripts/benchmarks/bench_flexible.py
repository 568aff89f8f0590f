"""Time the adaptive bead-spring models (ROS2, ROS34PW2) against the fixed-step one; print ratios.

Usage: python scripts/benchmarks/bench_flexible.py [--dx 4] [--cache .fibersweep-cache]
       [--moduli 26e6 5e6 1e6 0.1e6] [--lengths 0.5 1.0] [--y0 0.45]
       [--reference-dt 1e-6] [--reference-moduli 26e6] [--reference-lengths 1.0]

For every (E, L) on the grid, one run from (theta0 = 0, y0/h) is timed with
``bead-spring`` (fixed Δt = 5e-5 s, today's default) and with
``bead-spring-ros2`` (adaptive), in the same process after the Numba kernels
are compiled; the ratio of the two wall times is printed with both δ. For the
(E, L) named by ``--reference-moduli`` x ``--reference-lengths``, a reference
run of ``bead-spring`` at Δt = ``--reference-dt`` (1e-6 s; minutes per run)
gives the error of both models: |Δδ| (δ = (y_f - y0)/h_obs) and the largest
distance between the final bead positions at the reference's end time [µm]
(``simulate_for`` to the same time). ``--reference-dt 0`` skips the references.
``--equal-accuracy`` instead times, for every (E, L) of the grid, two accuracy
levels of three runs each: fixed Δt = 2e-4 / 1e-4 s, ROS2 at tolerance
3e-4 / 1e-4 µm and ROS34PW2 (``fiber.step.rosenbrock: ros34pw2``) at 1e-5 /
1e-6 µm (its error estimate is that of a second-order solution, so it needs a
tighter tolerance than ROS2 for the same error). Errors are taken against the
Δt = 5e-5 s run (at 26 MPa, l_obs within 1e-6 in δ of Δt = 1e-6 s): |Δδ| and
the largest bead error at a common time. It
prints the ratios of the wall times (fixed/ros3, ros2/ros3, fixed/ros2),
measured in the same run, and their min / median / max over the grid.

With ``--against TREE`` (a checkout of another version), it times every (E, L)
of the grid with each integrator of ``--integrators`` (fixed, ros2, ros3; tolerances
at their defaults) in this tree and in TREE alternately (each first in turn),
``--rounds`` times each in fresh processes (Numba compiled beforehand in each), and
prints the ratio
this/other of the median over rounds of each round's minimum of ``--repeat`` runs,
and whether both took the same steps. ``--cpu`` times the process's CPU time instead
of the wall clock (steadier when other work loads the cores). The settings are spelled so that every
version reads them (the former model name ``bead-spring-ros2``).

Usage: python scripts/bench_flexible.py --against /tmp/before [--rounds 3] [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from fibersweep.config.fiber import FiberSettings, StepSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate, simulate_for
from fibersweep.flow.cache import get_flow_field

#: Arguments of a run of seconds (scripts/benchmarks/run.py --smoke): the script runs
#: end to end, its numbers mean nothing.
SMOKE = ["--moduli", "1e6", "--lengths", "0.5", "--reference-dt", "0", "--cache", "{cache}"]


def _run(field, model, E, start, dt=None):
    st = FiberSettings(model=model, young_modulus=E, step=StepSettings(dt=dt))
    t0 = time.perf_counter()
    r = simulate(field, st, start)
    return time.perf_counter() - t0, r


def _beads_at(field, model, E, start, t_end, dt=None):
    """Bead positions (n, 2) [µm] at time t_end [s]."""
    st = FiberSettings(model=model, young_modulus=E, step=StepSettings(dt=dt))
    traj, _ = simulate_for(field, st, start, t_end)
    return traj.beads[-1]


ACCURACY_LEVELS = (
    ("fixed dt = 2e-4 s", {"dt": 2e-4}, "ros2 tol 3e-4", {"tolerance": 3e-4},
     "ros3 tol 1e-5", {"rosenbrock": "ros34pw2", "tolerance": 1e-5}),
    ("fixed dt = 1e-4 s", {"dt": 1e-4}, "ros2 tol 1e-4", {"tolerance": 1e-4},
     "ros3 tol 1e-6", {"rosenbrock": "ros34pw2", "tolerance": 1e-6}),
)  # fmt: skip
"""Per accuracy level: the fixed-step run, the ROS2 run and the ROS34PW2 run compared."""

T_GRID = 2e-4
"""The comparison time is a multiple of this [s], so that every fixed step lands on it."""


def _settings(model, E, step):
    return FiberSettings(model=model, young_modulus=E, step=StepSettings(**step))


def _accuracy_run(field, model, E, step, start, ref_delta, ref_beads, t_cmp):
    """(wall [s], steps, |Δδ|, largest bead error at t_cmp [µm]) of one run."""
    st = _settings(model, E, step)
    t0 = time.perf_counter()
    r = simulate(field, st, start)
    wall = time.perf_counter() - t0
    traj, _ = simulate_for(field, st, start, t_cmp)
    err = float(np.max(np.hypot(*(traj.beads[-1] - ref_beads).T)))
    return wall, r.n_steps, abs(r.delta - ref_delta), err


def equal_accuracy(field, y0: float, moduli, lengths) -> None:
    """Print, per (E, L) and level of ACCURACY_LEVELS, the three runs and their wall-time ratios.

    Errors against the fixed-step Δt = 5e-5 s run of the same (E, L): |Δδ| (δ as
    reported, read at the first step past the stop line) and the largest bead
    distance [µm] at t_cmp, a multiple of T_GRID near 0.8 of the reference's end
    time: past the pillar contact (which ends near 0.6 of it at y0/h = 0.45), so
    it holds the error of the approach and of the contact, and is free of where a
    step lands on the stop line. Each ratio says, for δ and for the beads, whether
    the faster run's error is at most 1.5 times the slower run's ("=") or not
    ("LESS").
    """
    ratios: dict[str, list[float]] = {"fixed/ros3": [], "ros2/ros3": [], "fixed/ros2": []}
    for E in moduli:
        for L in lengths:
            start = FiberStart(0.0, y0, L)
            _, ref = _run(field, "bead-spring", E, start)
            t_cmp = T_GRID * round(0.8 * ref.t_end / T_GRID)
            traj, _ = simulate_for(field, _settings("bead-spring", E, {}), start, t_cmp)
            ref_beads = traj.beads[-1]
            print(f"E = {E / 1e6:g} MPa, L/l = {L:g}; reference: fixed dt = 5e-5 s, "
                  f"delta {ref.delta:+.7f}; beads compared at t = {t_cmp:.4f} s")  # fmt: skip
            for level in ACCURACY_LEVELS:
                res = {}
                runs = {
                    "fixed": (level[0], "bead-spring", level[1]),
                    "ros2": (level[2], "bead-spring-ros2", level[3]),
                    "ros3": (level[4], "bead-spring-ros2", level[5]),
                }
                for key, (label, model, step) in runs.items():
                    res[key] = _accuracy_run(field, model, E, step, start, ref.delta,
                                             ref_beads, t_cmp)  # fmt: skip
                    w, n, dd, eb = res[key]
                    print(f"  {label:20s} {w:7.3f} s {n:7d} steps  |d delta| {dd:.1e}  "
                          f"bead err {eb:.1e} um", flush=True)  # fmt: skip
                line = []
                for slow, fast in (("fixed", "ros3"), ("ros2", "ros3"), ("fixed", "ros2")):
                    a, b = res[slow], res[fast]
                    d_ok = "=" if b[2] <= 1.5 * a[2] else "LESS"
                    b_ok = "=" if b[3] <= 1.5 * a[3] else "LESS"
                    ratios[f"{slow}/{fast}"].append(a[0] / b[0])
                    line.append(f"{slow}/{fast} {a[0] / b[0]:5.1f} (delta {d_ok}, beads {b_ok})")
                print("  -> speed-up " + ", ".join(line))
    for key, v in ratios.items():
        print(f"speed-up {key}: min {min(v):.1f}, median {float(np.median(v)):.1f}, "
              f"max {max(v):.1f}")  # fmt: skip


#: --against: each integrator as (model, step settings), in a spelling every version reads
INTEGRATORS = {
    "fixed": ("bead-spring", {}),
    "ros2": ("bead-spring-ros2", {}),
    "ros3": ("bead-spring-ros2", {"rosenbrock": "ros34pw2"}),
}


def child(args: argparse.Namespace) -> None:
    """Timings of the tree on PYTHONPATH, as JSON {case: [minimum seconds, steps]}."""
    field, _ = get_flow_field(FlowSettings(dx=args.dx), args.cache)
    warm = FiberStart(0.0, 0.8, 0.5)
    out = {}
    for name in args.integrators:
        model, step = INTEGRATORS[name]
        simulate(field, _settings(model, 26e6, step), warm)  # compile
        for E in args.moduli:
            for L in args.lengths:
                st = _settings(model, E, step)
                times = []
                clock = time.process_time if args.cpu else time.perf_counter
                for _ in range(args.repeat):
                    t0 = clock()
                    r = simulate(field, st, FiberStart(0.0, args.y0, L))
                    times.append(clock() - t0)
                out[f"{name:5s} E = {E / 1e6:g} MPa, L/l = {L:g}"] = [min(times), r.n_steps]
    print(json.dumps(out))


def against(args: argparse.Namespace) -> None:
    """This tree and ``args.against``, alternately in fresh processes: ratios this/other."""
    here = Path(__file__).resolve().parents[2]  # the repository
    trees = {"this": here, "other": args.against.resolve()}
    argv = [sys.executable, str(Path(__file__).resolve()), "--child", "--dx", str(args.dx),
            "--cache", str(Path(args.cache).resolve()), "--repeat", str(args.repeat),
            "--y0", str(args.y0), "--moduli", *map(str, args.moduli),
            "--lengths", *map(str, args.lengths), "--integrators", *args.integrators,
            *(["--cpu"] if args.cpu else [])]  # fmt: skip
    times: dict[tuple[str, str], list[float]] = {}
    steps: dict[tuple[str, str], int] = {}
    for rnd in range(args.rounds):
        order = list(trees.items())
        for name, tree in order[:: 1 if rnd % 2 == 0 else -1]:  # each tree first in turn
            env = {**os.environ, "PYTHONPATH": str(tree)}
            run = subprocess.run(argv, cwd=tree, env=env, capture_output=True, text=True)
            if run.returncode != 0:
                raise SystemExit(f"{tree}: {run.stderr}")
            for case, (t, n) in json.loads(run.stdout.strip().splitlines()[-1]).items():
                times.setdefault((case, name), []).append(t)
                steps[(case, name)] = n
            print(f"round {rnd} {name} done", flush=True)
    clock = "CPU" if args.cpu else "wall"
    print(f"this: {trees['this']}\nother: {trees['other']}\n{args.rounds} rounds, each the "
          f"minimum of {args.repeat} runs ({clock} time); ratio of the medians over rounds; "
          f"y0/h = {args.y0}")  # fmt: skip
    for case in dict.fromkeys(c for c, _ in times):
        a = statistics.median(times[(case, "this")])
        b = statistics.median(times[(case, "other")])
        same = "same" if steps[(case, "this")] == steps[(case, "other")] else "DIFFERENT"
        print(f"  {case:<32} this {a * 1e3:9.1f} ms  other {b * 1e3:9.1f} ms  "
              f"ratio {a / b:.3f}  ({same} steps)")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, default=4.0)
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--moduli", type=float, nargs="+", default=[26e6, 5e6, 1e6, 0.1e6])
    ap.add_argument("--lengths", type=float, nargs="+", default=[0.5, 1.0])
    ap.add_argument("--y0", type=float, default=0.45, help="start y0/h_obs (theta0 = 0)")
    ap.add_argument("--reference-dt", type=float, default=1e-6)
    ap.add_argument("--reference-moduli", type=float, nargs="*", default=[26e6])
    ap.add_argument("--reference-lengths", type=float, nargs="*", default=[1.0])
    ap.add_argument("--equal-accuracy", action="store_true", help="only the matched-error table")
    ap.add_argument("--against", type=Path, help="another checkout: before/after ratios")
    ap.add_argument("--rounds", type=int, default=3, help="rounds per tree (--against)")
    ap.add_argument("--repeat", type=int, default=3, help="runs per case and round (--against)")
    ap.add_argument("--integrators", nargs="+", choices=list(INTEGRATORS),
                    default=list(INTEGRATORS), help="--against: the integrators timed")  # fmt: skip
    ap.add_argument("--cpu", action="store_true", help="--against: CPU time, not wall time")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args)
        return
    if args.against is not None:
        against(args)
        return
    field, _ = get_flow_field(FlowSettings(dx=args.dx), args.cache)
    warm = FiberStart(0.0, 0.8, 0.5)
    for m in ("bead-spring", "bead-spring-ros2"):
        _run(field, m, 26e6, warm)
    _accuracy_run(field, "bead-spring-ros2", 26e6, ACCURACY_LEVELS[0][5], warm, 0.0,
                  np.zeros((11, 2)), 0.01)  # fmt: skip
    if args.equal_accuracy:
        equal_accuracy(field, args.y0, args.moduli, args.lengths)
        return
    print(
        f"flow field dx = {args.dx} µm; start theta0 = 0, y0/h = {args.y0}; compiled before timing"
    )
    print(f"{'E [MPa]':>8} {'L/l':>5} {'fixed [s]':>10} {'ros2 [s]':>9} {'ratio':>6} "
          f"{'steps f/r':>13} {'delta fixed':>12} {'delta ros2':>11} class")  # fmt: skip
    ratios = []
    for E in args.moduli:
        for L in args.lengths:
            start = FiberStart(0.0, args.y0, L)
            tb, rb = _run(field, "bead-spring", E, start)
            tr, rr = _run(field, "bead-spring-ros2", E, start)
            ratios.append(tb / tr)
            print(f"{E / 1e6:8.2f} {L:5.2f} {tb:10.3f} {tr:9.3f} {tb / tr:6.1f} "
                  f"{rb.n_steps:6d}/{rr.n_steps:<6d} {rb.delta:+12.5f} {rr.delta:+11.5f} "
                  f"{rb.cls}/{rr.cls}", flush=True)  # fmt: skip
    print(f"speed-up fixed/ros2: min {min(ratios):.1f}, median {float(np.median(ratios)):.1f}")
    if args.reference_dt <= 0:
        return
    print(f"\nerrors against bead-spring at dt = {args.reference_dt:g} s")
    print(f"{'E [MPa]':>8} {'L/l':>5} {'ref [s]':>8} {'|d delta| fixed':>16} {'ros2':>9} "
          f"{'bead err fixed [um]':>20} {'ros2':>8}")  # fmt: skip
    for E in args.reference_moduli:
        for L in args.reference_lengths:
            start = FiberStart(0.0, args.y0, L)
            t_ref, ref = _run(field, "bead-spring", E, start, dt=args.reference_dt)
            _, rb = _run(field, "bead-spring", E, start)
            _, rr = _run(field, "bead-spring-ros2", E, start)
            # Beads at a time within the pass (half the reference's end time).
            t_cmp = 0.5 * ref.t_end
            b_ref = _beads_at(field, "bead-spring", E, start, t_cmp, dt=args.reference_dt)
            b_fix = _beads_at(field, "bead-spring", E, start, t_cmp)
            b_ros = _beads_at(field, "bead-spring-ros2", E, start, t_cmp)
            e_fix = float(np.max(np.hypot(*(b_fix - b_ref).T)))
            e_ros = float(np.max(np.hypot(*(b_ros - b_ref).T)))
            d_fix = abs(rb.delta - ref.delta) if math.isfinite(ref.delta) else math.nan
            d_ros = abs(rr.delta - ref.delta) if math.isfinite(ref.delta) else math.nan
            print(f"{E / 1e6:8.2f} {L:5.2f} {t_ref:8.0f} {d_fix:16.2e} {d_ros:9.2e} "
                  f"{e_fix:20.3f} {e_ros:8.3f}   (ref delta {ref.delta:+.5f} {ref.cls})",
                  flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
