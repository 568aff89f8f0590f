"""The ``faxen`` term beside a circle pillar of the DLD array: u and (a²/6)∇²u around it.

Reads the ε = 0.1 circle-array cell field (dx = 2 µm; array_dc.py's) and its in-plane
Laplacian as the ``faxen`` effect reads them (the padded cell, the field's lattice
Laplacian, the IB interpolation) at bead centres ``--gap`` µm beyond contact with the
pillar's outline, at angles from +x round the pillar; prints the flow, the Faxén term
and their components normal to the pillar (negative: towards it).

    python3 scripts/studies/arrays/faxen_push.py [--radii 6 8] [--gap 0.9]
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from fibersweep.config.flow import FlowSettings
from fibersweep.fiber.effects.faxen import lattice_laplacian
from fibersweep.fiber.rows import PAD
from fibersweep.flow.cache import get_flow_field
from fibersweep.flow.field import interpolate_ib


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--radii", type=float, nargs="+", default=[6.0, 8.0])
    ap.add_argument("--gap", type=float, default=0.9)
    ap.add_argument("--shift", type=float, default=0.1)
    ap.add_argument("--cache", default=".fibersweep-cache")
    args = ap.parse_args()
    fs = FlowSettings.model_validate(
        {"dx": 2.0, "array": {"pillar_shape": "circle", "shift": args.shift}}
    )
    cell, _ = get_flow_field(fs, args.cache)
    ux, uy = cell.extended(PAD)
    lx, ly = lattice_laplacian(ux, uy, cell.dx)
    x0, y0, x1, y1 = cell.array.shape.bounds
    cx, cy, r = 0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * (x1 - x0)
    off = PAD * cell.dx
    for a in args.radii:
        d = r + a + args.gap
        print(f"a = {a:g} µm, centre {args.gap:g} µm beyond contact (angle from +x)")
        for ang in (180, 150, 120, 90, 60):
            t = math.radians(ang)
            px = np.array([cx + d * math.cos(t) + off])
            py = np.array([cy + d * math.sin(t) + off])
            u = np.zeros((1, 2))
            lap = np.zeros((1, 2))
            interpolate_ib(ux, uy, cell.dx, px, py, u)
            interpolate_ib(lx, ly, cell.dx, px, py, lap)
            n = np.array([math.cos(t), math.sin(t)])
            f = a * a / 6.0 * lap[0]
            print(f"  {ang:4d}°: u {u[0].round(1)}  faxen {f.round(1)}  "
                  f"u_n {u[0] @ n:7.1f}  faxen_n {f @ n:7.1f} µm/s")  # fmt: skip


if __name__ == "__main__":
    main()
