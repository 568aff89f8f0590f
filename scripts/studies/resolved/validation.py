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
* ``rod``: torque-free spins of a capsule (radius a, straight half-length a, length
  4a: aspect ratio r = 2) along and across the flow, box 12a wide, plates 12a apart:
  r_e and γ̇T/2π (Jeffery, Bretherton), beside a spheroid of the same r (r_e = 2,
  γ̇T/2π = 2.5) and Cox's (1971) slender-body r_e = 1.24 r/√(ln r) (r = 2 is outside
  its range; printed for orientation only); and the spin at 45° to the flow, which
  Jeffery's orbit puts at γ̇/2 for any r_e.

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
            # Jeffery's orbit for any axisymmetric body: ω(φ) = γ̇ (r_e² sin²φ + cos²φ)/(r_e² + 1),
            # so at 45° the spin is γ̇/2 whatever r_e: a check of the orbit's form itself
            w45, s45, t45 = shear_spin(a, a, 45.0, n, n, args.tau)
            r = 2.0
            cox = 1.24 * r / math.sqrt(math.log(r))
            print(f"| {a:g} | {n}³ | r_e {r_e:.4f}, γ̇T/2π {period:.4f}; ω(45°)/γ̇ {abs(w45):.4f} "
                  f"| spheroid r = 2: γ̇T/2π 2.5; Jeffery ω(45°)/γ̇ 0.5; Cox r_e {cox:.3f} "
                  f"| T {period / 2.5 - 1:+.4f}; ω(45°) {abs(w45) / 0.5 - 1:+.4f} "
                  f"| {steps + s45} | {secs + t45:.0f} |", flush=True)
            continue
        print(f"| {a:g} | {box} | {val:.4f} | {ref:.4f} | {val / ref - 1:+.4f} | {steps} "
              f"| {secs:.0f} |", flush=True)


if __name__ == "__main__":
    main()
