"""The elasto-viscous number μ̄ of every stiffness and length a config sweeps.

For each setting combination of CONFIG (with KEY=VALUE overrides) and each length of
its sweep, μ̄ = 8πμγ̇L⁴/(Bc) with γ̇ = U_center / (pillar size)
(:mod:`fibersweep.fiber.models.elastoviscous`), printed as a Markdown table: one row per
Young's modulus, one column per length. Lengths are µm in a pillar array and l_obs
in a channel (converted to µm here).

    python3 scripts/studies/flexible/elastoviscous.py configs/array-flexible.yaml
    python3 scripts/studies/flexible/elastoviscous.py configs/quick.yaml \
        'sweep.fiber.young_modulus=[26e6, 1e6, 1e5]' 'sweep.length=[0.6, 1.2]'
"""

from __future__ import annotations

import argparse

from fibersweep.config import axis_values, load_config
from fibersweep.fiber.models.elastoviscous import elastoviscous_number, pillar_shear_rate


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("config")
    ap.add_argument("overrides", nargs="*", help="KEY=VALUE")
    args = ap.parse_args()
    cfg = load_config(args.config, args.overrides)
    lengths = [float(v) for v in axis_values(cfg.sweep.length)]
    rows = {}
    for combo in cfg.combinations():
        c = combo.config
        rate = pillar_shear_rate(c.flow)
        if c.flow.array is None:
            l_obs = c.flow.geometry.to_geometry().pillar_base_length
            lengths_um = [L * l_obs for L in lengths]
        else:
            lengths_um = lengths
        mu = c.flow.fluid.viscosity
        E, a = c.fiber.young_modulus, c.fiber.bead_radius
        rows[E] = (rate, [elastoviscous_number(mu, rate, L, E, a) for L in lengths_um])
    unit = "µm" if cfg.flow.array is not None else "l_obs"
    rate = next(iter(rows.values()))[0]
    print(f"{args.config}: μ = {cfg.flow.fluid.viscosity} Pa s, γ̇ = U_center / pillar size "
          f"= {rate:g} 1/s, a = {cfg.fiber.bead_radius} µm")  # fmt: skip
    print("\n| E [Pa] | " + " | ".join(f"L = {L:g} {unit}" for L in lengths) + " |")
    print("|---|" + "---|" * len(lengths))
    for E, (_, values) in sorted(rows.items(), reverse=True):
        print(f"| {E:.3g} | " + " | ".join(f"{v:.3g}" for v in values) + " |")


if __name__ == "__main__":
    main()
