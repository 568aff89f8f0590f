#!/usr/bin/env python3
"""Resolved-particle step: node updates per second, node-wise against blocked kernels.

The coupled step of a bump-or-zigzag decision (:mod:`fibersweep.resolved.dld`: the
circle array's cell, a sphere of ``--diameter`` µm on the pillar's apex, lubrication
and contact on) at each ``--dx``, timed for ``--steps`` steps after a warm-up. Each
variant runs in its own process, the variants alternate for ``--rounds`` rounds on the
same machine and load, and the script prints every time, the best per variant and the
ratios to the node-wise kernels. Variants:

* ``nodewise``: this tree, ``Lattice(blocked=False)`` (the node-loop collision and
  node-table streaming of :mod:`fibersweep.resolved.kernels`);
* ``blocked``: this tree's default (:mod:`fibersweep.resolved.kernels_blocked`);
* ``baseline``: the tree given by ``--baseline`` (its own default step), for example
  the commit before the blocked kernels, unpacked with
  ``git archive 02088b9 | tar -x -C /tmp/resolved-base``.

``--profile`` also splits one step of the blocked variant into its parts (collision,
streaming, the pillar's links, the particle's links, refilling, the rest: the body's
update, contact and bookkeeping in Python).

    python3 scripts/benchmarks/bench_resolved.py [--dx 2 1] [--threads 1 2] [--steps 300]
        [--rounds 2] [--baseline TREE] [--profile]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]

#: a smoke pass (scripts/benchmarks/run.py --smoke): a coarse cell, a few steps, one round
SMOKE = ["--dx", "4", "--threads", "1", "--steps", "5", "--rounds", "1", "--profile"]


def _setup(dx: float, diameter: float, threads: int, blocked: bool | None):
    """This process's tree: the coupled sphere in the cell at rest, its force at Re_p = 0.2."""
    import numpy as np

    from fibersweep.resolved import dld
    from fibersweep.resolved.lattice import FluidSettings, Lattice
    from fibersweep.resolved.particle import Body, BodyState
    from fibersweep.resolved.run import Coupled

    cs = dld.CellSettings(shift=0.1, dx=dx, tau=1.5, reynolds=0.2)
    box, shape, _ = dld._box(cs)
    fluid = FluidSettings(tau=cs.tau)
    radius = diameter / 2.0 / dx
    kw = {} if blocked is None else {"blocked": blocked}
    lat = Lattice(box, fluid, force=(1e-5, 1e-6, 0.0), **kw)
    lat.threads = threads  # both trees read the attribute at each step
    gaps: list = []
    act, keep = dld._contact(cs, shape, box, radius, fluid, gaps)
    start = np.array([shape.cx, shape.cy + shape.radius + radius + cs.start_gap, box.nz])
    run = Coupled(lat, Body(radius), BodyState(start), motion="planar", external=act,
                  constrain=keep)  # fmt: skip
    return run


def _parts(run, steps: int) -> dict[str, float]:
    """Seconds per call of each kernel of one step on the run's current state (this tree)."""
    import numpy as np

    from fibersweep.resolved import kernels, kernels_blocked

    lat = run.lattice
    om_p, om_m = lat.fluid.rates
    body = run.state.vector(run.body)
    node, q, t, beyond = lat.links
    calls = {
        "collision": lambda: kernels_blocked.collide_blocked(
            lat.f, lat.flags, lat.force, om_p, om_m
        ),  # fmt: skip
        "streaming": lambda: kernels_blocked.stream_rows(
            lat.f, lat.fn, lat.rows, lat.src, lat.box.wall_velocity
        ),  # fmt: skip
        "pillar links": lambda: kernels.static_links(
            lat.f, lat.fn, lat.flags, node, q, t, beyond
        ),  # fmt: skip
        "particle links": lambda: kernels.particle_links(
            lat.f, lat.fn, lat.flags, lat.dims, body, np.zeros(43)
        ),  # fmt: skip
        "refill": lambda: kernels.refill(
            lat.f, lat.flags.copy(), lat.dims, body, 0.01, np.zeros(6)
        ),  # fmt: skip
    }
    out = {}
    for name, fn in calls.items():
        fn()
        t0 = time.perf_counter()
        for _ in range(steps):
            fn()
        out[name] = (time.perf_counter() - t0) / steps
    return out


