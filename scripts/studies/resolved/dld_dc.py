"""Critical diameter D_c of a resolved sphere in the circle array by bisection on bump/zigzag.

The unit cell of docs/validation/near-wall.md (circle pillars 40 µm, periods 80 µm,
G = H = 40 µm) with row shift ε, solved on the resolved lattice
(:mod:`fibersweep.resolved.dld`); a sphere starts on a pillar's apex and bumps if it
passes above the next ``--passes`` pillars. Prints every decision and the bracket.

    python3 scripts/studies/resolved/dld_dc.py --shift 0.1 --lo 8 --hi 20 [--dx 2] [--tau 1.5]
        [--reynolds 0.2] [--tol 1] [--only D ...] [--threads N]

``--only`` runs the listed diameters without bisection (the Reynolds check).
"""

from __future__ import annotations

import argparse
import logging

from fibersweep.resolved.dld import CellSettings, critical_diameter, decide


def row(d) -> str:
    return (f"| {d.diameter:6.2f} | {'bump' if d.bumps else 'zigzag':6s} | "
            + ", ".join(f"{o:+.2f}" for o in d.offsets)
            + f" | {d.min_gap:.2f} | {d.reynolds:.3g} | {d.steps} | {d.seconds:.0f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--shift", type=float, required=True)
    ap.add_argument("--dx", type=float, default=2.0)
    ap.add_argument("--tau", type=float, default=1.5)
    ap.add_argument("--reynolds", type=float, default=0.2)
    ap.add_argument("--passes", type=int, default=2)
    ap.add_argument("--lo", type=float, default=8.0)
    ap.add_argument("--hi", type=float, default=28.0)
    ap.add_argument("--tol", type=float, default=1.0)
    ap.add_argument("--only", type=float, nargs="*")
    ap.add_argument("-v", "--verbose", action="store_true", help="log progress every 5000 steps")
    ap.add_argument("--cache", default=".fibersweep-cache/resolved",
                    help="folder that keeps the solved empty cell between runs")
    ap.add_argument("--threads", type=int, default=None,
                    help="threads of the lattice kernels (default: one below 200 000 nodes)")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)
    logging.getLogger("fibersweep.resolved.dld").setLevel(
        logging.DEBUG if args.verbose else logging.INFO)  # fmt: skip
    cs = CellSettings(shift=args.shift, dx=args.dx, tau=args.tau, reynolds=args.reynolds,
                      passes=args.passes, threads=args.threads,
                      cache_dir=args.cache)
    print(f"eps = {cs.shift}, dx = {cs.dx} µm, tau = {cs.tau}, Re_p = {cs.reynolds}, "
          f"contact gap {cs.contact_gap * cs.dx:g} µm, passes {cs.passes}")
    print("| D [µm] | outcome | height above next pillars [µm] | least gap [µm] | Re_p "
          "| steps | s |")
    print("|---|---|---|---|---|---|---|")
    if args.only:
        for dia in args.only:
            print(row(decide(cs, dia)), flush=True)
        return
    lo, hi, done = critical_diameter(cs, args.lo, args.hi, args.tol)
    for d in done:
        print(row(d))
    davis = 1.4 * 40.0 * cs.shift**0.48
    print(f"D_c in [{lo:.2f}, {hi:.2f}] µm, midpoint {0.5 * (lo + hi):.2f} µm; "
          f"Davis 1.4 G eps^0.48 = {davis:.1f} µm")


if __name__ == "__main__":
    main()
