"""One-bead fibers (spheres) through the array: zigzag/displacement transition vs the DLD law.

For each row shift ε, spheres of diameter D = 2a (one bead of radius a) run
through ``--rows`` rows from ``--starts`` seeded random entries (an ordinary
``fibersweep run`` sweep with ``flow.array`` set and ``sweep.random``); D_c is where
the mean displacement fraction crosses 1/2 (linear in D). It is compared with
the empirical law of Davis, D_c = 1.4 G ε^0.48, and with the steric estimate
D_c = 2 β of a point particle that follows the streamlines until it touches
(β the first-streamline width of the simulated gap profile).

    python3 scripts/studies/arrays/array_dc.py [--shifts 0.1 0.2] [--starts 8] [--rows 20]
        [--effect near_wall=1] [--radii 5 6 7 8 9 10] [--steric] [--gap 0.3] [--depth 80]
        [--curvature local]

``--effect NAME=VALUE`` (repeatable) adds a fiber effect to every run, e.g. the
near-wall hydrodynamics of the pillar (``near_wall=1``: the sphere-wall theory).
``--gap DELTA`` uses the gap contact law (``fiber.contact.law: gap``, range DELTA µm of
surface gap for every sphere size) instead of the source's chi law; ``--depth H`` sets
the array's depth [µm] (default 40 = G); ``--curvature local`` makes the near-wall
resistance follow the pillar's curvature (``fiber.contact.curvature``). ``--radii``
restricts the sphere radii a [µm] (default 1 to 13 µm in steps of 1).
``--steric`` also solves each cell once more for its 3D velocity and prints the
steric bound 2β of the simulated gap profile (the first streamline's width,
:func:`fibersweep.flow.cell.first_streamline_width`) and of a parabolic profile,
(β/G)²(3 − 2β/G) = ε.
"""

from __future__ import annotations

import argparse
import tempfile

import numpy as np
from scipy.optimize import brentq

from fibersweep.config import parse_config
from fibersweep.flow.cell import first_streamline_width, solve_cell
from fibersweep.sweep.runner import run_sweep
from fibersweep.sweep.store import read_runs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--shifts", type=float, nargs="+", default=[0.1, 0.2])
    ap.add_argument("--starts", type=int, default=8)
    ap.add_argument("--rows", type=int, default=20)
    ap.add_argument("--shape", default="circle")
    ap.add_argument("--effect", action="append", default=[], metavar="NAME=VALUE")
    ap.add_argument("--radii", type=float, nargs="+", default=[float(r) for r in range(1, 14)])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--steric", action="store_true", help="print the steric bound 2β too")
    ap.add_argument("--gap", type=float, default=None, help="gap contact law, range [µm]")
    ap.add_argument("--depth", type=float, default=40.0, help="array depth H [µm]")
    ap.add_argument(
        "--curvature",
        choices=("plane", "local"),
        default="plane",
        help="near_wall: the pillar as its tangent plane or with its curvature",
    )
    args = ap.parse_args()
    effects = {}
    for item in args.effect:
        name, _, value = item.partition("=")
        effects[name] = float(value)
    radii = sorted(args.radii)
    contact = {} if args.gap is None else {"law": "gap", "gap_um": args.gap}
    if args.curvature != "plane":
        contact["curvature"] = args.curvature
    print(f"{args.shape} pillars 40 µm, periods 80 µm (G = 40 µm), depth {args.depth:g} µm, "
          f"dx = 2 µm; effects {effects or 'none'}; contact {contact or 'chi 1.1'}")  # fmt: skip
    for eps in args.shifts:
        fr = []
        with tempfile.TemporaryDirectory() as tmp:
            for a in radii:
                cfg = parse_config({
                    "flow": {"dx": 2.0, "array": {"pillar_shape": args.shape, "shift": eps,
                                                  "depth": args.depth}},
                    "fiber": {"bead_radius": a, "array_rows": args.rows, "effects": effects,
                              "contact": contact},
                    "sweep": {"length": [2 * a], "theta0": [-10.0, 10.0], "y0": [0.0, 1.0],
                              "random": {"count": args.starts, "seed": 0}},
                    "run": {"output": f"{tmp}/a{a:g}", "cache_dir": ".fibersweep-cache",
                            "workers": args.workers},
                })  # fmt: skip
                run_sweep(cfg)
                df = read_runs(cfg.run.output)
                fr.append(float(df["fraction"].mean()))
        d = 2 * np.array(radii)
        f = np.array(fr) - 0.5
        k = np.flatnonzero((f[:-1] < 0) & (f[1:] >= 0))
        dc = float(d[k[0]] - f[k[0]] * (d[k[0] + 1] - d[k[0]]) / (f[k[0] + 1] - f[k[0]])) if \
            k.size else float("nan")  # fmt: skip
        davis = 1.4 * 40.0 * eps**0.48
        print(
            f"eps = {eps:g}: mean fraction by D [µm]: "
            + ", ".join(f"{di:g}:{fi:.2f}" for di, fi in zip(d, fr, strict=True))
        )
        print(
            f"  D_c (model) = {dc:.1f} µm; Davis 1.4 G eps^0.48 = {davis:.1f} µm; "
            f"ratio {dc / davis:.2f}"
        )
        if args.steric:
            beta, gap = first_streamline_width(cfg.flow.array.to_array(), solve_cell(cfg.flow).u,
                                               cfg.flow.dx)  # fmt: skip
            parab = brentq(lambda b, e=eps: b * b * (3 - 2 * b) - e, 0.0, 1.0) * gap
            print(f"  steric 2β: simulated gap profile {2 * beta:.1f} µm, "
                  f"parabolic {2 * parab:.1f} µm (G = {gap:g} µm)")  # fmt: skip


if __name__ == "__main__":
    main()
