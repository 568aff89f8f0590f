"""Fine patch against the single fine grid: separatrix, peak speed, midplane L2 near the pillar.

Solves the channel once at ``--channel-dx``, nests patches of several margins at
``--patch-dx`` in it, and compares each (and the channel field alone) with the
whole channel solved at ``--patch-dx`` (read from / stored in ``--cache``).
Prints one table row per field; ``--json`` writes the rows.

Example (the reduced channel of docs/validation/flow.md, 'Fine patch')::

    python3 scripts/studies/flow/patch_study.py --width 400 --length 800 --margins 20 40 80 160
"""

from __future__ import annotations

import argparse
import json
import logging
import time

import numpy as np

from fibersweep.config.flow import FlowSettings
from fibersweep.flow.cache import get_flow_field
from fibersweep.flow.lbm import solve_nested
from fibersweep.flow.patch import solve_patched
from fibersweep.flow.solver import field_from_solution
from fibersweep.flow.streamlines import separatrix_y


def near_mask(field, reach: float) -> np.ndarray:
    """Fluid nodes within ``reach`` µm of the pillar's bounding box, shape (nx, ny)."""
    x0, y0, x1, y1 = field.geometry.shape.bounds
    X, Y = np.meshgrid(field.x_nodes, field.y_nodes, indexing="ij")
    box = (X > x0 - reach) & (X < x1 + reach) & (Y > y0 - reach) & (Y < y1 + reach)
    return box & ~field.solid


def compare(field, ref, mask: np.ndarray) -> dict:
    """Separatrix, peak speed near the pillar and relative midplane L2 against ``ref``."""
    if abs(field.dx - ref.dx) < 1e-12:  # same nodes: compare nodal values
        u = np.column_stack([field.ux[mask], field.uy[mask]])
    else:  # the channel field alone: its interpolation (IB kernel) at the fine nodes
        X, Y = np.meshgrid(ref.x_nodes, ref.y_nodes, indexing="ij")
        u = field.velocity(np.column_stack([X[mask], Y[mask]]))
    r = np.column_stack([ref.ux[mask], ref.uy[mask]])
    return {
        "separatrix": separatrix_y(field),
        "peak_speed": float(np.max(np.hypot(u[:, 0], u[:, 1]))),
        "l2_rel": float(np.linalg.norm(u - r) / np.linalg.norm(r)),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--width", type=float, default=400.0, help="channel width [µm]")
    ap.add_argument("--length", type=float, default=800.0, help="channel length [µm]")
    ap.add_argument("--channel-dx", type=float, default=4.0)
    ap.add_argument("--patch-dx", type=float, default=2.0)
    ap.add_argument("--margins", type=float, nargs="+", default=[20.0, 40.0, 80.0, 160.0])
    ap.add_argument("--reach", type=float, default=40.0, help="L2 region around the pillar [µm]")
    ap.add_argument("--cache", default="/work/testcache", help="flow cache for the fine field")
    ap.add_argument("--json", default=None, help="write the rows here")
    ap.add_argument("--save", default=None, help="write the fields to this .npz")
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")
    geo = {"width": args.width, "length": args.length}
    channel = FlowSettings.model_validate({"geometry": geo, "dx": args.channel_dx})
    t0 = time.perf_counter()
    coarse = solve_nested(channel)
    coarse_field = field_from_solution(channel, coarse)
    t_channel = time.perf_counter() - t0
    patched = {}
    for m in args.margins:
        s = FlowSettings.model_validate(
            {"geometry": geo, "dx": args.channel_dx, "patch": {"dx": args.patch_dx, "margin": m}}
        )
        t0 = time.perf_counter()
        patched[m] = (solve_patched(s, coarse=coarse), time.perf_counter() - t0)
    fine_settings = FlowSettings.model_validate({"geometry": geo, "dx": args.patch_dx})
    t0 = time.perf_counter()
    ref, info = get_flow_field(fine_settings, args.cache)
    t_ref = time.perf_counter() - t0
    mask = near_mask(ref, args.reach)
    rows = [{"field": f"channel dx={args.channel_dx:g}", "seconds": t_channel,
             **compare(coarse_field, ref, mask)}]  # fmt: skip
    for m, (f, sec) in patched.items():
        nodes = f.meta["patch"]["nodes"]
        rows.append({"field": f"patch margin={m:g} ({nodes[0]}x{nodes[1]}x{nodes[2]})",
                     "seconds": sec, **compare(f, ref, mask)})  # fmt: skip
    rows.append({"field": f"whole channel dx={args.patch_dx:g}" + (" (cached)" if info.hit else ""),
                 "seconds": t_ref, **compare(ref, ref, mask)})  # fmt: skip
    print(f"{'field':<36} {'separatrix':>10} {'d_sep':>8} {'peak um/s':>10} {'L2 rel':>9} {'s':>7}")
    s_ref, p_ref = rows[-1]["separatrix"], rows[-1]["peak_speed"]
    for r in rows:
        print(
            f"{r['field']:<36} {r['separatrix']:10.4f} {r['separatrix'] - s_ref:+8.4f} "
            f"{r['peak_speed']:10.2f} {r['l2_rel']:9.2e} {r['seconds']:7.1f}"
        )
    print(f"peak speed of the fine field {p_ref:.2f} um/s; L2 over {int(mask.sum())} fluid nodes "
          f"within {args.reach:g} um of the pillar's bounding box")  # fmt: skip
    if args.save:
        arrays = {f"m{m:g}_{c}": getattr(f, "u" + c) for m, (f, _) in patched.items() for c in "xy"}
        np.savez(args.save, ref_ux=ref.ux, ref_uy=ref.uy, **arrays)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