def worker(dx: float, diameter: float, steps: int, threads: int, blocked: bool | None,
           profile: bool) -> dict:  # fmt: skip
    """Time ``steps`` coupled steps after 20 warm-up steps; JSON-able result."""
    import numba

    numba.set_num_threads(threads)
    run = _setup(dx, diameter, threads, blocked)
    for _ in range(20):
        run.step()
    t0 = time.perf_counter()
    for _ in range(steps):
        run.step()
    per = (time.perf_counter() - t0) / steps
    res = {"s_per_step": per, "nodes": run.lattice.box.nodes}
    if profile:
        res["parts"] = _parts(run, steps)
    return res


def _spawn(tree: Path, args: list[str]) -> dict:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", *args]
    out = subprocess.run(cmd, env=env, cwd=str(tree), capture_output=True, text=True, check=False)
    if out.returncode != 0:
        raise RuntimeError(f"worker failed ({tree}):\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, nargs="+", default=[2.0, 1.0])
    ap.add_argument("--diameter", type=float, default=11.0)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--baseline", type=Path, default=None)
    ap.add_argument("--profile", action="store_true")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--variant", default="blocked", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        blocked = {"blocked": True, "nodewise": False, "baseline": None}[args.variant]
        res = worker(args.dx[0], args.diameter, args.steps, args.threads[0], blocked,
                     args.profile and args.variant == "blocked")  # fmt: skip
        print(json.dumps(res))
        return
    variants = ["nodewise", "blocked"] + (["baseline"] if args.baseline else [])
    load = os.getloadavg()[0]
    print(f"load average {load:.1f}; {args.steps} steps per timing, D = {args.diameter} µm, "
          f"eps = 0.1, Re_p = 0.2; best of {args.rounds} alternating rounds")  # fmt: skip
    for dx in args.dx:
        best: dict = {}
        parts = None
        for rnd in range(args.rounds):
            for th in args.threads:
                for v in variants:
                    tree = args.baseline if v == "baseline" else REPO
                    wa = ["--dx", str(dx), "--diameter", str(args.diameter), "--steps",
                          str(args.steps), "--threads", str(th), "--variant", v]  # fmt: skip
                    if args.profile and rnd == 0 and th == args.threads[0] and v == "blocked":
                        wa.append("--profile")
                    res = _spawn(tree, wa)
                    nodes = res["nodes"]
                    print(
                        f"dx = {dx:g} µm ({nodes} nodes) round {rnd} threads {th} {v:9s}: "
                        f"{res['s_per_step'] * 1e3:8.3f} ms/step, "
                        f"{nodes / res['s_per_step'] / 1e6:6.1f} e6 node updates/s",
                        flush=True,
                    )
                    key = (th, v)
                    best[key] = min(best.get(key, float("inf")), res["s_per_step"])
                    parts = res.get("parts", parts)
        print(f"\ndx = {dx:g} µm, best per variant (ms/step, e6 node updates/s, nodewise/this):")
        ref = best[(args.threads[0], "nodewise")]
        for (th, v), s in sorted(best.items()):
            print(
                f"  threads {th} {v:9s} {s * 1e3:8.3f} ms  {nodes / s / 1e6:6.1f} e6/s  "
                f"x{ref / s:5.2f} against nodewise at {args.threads[0]} thread(s)"
            )
        if parts is not None:
            total = best[(args.threads[0], "blocked")]
            print(f"  profile of one blocked step at {args.threads[0]} thread(s):")
            for name, s in parts.items():
                print(f"    {name:15s} {s * 1e3:8.3f} ms  {100 * s / total:5.1f} %")
            rest = total - sum(parts.values())
            print(f"    {'rest (Python)':15s} {rest * 1e3:8.3f} ms  {100 * rest / total:5.1f} %")


if __name__ == "__main__":
    main()
