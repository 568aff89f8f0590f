"""The source's worked examples and trapping rows with the near-contact physics (a prediction).

Rigid fibers with the paper's settings (configs/paper.yaml: rough pillar) on the
channel field (dx = 4 µm), with ``near_wall`` = 1, ``faxen`` = 1, the gap contact law
(``--gap`` δ_r µm), the local curvature (``fiber.contact.curvature: local``) and corner
radius ``--corner`` r_c µm; and the same without any of it. Prints each worked
example's class, δ at its quoted start, and the classes over y0/h_obs rows at
θ0 = 8°, L = 0.75 l_obs (the second example's trapping rows). Nothing here is fitted:
δ_r comes from the array calibration (array_dc.py).

    python3 scripts/studies/arrays/near_contact_examples.py --gap 0.3 [--corner 1.0]
"""

from __future__ import annotations

import argparse
import logging

from fibersweep.config.fiber import FiberSettings
from fibersweep.config.loading import load_config
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.flow.cache import get_flow_field

EXAMPLES = ((-3.7, 0.373, 0.82), (8.0, 0.351, 0.75))  # the source's (θ0, y0/h, L/l_obs)
SHORT = {"Above": "A", "Below": "B", "Trapping": "T", "Pole-vaulting": "PV"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--gap", type=float, required=True, help="delta_r [µm]")
    ap.add_argument("--corner", type=float, default=1.0, help="r_c [µm]")
    ap.add_argument("--y0", type=float, nargs="+",
                    default=[round(0.29 + 0.01 * i, 2) for i in range(9)])  # fmt: skip
    ap.add_argument("--config", default="configs/paper.yaml")
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--only-on", action="store_true", help="skip the runs without the physics")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)
    cfg = load_config(args.config)
    field, _ = get_flow_field(cfg.flow.model_copy(update={"dx": 4.0}), args.cache)
    base = cfg.fiber
    data = base.model_dump()
    data["contact"] = {**data["contact"], "law": "gap", "gap_um": args.gap,
                       "curvature": "local", "corner_radius": args.corner}  # fmt: skip
    data["effects"] = {**base.effects, "near_wall": 1.0, "faxen": 1.0}
    on = FiberSettings.model_validate(data)
    sets = [("near-contact", on)] if args.only_on else [("none", base), ("near-contact", on)]
    print(f"config {args.config}, dx 4 µm; near-contact: near_wall 1, faxen 1, gap "
          f"{args.gap:g} µm, curvature local, r_c {args.corner:g} µm")  # fmt: skip
    for name, st in sets:
        for th, y0, length in EXAMPLES:
            r = simulate(field, st, FiberStart(th, y0, length))
            print(f"{name:13s} example (θ0 {th:g}°, y0 {y0:g}, L {length:g}): {r.cls} "
                  f"δ {r.delta:.3f} contact {r.contact}", flush=True)  # fmt: skip
        row = []
        for y0 in args.y0:
            r = simulate(field, st, FiberStart(8.0, y0, 0.75))
            row.append(f"{y0:.2f}:{SHORT.get(r.cls, r.cls)}")
        print(f"{name:13s} θ0 8°, L 0.75 rows: " + " ".join(row), flush=True)


if __name__ == "__main__":
    main()
