"""Patch levels in the full channel: separatrix, peak speeds, time and memory per level.

Solves (or loads from ``--cache``) the channel at ``--channel-dx`` alone and with a
patch at each of ``--patch-dx`` (default margin unless ``--margin``), in that
order, each in full (channel included, ``--force`` to re-solve cached ones), and
prints per level the traced and flux separatrix (h_obs), the peak speeds over
the apex and below the base (/ U), the wall time and the peak resident memory of
this process so far. With three levels it gives the Richardson estimate: the
observed order from the three and the extrapolated separatrix.

Example (docs/validation/flow.md, 'Fine patch')::

    python3 scripts/studies/flow/patch_levels.py --patch-dx 2 1
"""

from __future__ import annotations

import argparse
import logging
import math
import resource
import time

from fibersweep.config.flow import FlowSettings
from fibersweep.flow.analysis import flux_separatrix, peak_speeds
from fibersweep.flow.cache import get_flow_field
from fibersweep.flow.streamlines import separatrix_y


def richardson(s: list[float], ratio: float = 2.0) -> tuple[float, float]:
    """(observed order, extrapolated value) from three levels s (coarse to fine, ratio 2)."""
    d1, d2 = s[1] - s[0], s[2] - s[1]
    if d1 == 0 or d2 == 0 or d1 / d2 <= 0:
        return math.nan, math.nan
    p = math.log(d1 / d2) / math.log(ratio)
    return p, s[2] + d2 / (ratio**p - 1.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--channel-dx", type=float, default=4.0)
    ap.add_argument("--patch-dx", type=float, nargs="+", default=[2.0, 1.0])
    ap.add_argument("--margin", type=float, default=None, help="patch margin [µm]")
    ap.add_argument("--threads", type=int, default=None, help="Numba threads (default: all)")
    ap.add_argument("--cache", default=".fibersweep-cache/patch")
    ap.add_argument("--force", action="store_true", help="re-solve cached levels")
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")
    if args.threads:
        import numba

        numba.set_num_threads(args.threads)
    levels = [FlowSettings(dx=args.channel_dx)]
    for pdx in args.patch_dx:
        patch = {"dx": pdx} if args.margin is None else {"dx": pdx, "margin": args.margin}
        levels.append(FlowSettings.model_validate({"dx": args.channel_dx, "patch": patch}))
    rows = []
    for s in levels:
        t0 = time.perf_counter()
        field, info = get_flow_field(s, args.cache, force=args.force)
        sec = time.perf_counter() - t0
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2  # KiB -> GiB
        apex, base = peak_speeds(field)
        rows.append((s.field_dx, separatrix_y(field), flux_separatrix(field).y_far_over_h,
                     apex, base, sec, info.hit, rss))  # fmt: skip
    print(f"{'dx um':>6} {'traced':>8} {'flux':>8} {'apex/U':>8} {'base/U':>8} "
          f"{'s':>7} {'cached':>6} {'max RSS GiB':>11}")  # fmt: skip
    for dx, tr, fl, a, b, sec, hit, rss in rows:
        print(f"{dx:6g} {tr:8.4f} {fl:8.4f} {a:8.4f} {b:8.4f} {sec:7.1f} {hit!s:>6} {rss:11.2f}")
    if len(rows) == 3:
        for name, col in (("traced", 1), ("flux", 2)):
            p, ext = richardson([r[col] for r in rows])
            fine = rows[-1][col]
            p2 = fine + (fine - rows[-2][col]) / 3.0
            print(f"Richardson {name}: observed order {p:.2f}, extrapolated {ext:.4f} "
                  f"(p = 2: {p2:.4f}); finest level off by {abs(fine - ext):.4f}")  # fmt: skip


if __name__ == "__main__":
    main()
