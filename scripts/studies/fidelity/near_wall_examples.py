"""The source's two worked examples with and without the ``near_wall`` effect.

For each worked example (θ0, L) it runs y0/h_obs over ``--y0`` with the paper's
fiber settings (configs/paper.yaml: rigid, rough pillar) on one channel field and
prints the class per y0 for each fiber setting: no effect, ``near_wall`` = 1 (the
sphere-wall theory) and ``pillar_hydro`` = ``--hydro`` (the first-reflection drag
at the source's "about 10 % slower"), then the quoted starts' class, δ and contact.

The field: the channel at ``--dx`` (default 4 µm, sub-grid pillar) or, with
``--patch``, a dx = 2 µm patch round the pillar in it (the finer field the
fidelity study uses).

Usage:
    python3 scripts/studies/fidelity/near_wall_examples.py [--dx 4] [--patch] [--cache DIR]
"""

from __future__ import annotations

import argparse
import logging

from fibersweep.config.flow import FlowSettings
from fibersweep.config.loading import load_config
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.flow.cache import get_flow_field

EXAMPLES = ((-3.7, 0.373, 0.82), (8.0, 0.351, 0.75))  # the source's (θ0, y0/h, L/l_obs)
SHORT = {"Above": "A", "Below": "B", "Trapping": "T", "Pole-vaulting": "PV"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--y0", type=float, nargs="+",
                    default=[round(0.29 + 0.01 * i, 2) for i in range(13)])  # fmt: skip
    ap.add_argument("--dx", type=float, default=4.0)
    ap.add_argument("--patch", action="store_true", help="a dx = 2 µm patch round the pillar")
    ap.add_argument("--hydro", type=float, default=0.4)
    ap.add_argument("--config", default="configs/paper.yaml")
    ap.add_argument("--cache", default=".fibersweep-cache")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)
    flow = {"dx": args.dx, **({"patch": {"dx": 2.0}} if args.patch else {})}
    field, _ = get_flow_field(FlowSettings.model_validate(flow), args.cache)
    cases = {
        "none": load_config(args.config).fiber,
        "near_wall 1": load_config(args.config, ["fiber.effects.near_wall=1"]).fiber,
        f"pillar_hydro {args.hydro:g}": load_config(
            args.config, [f"fiber.effects.pillar_hydro={args.hydro}"]
        ).fiber,
    }
    print(f"field: {flow}; fiber: {args.config}")
    head = " ".join(f"{y:>4.2f}"[1:] for y in args.y0)
    for theta0, y0q, length in EXAMPLES:
        print(f"\ntheta0 = {theta0:g} deg, L = {length:g} l_obs (source's y0 = {y0q}); "
              "class by y0/h:")  # fmt: skip
        print(f"  {'fiber':<18} {head}")
        for name, fs in cases.items():
            row = []
            for y0 in args.y0:
                r = simulate(field, fs, FiberStart(theta0, y0, length))
                row.append(SHORT.get(r.cls, r.cls) if r.status == "ok" else "fail")
            print(f"  {name:<18} " + " ".join(f"{c:>4}" for c in row), flush=True)
        for name, fs in cases.items():
            r = simulate(field, fs, FiberStart(theta0, y0q, length))
            print(f"  at y0 = {y0q}: {name:<18} {r.cls:<14} delta {r.delta:+.3f}  "
                  f"contact y_c {r.y_c:.2f} theta_c {r.theta_c:.0f} deg  "
                  f"t_pass {r.t_pass:.2f} s", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
