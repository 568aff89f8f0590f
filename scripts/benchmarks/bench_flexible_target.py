"""Issue 27's speed target: the adaptive bead-spring model against today's run, at today's accuracy.

Usage::

    python scripts/benchmarks/bench_flexible_target.py references [--moduli 26e6 0.1e6] [--lengths \
        0.5 1.0]
    python scripts/benchmarks/bench_flexible_target.py compare [--moduli ...] [--lengths ...] \
        [--repeat 3]

"Today's run" is ``bead-spring`` at its default fixed step Δt = 5e-5 s (BDF2 with a
Newton solve, 4.1–4.3 s for L = l_obs). The target asks for the new integrator to be
20 × faster than that run *at equal accuracy*, errors measured against a Δt = 1e-6 s
reference. So, per (E, L), from θ0 = 0, y0/h = 0.45 (an apex contact) at dx = 4 µm:

``references`` runs ``bead-spring`` at Δt = 1e-6 s (minutes to tens of minutes per
run) and stores, in ``--ref-dir``, its δ and the bead positions at two common times,
0.5 and 0.8 of today's run's end time rounded to a multiple of T_GRID (during and
after the pillar contact). Existing files are kept (``--force`` redoes them).

``compare`` measures today's run's errors against the reference (|Δδ| and the largest
bead distance at the two times [µm]), then, for the adaptive model with
``fiber.step.rosenbrock`` ros2 and ros34pw2, scans the tolerances of TOLERANCES from
loose to tight and takes the loosest one at which *all three* errors are at most
today's (times ``--slack``, default 1: no slack). Each run is timed ``--repeat``
times in the same process, one model after the other, after the kernels are
compiled; the best time counts. It prints the ratio t_today / t_adaptive per
(E, L), and its min / median / max: the issue's number.

A second ratio compares with a *coarser* fixed step of the same accuracy as the
adaptive run (the stricter comparison of ``bench_flexible.py --equal-accuracy``): the
largest fixed Δt of FIXED_DTS whose errors are all within those of the chosen
adaptive run.
"""

from __future__ import annotations

import argparse
import math
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
SMOKE = [
    ["references", "--moduli", "26e6", "--lengths", "0.5", "--reference-dt", "1e-4",
     "--ref-dir", "{tmp}", "--cache", "{cache}"],
    ["compare", "--moduli", "26e6", "--lengths", "0.5", "--ref-dir", "{tmp}", "--repeat", "1",
     "--cache", "{cache}"],
]

T_GRID = 2e-4
"""Comparison times are multiples of this [s], so that fixed steps land on them."""
TOLERANCES = (1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7)
"""Tolerances [µm] scanned, loose to tight."""
FIXED_DTS = (4e-4, 2e-4, 1e-4, 5e-5)
"""Fixed steps [s] scanned for the stricter comparison, coarse to fine."""
METHODS = ("ros2", "ros34pw2")


def _settings(model: str, E: float, **step) -> FiberSettings:
    return FiberSettings(model=model, young_modulus=E, step=StepSettings(**step))


def _times(t_end_today: float) -> tuple[float, float]:
    return tuple(T_GRID * round(f * t_end_today / T_GRID) for f in (0.5, 0.8))  # type: ignore


def _ref_path(ref_dir: Path, E: float, L: float, y0: float, dx: float) -> Path:
    return ref_dir / f"ref-E{E:g}-L{L:g}-y{y0:g}-dx{dx:g}.npz"


def _beads_at_times(field, st, start, times) -> list[np.ndarray]:
    """Bead positions (n, 2) [µm] at each time of ``times`` (one run per time)."""
    return [simulate_for(field, st, start, t)[0].beads[-1] for t in times]


def references(field, args) -> None:
    """Compute and store the Δt = 1e-6 s references (module docstring)."""
    ref_dir = Path(args.ref_dir)
    ref_dir.mkdir(parents=True, exist_ok=True)
    for E in args.moduli:
        for L in args.lengths:
            path = _ref_path(ref_dir, E, L, args.y0, args.dx)
            if path.exists() and not args.force:
                print(f"{path}: kept", flush=True)
                continue
            start = FiberStart(0.0, args.y0, L)
            today = simulate(field, _settings("bead-spring", E), start)
            t5, t8 = _times(today.t_end)
            st = _settings("bead-spring", E, dt=args.reference_dt)
            t0 = time.perf_counter()
            ref = simulate(field, st, start)
            traj, _ = simulate_for(field, st, start, t8)
            i5 = int(np.argmin(np.abs(traj.t - t5)))
            if abs(traj.t[i5] - t5) > 0.5 * args.reference_dt:
                raise RuntimeError(f"no reference row at t = {t5} s")
            wall = time.perf_counter() - t0
            tmp = path.with_suffix(".tmp.npz")
            np.savez(tmp, delta=ref.delta, t_end=ref.t_end, cls=ref.cls, times=[t5, t8],
                     beads5=traj.beads[i5], beads8=traj.beads[-1], dt=args.reference_dt,
                     wall=wall)  # fmt: skip
            tmp.replace(path)
            print(f"E = {E / 1e6:g} MPa, L/l = {L:g}: delta {ref.delta:+.7f} ({ref.cls}), "
                  f"t_end {ref.t_end:.4f} s, {wall:.0f} s -> {path}", flush=True)  # fmt: skip


