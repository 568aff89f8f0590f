"""Where the source's two worked examples change class, on the model's field and its candidates.

For each start of the source's worked examples (θ0, L) it runs y0/h_obs over
``--y0`` (paper.yaml's fiber settings) and prints the class per y0, on:

* ``model``: the dx = 2 µm patch in the dx = 4 µm channel (TRT, sub-grid pillar);
* ``source``: the same with the source's lattice (BGK τ = 1, staircase pillar);
* ``source+plain``: that field as the plain forcing term reports it (ux − f/2);
* ``model+hydro``: the model's field with the pillar's hydrodynamic drag on the
  fiber (``fiber.effects.pillar_hydro`` = ``--hydro``, the source's ~10 % slowing);
* ``model+disk``: the model's field averaged over the bead's cross-section
  (``--thickness``; solves the patch again for its 3D field).

Fields come from ``--cache`` (scripts/offset_study.py stores them there).

Usage: python3 scripts/offset_band.py [--y0 0.30 0.31 ...] [--hydro 0.4] [--thickness]
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

from fibersweep.config.loading import load_config
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.flow.cache import get_flow_field

sys.path.insert(0, str(Path(__file__).resolve().parent))
from offset_study import EXAMPLES, plain_forcing, settings_of, thickness_fields  # noqa: E402

SHORT = {"Above": "A", "Below": "B", "Trapping": "T", "Pole-vaulting": "PV"}


def band(field, fiber, theta0: float, length: float, y0s: list[float]) -> str:
    out = []
    for y0 in y0s:
        r = simulate(field, fiber, FiberStart(theta0, y0, length))
        out.append(SHORT.get(r.cls, r.cls) if r.status == "ok" else "fail")
    return " ".join(f"{c:>2}" for c in out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    default_y0 = [round(0.29 + 0.01 * i, 2) for i in range(10)]
    ap.add_argument("--y0", type=float, nargs="+", default=default_y0)
    ap.add_argument("--hydro", type=float, default=0.4)
    ap.add_argument("--thickness", action="store_true")
    ap.add_argument("--config", default="configs/paper.yaml")
    ap.add_argument("--cache", default=".fibersweep-cache/patch")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)
    fiber = load_config(args.config).fiber
    hydro = load_config(args.config, [f"fiber.effects.pillar_hydro={args.hydro}"]).fiber
    model, _ = get_flow_field(settings_of(), args.cache)
    src = {"collision": "bgk", "tau": 1.0, "pillar_boundary": "staircase"}
    source, _ = get_flow_field(settings_of(**src), args.cache)
    cases = [("model", model, fiber), ("source", source, fiber),
             ("source+plain", plain_forcing(source), fiber),
             (f"model+hydro {args.hydro:g}", model, hydro)]  # fmt: skip
    if args.thickness:
        disk = [f for n, f in thickness_fields(settings_of(), 2.0).items() if n.startswith("disk")]
        cases.append(("model+disk a=2", disk[0], fiber))
    head = " ".join(f"{y:>4.2f}"[1:] for y in args.y0)
    for theta0, y0q, length in EXAMPLES:
        print(f"theta0 = {theta0:g} deg, L = {length:g} l_obs (source's start y0 = {y0q}); "
              f"class by y0/h:")  # fmt: skip
        print(f"  {'field':<18} {head}")
        for name, field, fs in cases:
            print(f"  {name:<18} {band(field, fs, theta0, length, args.y0)}", flush=True)


if __name__ == "__main__":
    main()
