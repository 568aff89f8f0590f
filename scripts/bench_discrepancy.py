"""Discrepancy runs: copy-by-copy batches against one batch per evaluation, in one run.

The workflow's stages ask for several model copies of the same fibers at once
(8 baseline copies; 2 copies per fit evaluation). Before, each copy was its own
batch of coarse tasks (4 per worker), so the workers waited at the end of every
copy for its slowest run (a Trapping run lasts as long as many others). Now all
copies of a stage go as one batch of small tasks (``Simulator(chunk_runs=8)``).

Each round runs the same work with both designs on fresh copy makers: the
baseline copies and a 5-value fit of friction on all fibers. The designs
alternate (the machine may be shared), the outcome tables are compared (they
must be identical: a run depends only on its start, seed and effects), and the
wall-time ratio of each round is printed with the median.

Usage: python scripts/bench_discrepancy.py [--n 60] [--rounds 2] [--workers 2]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import pandas as pd

from fibersweep.discrepancy.copies import CopyMaker
from fibersweep.discrepancy.noise import NoiseModel
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.fiber.settings import FiberSettings
from fibersweep.flow.cache import get_flow_field
from fibersweep.flow.settings import FlowSettings

BOX = {"theta0": (-10.0, 10.0), "y0": (0.15, 0.65), "length": (0.5, 1.4)}
FIT_VALUES = (0.2, 0.4, 0.5, 0.6, 0.8)  # friction values of a 5-evaluation fit


def work(field, starts: np.ndarray, workers: int, batched: bool, copies: int) -> tuple:
    """Baseline copies + a 2-copy fit over FIT_VALUES; returns (seconds, runs, tables)."""
    chunk = 8 if batched else 10**9  # 10**9: the old 4 tasks per worker
    t0 = time.perf_counter()
    with Simulator(field, FiberSettings(), workers=workers, progress=False,
                   chunk_runs=chunk) as sim:  # fmt: skip
        maker = CopyMaker(starts, NoiseModel(), 3, sim)
        tables = []
        for eff, ks in [(None, range(copies))] + [({"friction": v}, range(2)) for v in FIT_VALUES]:
            if batched:
                tables += maker.copies(ks, eff, desc="bench")
            else:
                tables += [maker.copy(k, eff, desc="bench") for k in ks]
        runs = sim.used
    return time.perf_counter() - t0, runs, tables


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=60, help="fibers")
    ap.add_argument("--copies", type=int, default=8, help="baseline copies")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cache", default=".fibersweep-cache/tests")
    args = ap.parse_args()
    field, _ = get_flow_field(FlowSettings(dx=4.0), args.cache)
    rng = np.random.default_rng(5)
    starts = np.column_stack([rng.uniform(*BOX[c], args.n) for c in ("theta0", "y0", "length")])
    # compile the kernels of both effect sets in this process and the workers first
    work(field, starts[:4], args.workers, True, 2)
    ratios = []
    for r in range(args.rounds):
        order = (False, True) if r % 2 == 0 else (True, False)
        res = {b: work(field, starts, args.workers, b, args.copies) for b in order}
        (t_old, runs, tab_old), (t_new, _, tab_new) = res[False], res[True]
        for a, b in zip(tab_old, tab_new, strict=True):
            pd.testing.assert_frame_equal(a, b)
        ratios.append(t_old / t_new)
        print(f"round {r + 1}: {runs} runs each; copy by copy {t_old:.1f} s "
              f"({runs / t_old:.1f} runs/s), batched {t_new:.1f} s ({runs / t_new:.1f} runs/s), "
              f"ratio {t_old / t_new:.2f}; outcomes identical")  # fmt: skip
    print(f"median speed-up of the batched design: {statistics.median(ratios):.2f}x "
          f"over {args.rounds} rounds")  # fmt: skip


if __name__ == "__main__":
    main()
