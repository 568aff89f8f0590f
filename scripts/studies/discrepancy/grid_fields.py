"""How another flow grid's field differs from the study field: a speed, and a shape.

For each ``--dx``, the field of the SPEC channel on that grid is sampled with the
study field (dx = 4 µm) on a regular set of points (every 5 µm in x over 100-2300 µm
and in y over 10-790 µm; points where either field is solid left out). Printed per
grid: the mean streamwise speed of both, the least-squares factor ``a`` that scales
the study field onto the other (what a faster or slower inlet can absorb), the
relative difference ``|u - u4| / |u4|`` before and after that scaling (after: the
part no speed change can absorb), and where the scaled difference is largest.

    python scripts/studies/discrepancy/grid_fields.py --dx 2 5 [--cache DIR]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from common import DEFAULT_CACHE, STUDY_FLOW, study_field  # noqa: E402

from fibersweep.config.flow import FlowSettings  # noqa: E402
from fibersweep.flow.cache import get_flow_field  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, nargs="+", default=[2.0, 5.0], help="grids [µm]")
    ap.add_argument("--cache", default=DEFAULT_CACHE)
    a = ap.parse_args(argv)
    ref = study_field(a.cache)
    x, y = np.meshgrid(np.arange(100.0, 2300.0 + 1e-9, 5.0), np.arange(10.0, 790.0 + 1e-9, 5.0))
    pts = np.column_stack([x.ravel(), y.ravel()])
    u4 = np.asarray(ref.velocity(pts))
    fields = {dx: get_flow_field(FlowSettings(dx=dx), a.cache)[0] for dx in a.dx}
    us = {dx: np.asarray(f.velocity(pts)) for dx, f in fields.items()}
    # solid in any field: zero velocity there
    fluid = np.all([np.linalg.norm(u, axis=1) > 1e-9 for u in [u4, *us.values()]], axis=0)
    r = u4[fluid]
    print(f"study field dx = {STUDY_FLOW.dx:g} µm: mean u_x {r[:, 0].mean():.1f} µm/s "
          f"over {fluid.sum()} fluid points")  # fmt: skip
    for dx, u in us.items():
        v = u[fluid]
        scale = float((v * r).sum() / (r * r).sum())
        left = v - scale * r
        norm = float(np.linalg.norm(r))
        worst = pts[fluid][np.argmax(np.linalg.norm(left, axis=1))]
        print(
            f"dx = {dx:g} µm: mean u_x {v[:, 0].mean():.1f} µm/s; scale a = {scale:.4f}; "
            f"|u - u4|/|u4| = {np.linalg.norm(v - r) / norm:.4f}, after scaling "
            f"{np.linalg.norm(left) / norm:.4f}; largest scaled difference "
            f"{np.linalg.norm(left, axis=1).max():.0f} µm/s at x = {worst[0]:.0f}, "
            f"y = {worst[1]:.0f} µm"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