def _errors(field, st, start, ref) -> tuple[float, float, float, float, int]:
    """(wall [s], |Δδ|, bead error at t5 [µm], at t8 [µm], steps) of one timed run."""
    t0 = time.perf_counter()
    r = simulate(field, st, start)
    wall = time.perf_counter() - t0
    b5, b8 = _beads_at_times(field, st, start, ref["times"])
    e5 = float(np.max(np.hypot(*(b5 - ref["beads5"]).T)))
    e8 = float(np.max(np.hypot(*(b8 - ref["beads8"]).T)))
    return wall, abs(r.delta - float(ref["delta"])), e5, e8, r.n_steps


def _best_time(field, st, start, repeat: int) -> float:
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        simulate(field, st, start)
        best = min(best, time.perf_counter() - t0)
    return best


def _within(err, bound, slack: float) -> bool:
    return all(e <= slack * b for e, b in zip(err[1:4], bound[1:4], strict=True))


def compare(field, args) -> None:
    """Print the speed-ups at today's accuracy (module docstring)."""
    ref_dir = Path(args.ref_dir)
    ratios: dict[str, list[float]] = {m: [] for m in METHODS}
    strict: dict[str, list[float]] = {m: [] for m in METHODS}
    warm = FiberStart(0.0, 0.8, 0.5)
    for m in METHODS:
        simulate(field, _settings("bead-spring-ros2", 26e6, rosenbrock=m), warm)
    simulate(field, _settings("bead-spring", 26e6), warm)
    fmt = "{:>22s} {:>8s} {:>7s} {:>9s} {:>11s} {:>11s}"
    for E in args.moduli:
        for L in args.lengths:
            path = _ref_path(ref_dir, E, L, args.y0, args.dx)
            if not path.exists():
                print(f"E = {E / 1e6:g} MPa, L/l = {L:g}: no reference ({path}); skipped")
                continue
            ref = np.load(path)
            start = FiberStart(0.0, args.y0, L)
            print(f"\nE = {E / 1e6:g} MPa, L/l = {L:g}: reference dt = {float(ref['dt']):g} s, "
                  f"delta {float(ref['delta']):+.7f}, beads at t = {ref['times'][0]:.4f}, "
                  f"{ref['times'][1]:.4f} s")  # fmt: skip
            print(fmt.format("run", "wall [s]", "steps", "|d delta|", "beads t5", "beads t8"))
            st_today = _settings("bead-spring", E)
            today = _errors(field, st_today, start, ref)
            t_today = min(today[0], _best_time(field, st_today, start, args.repeat))
            print(fmt.format("today: fixed dt 5e-5", f"{t_today:.3f}", str(today[4]),
                             *(f"{e:.1e}" for e in today[1:4])))  # fmt: skip
            for m in METHODS:
                chosen = None
                for tol in TOLERANCES:
                    st = _settings("bead-spring-ros2", E, rosenbrock=m, tolerance=tol)
                    err = _errors(field, st, start, ref)
                    ok = _within(err, today, args.slack)
                    print(fmt.format(f"{m} tol {tol:g}", f"{err[0]:.3f}", str(err[4]),
                                     *(f"{e:.1e}" for e in err[1:4]))
                          + ("  <- equal accuracy" if ok else ""), flush=True)  # fmt: skip
                    if ok:
                        chosen = (tol, st, err)
                        break
                if chosen is None:
                    print(f"  {m}: no tolerance reaches today's accuracy")
                    continue
                tol, st, err = chosen
                t_new = _best_time(field, st, start, args.repeat)
                ratios[m].append(t_today / t_new)
                line = (f"  -> {m} tol {tol:g}: {t_new:.3f} s, "
                        f"speed-up over today {t_today / t_new:.1f}")  # fmt: skip
                for dt in FIXED_DTS:
                    st_f = _settings("bead-spring", E, dt=dt)
                    ef = _errors(field, st_f, start, ref)
                    if _within(ef, err, 1.0):
                        t_f = _best_time(field, st_f, start, args.repeat)
                        strict[m].append(t_f / t_new)
                        line += f"; over fixed dt {dt:g} s of its accuracy {t_f / t_new:.1f}"
                        break
                print(line, flush=True)
    print()
    for m in METHODS:
        for name, v in (("over today's run", ratios[m]),
                        ("over a fixed step as accurate", strict[m])):  # fmt: skip
            if v:
                print(f"speed-up {m} {name}: min {min(v):.1f}, median "
                      f"{float(np.median(v)):.1f}, max {max(v):.1f} ({len(v)} cases)")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=("references", "compare"))
    ap.add_argument("--dx", type=float, default=4.0)
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--ref-dir", default="results/flexible-reference")
    ap.add_argument("--moduli", type=float, nargs="+", default=[26e6, 0.1e6])
    ap.add_argument("--lengths", type=float, nargs="+", default=[0.5, 1.0])
    ap.add_argument("--y0", type=float, default=0.45, help="start y0/h_obs (theta0 = 0)")
    ap.add_argument("--reference-dt", type=float, default=1e-6)
    ap.add_argument("--force", action="store_true")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--slack", type=float, default=1.0,
                    help="an adaptive run is as accurate when each error <= slack x "
                    "today's")  # fmt: skip
    args = ap.parse_args()
    field, _ = get_flow_field(FlowSettings(dx=args.dx), args.cache)
    if args.what == "references":
        references(field, args)
    else:
        compare(field, args)


if __name__ == "__main__":
    main()
