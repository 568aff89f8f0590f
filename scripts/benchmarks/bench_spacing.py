"""Speed target of the finer chain: 50 beads through 20 rows in under 30 s on one core.

Usage::

    python3 scripts/benchmarks/bench_spacing.py [--cache .fibersweep-cache] [--spacings 1 0.5 0.25]
        [--moduli 1e4 3e4 1e5] [--y0 0 0.82 0.9 0.95] [--blas-threads 1]

The array of ``configs/array-flexible.yaml`` (dx = 2 µm, triangles 40 µm, periods 80 µm),
ROS2 at its default tolerance, 20 rows. For each bead spacing b/2a the fiber has 50
beads, so L = 49 b + 2a (102, 53 and 28.5 µm at b = 2a, a, a/2). Each (b, E) runs from
θ0 = 0 at each ``--y0`` (starts that touch a pillar are skipped) after one compiling
run, and prints the CPU time of every run, the largest, and the largest over the 30 s
target (below 1: met).

The kernel's W = M J product calls BLAS. A multithreaded BLAS splits that product
over threads from 2n = 100 rows up, which on a shared or fully used machine costs far
more than it gives (a 57-bead run: 1.1 s on one thread, 13–50 s with the default
threads on two busy cores). The script therefore pins BLAS to ``--blas-threads``
threads (default 1, "one core") before numpy is loaded; a sweep's workers should be
run the same way (``OPENBLAS_NUM_THREADS=1``).
"""

from __future__ import annotations

import argparse
import os
import sys


def _pin_blas(argv: list[str]) -> None:
    """Set the BLAS thread count from ``--blas-threads`` before numpy is imported."""
    n = "1"
    if "--blas-threads" in argv:
        n = argv[argv.index("--blas-threads") + 1]
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = n


_pin_blas(sys.argv)

import time  # noqa: E402

import yaml  # noqa: E402

from fibersweep.config import parse_config  # noqa: E402
from fibersweep.fiber.array_run import start_clear  # noqa: E402
from fibersweep.fiber.models.spacing import n_beads, spacing_um  # noqa: E402
from fibersweep.fiber.result import FiberStart  # noqa: E402
from fibersweep.fiber.rows import array_pillar  # noqa: E402
from fibersweep.fiber.run import simulate  # noqa: E402
from fibersweep.flow.cache import get_flow_field  # noqa: E402

TARGET_S = 30.0
N_BEADS = 50

#: a smoke pass (scripts/benchmarks/run.py --smoke): one spacing, one start, two rows
SMOKE = ["--cache", "{cache}", "--spacings", "1", "--moduli", "1e5", "--y0", "0.0",
         "--rows", "2"]  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="configs/array-flexible.yaml")
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--spacings", type=float, nargs="+", default=[1.0, 0.5, 0.25])
    ap.add_argument("--moduli", type=float, nargs="+", default=[1e4, 3e4, 1e5])
    ap.add_argument("--y0", type=float, nargs="+", default=[0.0, 0.82, 0.9, 0.95])
    ap.add_argument("--rows", type=int, default=20)
    ap.add_argument("--blas-threads", default="1")
    args = ap.parse_args()
    with open(args.config) as fh:
        raw = yaml.safe_load(fh)
    # a sweep that validates (the script runs its own starts)
    raw["sweep"] = {"length": [80.0], "theta0": [0.0], "y0": [0.0, 1.0],
                    "random": {"count": 1, "seed": 0}}  # fmt: skip
    cfg = parse_config(raw)
    field, _ = get_flow_field(cfg.flow, args.cache)
    array = field.array
    print(f"BLAS threads {os.environ['OPENBLAS_NUM_THREADS']}; {args.rows} rows; target "
          f"{N_BEADS} beads under {TARGET_S:g} s CPU")  # fmt: skip
    a = cfg.fiber.bead_radius
    worst_all = 0.0
    for frac in args.spacings:
        length = (N_BEADS - 1) * spacing_um(a, frac) + 2 * a
        assert n_beads(length, a, frac) == N_BEADS
        for e in args.moduli:
            st = cfg.fiber.model_copy(
                update={"young_modulus": e, "bead_spacing": frac, "array_rows": args.rows}
            )
            st = type(st).model_validate(st.model_dump())  # validate the updated settings
            pillar = array_pillar(array, st, field.viscosity, field.u_center)
            ys = [y for y in args.y0 if start_clear(array, pillar, N_BEADS, a, y, 0.0, frac)]
            warm = st.model_copy(update={"array_rows": 1})
            simulate(field, warm, FiberStart(0.0, ys[0], length))  # compile
            times = []
            for y in ys:
                c0 = time.process_time()
                r = simulate(field, st, FiberStart(0.0, y, length))
                times.append(time.process_time() - c0)
                print(f"  b/2a={frac:g} L={length:.1f} E={e:.0e} y0={y:g}: "
                      f"{times[-1]:6.2f} s ({r.status}, {r.mode}, rows {r.rows}, "
                      f"steps {r.n_steps})", flush=True)  # fmt: skip
            worst = max(times)
            worst_all = max(worst_all, worst)
            print(f"b/2a={frac:g} E={e:.0e}: largest {worst:.2f} s, "
                  f"largest/target {worst / TARGET_S:.3f}", flush=True)  # fmt: skip
    print(f"all: largest {worst_all:.2f} s, largest/target {worst_all / TARGET_S:.3f} "
          f"({'met' if worst_all < TARGET_S else 'NOT met'})")  # fmt: skip


if __name__ == "__main__":
    main()
