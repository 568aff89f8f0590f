"""Time one fiber run (L = l_obs, start to far downstream) in both models; print the ratio.

Usage: python scripts/bench_fiber.py [--dx 4] [--cache .fibersweep-cache] [--repeat 5]

Timings on a shared machine are noisy, so the script reports the ratio of the
two models measured in the same process, after a warm-up that compiles the
Numba kernels (compilation is excluded; it is paid once per process).
"""

from __future__ import annotations

import argparse
import statistics
import time

from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.fiber.settings import FiberSettings
from fibersweep.flow.cache import get_flow_field
from fibersweep.flow.settings import FlowSettings

STARTS = {
    "no contact (theta0 = 0, y0/h = 0.8)": FiberStart(0.0, 0.8, 1.0),
    "contact at the apex (theta0 = 0, y0/h = 0.45)": FiberStart(0.0, 0.45, 1.0),
}


def _time(field, settings, start, repeat):
    out = []
    res = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = simulate(field, settings, start)
        out.append(time.perf_counter() - t0)
    return statistics.median(out), res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, default=4.0)
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--repeat", type=int, default=5, help="rigid repetitions (median)")
    args = ap.parse_args()
    field, _ = get_flow_field(FlowSettings(dx=args.dx), args.cache)
    rigid = FiberSettings()
    beads = FiberSettings(model="bead-spring")
    warm = FiberStart(0.0, 0.8, 0.5)
    simulate(field, rigid, warm)
    simulate(field, beads.model_copy(update={"x0": 1100.0}), warm)
    print(f"flow field dx = {args.dx} µm; fiber L = l_obs; Numba compiled before timing")
    for label, start in STARTS.items():
        tr, rr = _time(field, rigid, start, args.repeat)
        tb, rb = _time(field, beads, start, 1)
        print(f"\n{label}")
        print(f"  rigid       : {tr:8.3f} s  {rr.n_steps:7d} steps  class {rr.cls}  "
              f"delta {rr.delta:+.4f}")  # fmt: skip
        print(f"  bead-spring : {tb:8.3f} s  (dt = 5e-5 s)       class {rb.cls}  "
              f"delta {rb.delta:+.4f}")  # fmt: skip
        print(f"  ratio bead-spring / rigid = {tb / tr:.0f}")
        src_steps = rr.t_end / 1e-7
        print(f"  the source's scheme (dt = 1e-7 s) would need {src_steps:.1e} steps")


if __name__ == "__main__":
    main()
