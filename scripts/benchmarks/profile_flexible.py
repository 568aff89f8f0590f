"""Where the time of a Rosenbrock-W bead-spring pillar pass goes; prints a per-part table.

Usage: python scripts/benchmarks/profile_flexible.py [--dx 4] [--cache .fibersweep-cache]
       [--young-modulus 26e6] [--length 1.0] [--y0 0.45] [--tolerance 0.01]
       [--rosenbrock ros2|ros34pw2]

One run (theta0 = 0, y0/h, L/l_obs) is timed after the kernels are compiled, and
its accepted / rejected steps are counted. Each part of a step is then timed on
its own in a compiled loop over the run's recorded configurations (so the
contact phase weighs as in the run): the bead velocity f(q) (flow interpolation,
elastic and contact forces, the RPY mobility rebuild and M F), the Jacobian
J = dF/dq and W = M J; the factorisation of I - γhW and the solves (whose cost does
not depend on the configuration) 2 000 times at the last one. Per-step costs times the number of
calls per step (s stages: s f, one J, one system, one factorisation, s solves;
a rejected step redoes all but f(q) and J; s = 2 for ROS2, 4 for ROS34PW2)
estimate the share of each part.
"""

from __future__ import annotations

import argparse
import time

import numba as nb
import numpy as np

from fibersweep.config.fiber import FiberSettings, StepSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.fiber.hydro.rpy import fiber_offsets, rpy_fill
from fibersweep.fiber.integrators import rosenbrock as I
from fibersweep.fiber.integrators.lu import lu_solve
from fibersweep.fiber.integrators.rosw import GAMMA2
from fibersweep.fiber.kernel import record as R
from fibersweep.fiber.kernel.bundles import build_kernel
from fibersweep.fiber.models.beadspring import bead_velocity, force_jacobian, force_jacobian_fd
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.fiber.setup import prepare
from fibersweep.flow.cache import get_flow_field

#: Arguments of a run of seconds (scripts/benchmarks/run.py --smoke): the script runs
#: end to end, its numbers mean nothing.
SMOKE = ["--length", "0.5", "--cache", "{cache}"]

REPS = 2000


@nb.njit  # not cached: a cache here would not see edits of the package kernels
def _set(k, beads, i):
    for j in range(beads.shape[1]):
        k.work.x[j] = beads[i, j, 0]
        k.work.y[j] = beads[i, j, 1]


@nb.njit  # not cached: a cache here would not see edits of the package kernels
def _t_velocity(k, beads):
    flow, pillar, body, p, w, bw, effects, frame = k
    for i in range(beads.shape[0]):
        _set(k, beads, i)
        bead_velocity(frame, flow, pillar, body, p, w, bw, effects)


@nb.njit  # not cached: a cache here would not see edits of the package kernels
def _t_mobility(k, beads):
    w = k.work
    for i in range(beads.shape[0]):
        _set(k, beads, i)
        rpy_fill(w.x, w.y, k.params.a, k.params.mu, k.bead.mob)


@nb.njit  # not cached: a cache here would not see edits of the package kernels
def _t_set(k, beads):
    for i in range(beads.shape[0]):
        _set(k, beads, i)


@nb.njit  # not cached: a cache here would not see edits of the package kernels
def _t_jacobian(k, beads, fd):
    flow, pillar, body, p, w, bw, effects, frame = k
    for i in range(beads.shape[0]):
        _set(k, beads, i)
        # the contact stiffness w.st of this configuration (which beads are in contact)
        bead_velocity(frame, flow, pillar, body, p, w, bw, effects)
        if fd:
            force_jacobian_fd(frame, pillar, p, w, bw)
        else:
            force_jacobian(frame, pillar, p, w, bw)


@nb.njit  # not cached: a cache here would not see edits of the package kernels
def _t_wmatrix(k, beads):
    flow, pillar, body, p, w, bw, effects, frame = k
    for i in range(beads.shape[0]):
        _set(k, beads, i)
        bead_velocity(frame, flow, pillar, body, p, w, bw, effects)
        force_jacobian(frame, pillar, p, w, bw)
        I.w_matrix(bw)


@nb.njit  # not cached: a cache here would not see edits of the package kernels
def _t_factor(k, reps, piv):
    for _ in range(reps):
        I.system(k.bead, 1e-4, piv, GAMMA2)


@nb.njit  # not cached: a cache here would not see edits of the package kernels
def _t_solve(k, reps, piv, b):
    for _ in range(reps):
        lu_solve(k.bead.lhs, piv, b)


@nb.njit  # not cached: a cache here would not see edits of the package kernels
def _t_np_solve(k, reps, b):
    for _ in range(reps):
        lhs = k.bead.lhs.copy()
        np.linalg.solve(lhs, b)


def _run(k, setup):
    """(accepted, rejected, beads (rows, n, 2), record rows) of a run, as run_rosenbrock."""
    n = setup.n
    s = fiber_offsets(n, k.params.a)
    th0 = setup.th0
    q = np.column_stack([setup.x0 + s * np.cos(th0), setup.y0_abs + s * np.sin(th0)]).ravel()
    state = np.array([0.0, np.nan, th0, min(1e-5, k.params.dt_max), 0.0])
    scratch = [np.zeros(2 * n) for _ in range(5)]
    recs, brecs = [], []
    while True:
        rec = np.empty((R.CHUNK, R.NCOLS))
        brec = np.empty((R.CHUNK, n, 2))
        rows, code = I.integrate_rosenbrock(q, state, k, rec, brec, *scratch)
        recs.append(rec[:rows])
        brecs.append(brec[:rows])
        if code != R.CHUNK_FULL:
            beads = np.concatenate(brecs)
            return beads.shape[0] - 1, int(state[4]), beads, np.concatenate(recs)


