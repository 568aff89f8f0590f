"""Grid convergence of the resolved particle against published Stokes-flow results.

Cases (each at the radii given, the box scaled with the radius):

* ``array``: fixed sphere in a periodic cube of side 4a (φ = 0.0654), drag factor K
  against Zick & Homsy / Sangani & Acrivos;
* ``slit``: sphere translating on the midplane of a slit of gap 4a (a/l = 0.5),
  box 8a wide, against Faxén's midplane law;
* ``wall``: sphere moving towards a plane wall at h = 2a, box 8a wide and 12a high,
  against Brenner's series with the far wall superposed, λ_B(h) + λ_B(H − h) − 1;
* ``spin``: torque-free sphere in simple shear between plates 6a apart, box 6a
  wide: spin/γ̇ against ½ (Jeffery's r_e = 1: period 4π/γ̇);
* ``rod``: torque-free spins of a capsule (radius a, straight half-length a) along
  and across the flow, box 12a wide, plates 12a apart: r_e and γ̇T/2π
  (Jeffery, Bretherton), beside Cox's (1971) slender-body r_e = 1.24 r/√(ln r)
  (r = 2 is outside its range; printed for orientation only).

    python3 scripts/studies/resolved/validation.py array --radii 4 6 8 [--tau 1.0]
"""

from __future__ import annotations

import argparse
import math

from fibersweep.resolved.cases import (
    array_drag,
    brenner_normal,
    jeffery_period,
    shear_spin,
    slit_drag,
    wall_drag,
)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("case", choices=["array", "slit", "wall", "spin", "rod"])
    ap.add_argument("--radii", type=float, nargs="+", default=[4.0, 6.0, 8.0])
    ap.add_argument("--tau", type=float, default=1.0)
    ap.add_argument("--width", type=float, default=None, help="box width in radii")
    args = ap.parse_args()
    print(f"case {args.case}, tau = {args.tau}")
    print("| a [lu] | box | result | reference | error | steps | s |")
    print("|---|---|---|---|---|---|---|")
    for a in args.radii:
        if args.case == "array":
            r = array_drag(a, int(round(4 * a)), args.tau)
            box, val, ref, steps, secs = r.detail["box"], r.value, r.reference, r.steps, r.seconds
        elif args.case == "slit":
            w = int(round((args.width or 8) * a))
            r = slit_drag(a, int(round(4 * a)), w, args.tau)
            box, val, ref, steps, secs = f"{w}²×{int(4 * a)}", r.value, r.reference, r.steps, \
                r.seconds
        elif args.case == "wall":
            w, hgt = int(round((args.width or 8) * a)), int(round(12 * a))
            r = wall_drag(a, 2 * a, w, hgt, args.tau)
            ref = brenner_normal(2.0) + brenner_normal((hgt - 2 * a) / a) - 1.0
            box, val, steps, secs = f"{w}²×{hgt}", r.value, r.steps, r.seconds
        elif args.case == "spin":
            n = int(round((args.width or 6) * a))
            val, steps, secs = shear_spin(a, 0.0, 0.0, n, n, args.tau)
            val, ref, box = abs(val), 0.5, f"{n}³"
        else:
            n = int(round((args.width or 12) * a))
            period, r_e, steps, secs = jeffery_period(a, a, n, n, args.tau)
            r = 2.0
            cox = 1.24 * r / math.sqrt(math.log(r))
            print(f"| {a:g} | {n}³ | r_e {r_e:.4f}, γ̇T/2π {period:.4f} | Cox r_e {cox:.3f}, "
                  f"γ̇T/2π {cox + 1 / cox:.3f} | {period / (cox + 1 / cox) - 1:+.4f} | {steps} "
                  f"| {secs:.0f} |", flush=True)
            continue
        print(f"| {a:g} | {box} | {val:.4f} | {ref:.4f} | {val / ref - 1:+.4f} | {steps} "
              f"| {secs:.0f} |", flush=True)


if __name__ == "__main__":
    main()
