"""Compare two cached unit-cell fields (``cell-<key>.npz``) of the same array.

Prints the largest difference of the midplane velocity over the peak speed, in
the whole cell and at its fluid nodes away from the pillar's ghost nodes, with
each field's solver version, steps and residual. Used to show that a change of
the cell solver moves the field by no more than its convergence tolerance.

Usage:  python scripts/compare_cells.py CELL_A.npz CELL_B.npz
"""

from __future__ import annotations

import argparse

import numpy as np

from fibersweep.flow.cell_cache import load_cell_field


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a")
    ap.add_argument("b")
    args = ap.parse_args()
    fa, fb = load_cell_field(args.a), load_cell_field(args.b)
    if fa.ux.shape != fb.ux.shape or fa.array != fb.array:
        raise SystemExit("the two fields are not of the same cell")
    for name, f in (("A", fa), ("B", fb)):
        m = f.meta
        print(f"{name}: {m['solver_version']}, {m['steps']} steps, residual {m['residual']:.2e}, "
              f"mean-flow angle {m['mean_flow_angle_deg']:.2e} deg")  # fmt: skip
    speed = np.hypot(fa.ux, fa.uy)
    peak = float(speed.max())
    d = np.hypot(fa.ux - fb.ux, fa.uy - fb.uy)
    x = (np.arange(fa.ux.shape[0]) + 0.5) * fa.dx
    y = (np.arange(fa.ux.shape[1]) + 0.5) * fa.dx
    X, Y = np.meshgrid(x, y, indexing="ij")
    fluid = ~fa.array.shape.inside(X, Y, margin=1e-9 * fa.dx)
    print(f"peak speed {peak:.6g} µm/s")
    print(f"max |u_A - u_B| / peak: {d.max() / peak:.3e} (all nodes), "
          f"{d[fluid].max() / peak:.3e} (fluid nodes)")  # fmt: skip


if __name__ == "__main__":
    main()
