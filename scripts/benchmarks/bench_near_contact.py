"""Cost of the near-contact physics: rigid runs with all of it on against none, in one process.

    python3 scripts/benchmarks/bench_near_contact.py [--cache DIR] [--rounds 5] [--repeat 3]
        [--gap 0.3] [--corner 1.0] [--flexible | --only-flexible]

"All on" is ``near_wall`` = 1, ``faxen`` = 1, the gap contact law (``--gap`` µm) and the
local curvature (``fiber.contact.curvature: local``, ``corner_radius`` ``--corner`` µm);
"off" the defaults. Cases as ``bench_near_wall.py``: the channel's rigid fiber
(dx = 4 µm, L = l_obs, 22 beads) without contact and with contact at the apex, and a
sphere (a = 6 µm) through 20 rows of the circle array at ε = 0.1. On and off alternate
``--rounds`` times, each round the minimum of ``--repeat`` runs; CPU time of the
process; printed: medians, the ratio per run and per step. ``--flexible`` also times one
bead-spring run (ros2) through 20 rows of ``configs/array-flexible.yaml`` (its triangle
array, ε = 0.1) at b = a/2 (``bead_spacing`` 0.5, E = 100 kPa, L = 80 µm, θ0 = 10°,
y0 = 0), against the 10 s target, with the gap law (``--gap``) and with the chi law. The
settings refuse every effect on a chain with b ≠ 2a (``near_wall``, ``faxen``: per-bead
forces and mobilities validated for touching beads only), and the local curvature acts
only through ``near_wall``, so of the near-contact physics only the gap law acts there.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from fibersweep.config.fiber import FiberSettings
from fibersweep.config.loading import load_config
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
    ap.add_argument("--only-flexible", action="store_true", help="the flexible run alone")
    args = ap.parse_args()
    print(f"all on (near_wall 1, faxen 1, gap {args.gap:g} µm, curvature local, r_c "
          f"{args.corner:g} µm) against off; {args.rounds} rounds alternating, each the minimum "
          f"of {args.repeat} runs; medians over rounds")  # fmt: skip
    for label, field, off, start in [] if args.only_flexible else cases(args.cache):
        compare(label, field, off, _all_on(off, args.gap, args.corner), start, args.rounds,
                args.repeat)  # fmt: skip
    if args.flexible or args.only_flexible:
        _flexible(args.cache, args.gap, args.repeat)


def _flexible(cache: str, gap: float, repeat: int) -> None:
    """Time the bead-spring run of configs/array-flexible.yaml at b = a/2, gap law and chi law."""
    cfg = load_config(Path(__file__).resolve().parents[2] / "configs" / "array-flexible.yaml")
    field, _ = get_flow_field(cfg.flow, cache)
    base = {**cfg.fiber.model_dump(), "young_modulus": 1.0e5, "bead_spacing": 0.5}
    start = FiberStart(10.0, 0.0, 80.0)
    for name, contact in (("gap", {"law": "gap", "gap_um": gap}), ("chi", {})):
        flex = FiberSettings.model_validate({**base, "contact": contact})
        res = simulate(field, flex, start)  # compile
        t, n = best(field, flex, start, repeat)
        print(f"flexible, b = a/2, 20 rows (E 100 kPa, L 80 µm, theta0 10 deg, y0 0), "
              f"{name} law: {t:.2f} s CPU, {n} steps, mode {res.mode}, fraction "
              f"{res.fraction:.3f} (target < 10 s)", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
