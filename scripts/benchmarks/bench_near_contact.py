"""Cost of the near-contact physics: rigid runs with all of it on against none, in one process.

    python3 scripts/benchmarks/bench_near_contact.py [--cache DIR] [--rounds 5] [--repeat 3]
        [--gap 0.3] [--corner 1.0] [--flexible]

"All on" is ``near_wall`` = 1, ``faxen`` = 1, the gap contact law (``--gap`` µm) and the
local curvature (``fiber.contact.curvature: local``, ``corner_radius`` ``--corner`` µm);
"off" the defaults. Cases as ``bench_near_wall.py``: the channel's rigid fiber
(dx = 4 µm, L = l_obs, 22 beads) without contact and with contact at the apex, and a
sphere (a = 6 µm) through 20 rows of the circle array at ε = 0.1. On and off alternate
``--rounds`` times, each round the minimum of ``--repeat`` runs; CPU time of the
process; printed: medians, the ratio per run and per step. ``--flexible`` also times one
bead-spring run (ros2) through 20 rows of ``configs/array-flexible.yaml``'s array at
b = a/2 (``bead_spacing`` 0.5, E = 100 kPa, L = 80 µm; effects cannot act on a finer
chain, so it runs with the gap law only), against the 10 s target.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from fibersweep.config.fiber import FiberSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.flow.cache import get_flow_field

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_near_wall import best, cases, compare  # noqa: E402  (the same cases and timing)

SMOKE = ["--rounds", "1", "--repeat", "1", "--cache", "{cache}"]


def _all_on(base: FiberSettings, gap: float, corner: float) -> FiberSettings:
    contact = base.contact.model_copy(
        update={"law": "gap", "gap_um": gap, "curvature": "local", "corner_radius": corner}
    )
    return FiberSettings.model_validate(
        {
            **base.model_dump(),
            "contact": contact.model_dump(),
            "effects": {"near_wall": 1.0, "faxen": 1.0},
        }
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--gap", type=float, default=0.3, help="gap law range delta_r [µm]")
    ap.add_argument("--corner", type=float, default=1.0, help="corner radius r_c [µm]")
    ap.add_argument("--flexible", action="store_true", help="also the flexible 20-row run")
    args = ap.parse_args()
    print(f"all on (near_wall 1, faxen 1, gap {args.gap:g} µm, curvature local, r_c "
          f"{args.corner:g} µm) against off; {args.rounds} rounds alternating, each the minimum "
          f"of {args.repeat} runs; medians over rounds")  # fmt: skip
    for label, field, off, start in cases(args.cache):
        compare(label, field, off, _all_on(off, args.gap, args.corner), start, args.rounds,
                args.repeat)  # fmt: skip
    if args.flexible:
        flow = FlowSettings.model_validate(
            {"dx": 2.0, "array": {"pillar_shape": "circle", "shift": 0.1}}
        )
        field, _ = get_flow_field(flow, args.cache)
        flex = FiberSettings.model_validate(
            {
                "model": "bead-spring",
                "integrator": "ros2",
                "young_modulus": 1.0e5,
                "bead_spacing": 0.5,
                "array_rows": 20,
                "contact": {"law": "gap", "gap_um": args.gap},
            }
        )
        start = FiberStart(0.0, 0.37, 80.0)
        simulate(field, flex, start)  # compile
        t, n = best(field, flex, start, 1)
        print(f"flexible, b = a/2, 20 rows (E 100 kPa, L 80 µm): {t:.2f} s CPU, {n} steps "
              f"(target < 10 s)", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