def _per_config(fn, k, beads, *args) -> float:
    """Seconds per configuration of ``fn`` over the run's configurations ``beads``."""
    fn(k, beads[:2], *args)  # compile
    t0 = time.perf_counter()
    fn(k, beads, *args)
    return (time.perf_counter() - t0) / beads.shape[0]


def _time(fn, *args) -> float:
    """Seconds per call of a part at a fixed configuration (REPS calls)."""
    fn(args[0], 2, *args[1:])  # compile
    t0 = time.perf_counter()
    fn(args[0], REPS, *args[1:])
    return (time.perf_counter() - t0) / REPS


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, default=4.0)
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--young-modulus", type=float, default=26e6)
    ap.add_argument("--length", type=float, default=1.0)
    ap.add_argument("--y0", type=float, default=0.45)
    ap.add_argument("--tolerance", type=float, default=0.01)
    ap.add_argument("--rosenbrock", choices=("ros2", "ros34pw2"), default="ros2")
    args = ap.parse_args()
    stages = 2 if args.rosenbrock == "ros2" else 4
    field, _ = get_flow_field(FlowSettings(dx=args.dx), args.cache)
    st = FiberSettings(
        model="bead-spring",
        integrator=args.rosenbrock,
        young_modulus=args.young_modulus,
        step=StepSettings(tolerance=args.tolerance),
    )
    start = FiberStart(0.0, args.y0, args.length)
    simulate(field, st, start)  # compile
    t0 = time.perf_counter()
    simulate(field, st, start)
    wall = time.perf_counter() - t0
    setup = prepare(field, st, start, np.random.default_rng(0))
    k = build_kernel(setup)
    n = setup.n
    s = fiber_offsets(n, k.params.a)
    k.work.x[:] = setup.x0 + s
    k.work.y[:] = setup.y0_abs
    piv = np.zeros(2 * n, dtype=np.int64)
    b = np.ones(2 * n)
    acc, rej, beads, rec = _run(build_kernel(setup), setup)
    t_set = _per_config(_t_set, k, beads)
    t_f = _per_config(_t_velocity, k, beads) - t_set
    t_m = _per_config(_t_mobility, k, beads) - t_set
    t_j = _per_config(_t_jacobian, k, beads, False) - t_f - t_set
    t_jfd = _per_config(_t_jacobian, k, beads, True) - t_f - t_set
    t_w = _per_config(_t_wmatrix, k, beads) - t_j - t_f - t_set
    bead_velocity(k.frame, k.flow, k.pillar, k.body, k.params, k.work, k.bead, k.effects)
    force_jacobian(k.frame, k.pillar, k.params, k.work, k.bead)
    I.w_matrix(k.bead)
    t_lu = _time(_t_factor, k, piv)
    t_sol = _time(_t_solve, k, piv, b)
    t_np = _time(_t_np_solve, k, b)
    # calls: f(q) once per accepted step, the other stages' f once per try; J and W
    # once per accepted step; system + LU and the s solves once per try
    tries = acc + rej
    parts = {
        "f(q): flow, forces, mobility, M F": (t_f, acc + (stages - 1) * tries),
        "  of which the RPY mobility rebuild": (t_m, acc + (stages - 1) * tries),
        "Jacobian J (analytic elastic)": (t_j, acc),
        "W = M J": (t_w, acc),
        "I - γhW and its LU": (t_lu, tries),
        f"{stages} triangular solves": (stages * t_sol, tries),
    }
    print(f"run ({args.rosenbrock}): {n} beads, E = {args.young_modulus:g} Pa, "
          f"L/l = {args.length}, "
          f"tol {args.tolerance} µm: {wall:.3f} s wall, {acc} accepted + {rej} rejected steps, "
          f"{1e6 * wall / acc:.1f} µs per accepted step")  # fmt: skip
    print(f"{'part':38s} {'µs/call':>8} {'calls':>7} {'s':>7} {'share':>6}")
    for name, (t, calls) in parts.items():
        print(f"{name:38s} {1e6 * t:8.2f} {calls:7d} {t * calls:7.3f} {t * calls / wall:6.1%}")
    rest = wall - sum(t * c for nm, (t, c) in parts.items() if not nm.startswith(" "))
    print(f"{'rest (recording, stop test, setup)':38s} {'':8s} {'':7s} {rest:7.3f}")
    h = np.diff(rec[:, R.COLS.index("t")])
    c = rec[:-1, R.COLS.index("contact")] > 0
    print(f"in contact: {int(c.sum())} steps over {h[c].sum():.3f} s (median step "
          f"{np.median(h[c]):.1e} s); free: {int((~c).sum())} steps over {h[~c].sum():.3f} s "
          f"(median step {np.median(h[~c]):.1e} s)")  # fmt: skip
    print(
        f"for comparison (µs/call): Jacobian by central differences {1e6 * t_jfd:.2f}, "
        f"copy + np.linalg.solve {1e6 * t_np:.2f}"
    )


if __name__ == "__main__":
    main()
