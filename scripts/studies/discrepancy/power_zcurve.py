"""The expected z of the power analysis's strongest tests against an effect's magnitude.

The power analysis scales z with a power law of the magnitude; this prints what
the z-vector really is at several magnitudes, on one set of simulated starts
(the starts of ``study_discrepancy.py --predict-only --power-seeds SEED``), so
the law can be checked where a limit lies (docs/validation/discrepancy.md, *Limits read
near the limit*)::

    python scripts/studies/discrepancy/power_zcurve.py --seeds 1 2 --effect inlet_speed \
        --magnitudes 0.15 0.075 0.03 0.015 0.0075
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.copies import CopyMaker, NoiseModel
from fibersweep.discrepancy.detection import ensemble_factor
from fibersweep.discrepancy.gap import assess_gap, feature_one_sided, value_matrices
from fibersweep.discrepancy.observables import scored
from fibersweep.discrepancy.power import _z_vector
from fibersweep.discrepancy.simulate import Simulator

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from common import DEFAULT_CACHE, study_field, uniform_starts  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1])
    ap.add_argument("--effect", default="inlet_speed")
    ap.add_argument("--magnitudes", type=float, nargs="+", default=[0.15, 0.075, 0.03, 0.015])
    ap.add_argument("--simulate", type=int, default=40, help="simulated starts")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cache", default=DEFAULT_CACHE)
    args = ap.parse_args()
    field = study_field(args.cache)
    n = args.simulate
    ens = ensemble_factor(3, 8)  # as power.analyse_power: 3 copies, a workflow of 8
    for seed in args.seeds:
        rng = np.random.default_rng([seed, 17])
        starts = uniform_starts(rng, n)
        with Simulator(field, FiberSettings(), workers=args.workers, progress=False) as sim:
            maker = CopyMaker(starts, NoiseModel(), seed, sim)
            rows = np.arange(n)
            base = maker.copies(range(3), None, rows, desc="baseline")
            g0 = assess_gap(value_matrices(base[0], base[1:], scored()), rng, n_perm=99, n_boot=10)
            side = feature_one_sided(g0)
            for m in args.magnitudes:
                z, _ = _z_vector(maker, base, {args.effect: m}, rows, scored(), rng)
                z = z * ens
                top = np.argsort(-np.abs(z))[:3]
                tests = "  ".join(
                    f"test {j} ({'score' if side[j] else 'residual'}) {z[j]:+.2f}" for j in top
                )
                print(f"seed {seed}  {args.effect} = {m:g}:  {tests}", flush=True)


if __name__ == "__main__":
    main()
