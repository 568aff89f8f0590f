"""Step-by-step trace of one resolved sphere in the circle array's cell (the set-up of a decision).

Prints every ``--every`` steps the centre (lattice units), the velocity over the gap
speed u_g, the hydrodynamic force of the step, the spin, the surface gap to the
nearest pillar and its normal: where a sphere slides, creeps or is pinned at contact.

    python3 scripts/studies/resolved/trace.py --shift 0.1 --diameter 11 --reynolds 0.1
        --steps 14000 --every 500
"""

from __future__ import annotations

import argparse

import numpy as np

from fibersweep.resolved.dld import CellSettings, _box, _contact, _nearest_pillar, empty_cell
from fibersweep.resolved.particle import Body, BodyState
from fibersweep.resolved.run import Coupled


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--shift", type=float, required=True)
    ap.add_argument("--diameter", type=float, required=True)
    ap.add_argument("--reynolds", type=float, default=0.2)
    ap.add_argument("--dx", type=float, default=2.0)
    ap.add_argument("--tau", type=float, default=1.5)
    ap.add_argument("--steps", type=int, default=14000)
    ap.add_argument("--every", type=int, default=500)
    ap.add_argument("--cache", default=".fibersweep-cache/resolved")
    args = ap.parse_args()
    cs = CellSettings(shift=args.shift, dx=args.dx, tau=args.tau, reynolds=args.reynolds,
                      cache_dir=args.cache)  # fmt: skip
    radius = args.diameter / 2.0 / cs.dx
    lat, u_gap = empty_cell(cs, radius)
    box, shape, _ = _box(cs)
    start = np.array([shape.cx, shape.cy + shape.radius + radius + cs.start_gap, box.nz])
    act, keep = _contact(cs, shape, box, radius, lat.fluid, [])
    run = Coupled(lat, Body(radius), BodyState(start), motion="planar", external=act,
                  constrain=keep)  # fmt: skip
    print(f"D = {args.diameter} µm, Re_p = {cs.reynolds}, u_g = {u_gap:.4g} (lattice units)")
    print("| step | x | y | u/u_g | v/u_g | F_x | F_y | ω_z | gap | normal |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for k in range(1, args.steps + 1):
        f, _ = run.step()
        if k % args.every == 0:
            st = run.state
            h, n = _nearest_pillar(shape, box, st.x, radius)
            print(f"| {k} | {st.x[0]:.3f} | {st.x[1]:.3f} | {st.u[0] / u_gap:+.4f} | "
                  f"{st.u[1] / u_gap:+.4f} | {f[0]:+.3e} | {f[1]:+.3e} | {st.w[2]:+.2e} | "
                  f"{h:.3f} | ({n[0]:+.3f}, {n[1]:+.3f}) |", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
