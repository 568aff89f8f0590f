"""Detection of a random effect against its magnitude: the dispersion test and the gap family.

On ``--n`` starts drawn from the study box, ``--copies`` baseline copies are
simulated, and ``--replicas`` copies with the random effect at each magnitude
(common random numbers: copy r with the effect shares its start jitter, run
seed and noise draws with baseline copy r). Each copy r with the effect plays
the measurement, the baseline copies j != r the model, as in the power
analysis; each baseline copy r against the others is a no-effect data set.
For every data set it records whether the dispersion test
(:func:`fibersweep.discrepancy.dispersion.dispersion_test`, one-sided, alone at
``--alpha``) rejects and whether the gap family (:func:`gap.assess_gap`, Holm)
finds a gap, and prints the rates with their binomial standard errors.

Usage::

    python scripts/studies/discrepancy/study_dispersion.py --effect start_noise --magnitudes 1 2 3 \
        --n 100 --replicas 8 --out results/dispersion
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.copies import CopyMaker, NoiseModel
from fibersweep.discrepancy.dispersion import dispersion_test
from fibersweep.discrepancy.gap import assess_gap, value_matrices
from fibersweep.discrepancy.observables import scored
from fibersweep.discrepancy.simulate import Simulator

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from common import DEFAULT_CACHE, study_field, uniform_starts  # noqa: E402

log = logging.getLogger("dispersion")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--effect", default="start_noise")
    ap.add_argument("--magnitudes", type=float, nargs="+", default=[1.0, 2.0, 3.0])
    ap.add_argument("--n", type=int, default=100)
    ap.add_argument("--copies", type=int, default=9, help="baseline copies (>= replicas + 1)")
    ap.add_argument("--replicas", type=int, default=8)
    ap.add_argument("--seed", type=int, default=31)
    ap.add_argument("--alpha", type=float, default=0.05)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cache", default=DEFAULT_CACHE)
    ap.add_argument("--out", default="results/dispersion")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)
    field = study_field(args.cache)
    rng = np.random.default_rng([args.seed, 5])
    starts = uniform_starts(rng, args.n)
    obs = scored()
    rows = []
    with Simulator(field, FiberSettings(), workers=args.workers, progress=False) as sim:
        maker = CopyMaker(starts, NoiseModel(), args.seed, sim)
        base = maker.copies(range(args.copies), None, desc="baseline")
        for m in [0.0, *args.magnitudes]:
            reps = range(min(args.replicas, args.copies)) if m == 0.0 else range(args.replicas)
            data = base if m == 0.0 else maker.copies(reps, {args.effect: m}, desc=f"{m:g}")
            for r in reps:
                model = [base[j] for j in range(args.copies) if j != r]
                vals = value_matrices(data[r], model, obs)
                d = dispersion_test(vals, rng, n_perm=1999)
                g = assess_gap(vals, rng, alpha=args.alpha, n_perm=1999, n_boot=10)
                rows.append({"magnitude": m, "replica": r, "p_dispersion": d.p_value,
                             "z_dispersion": d.z, "gap": g.any, "flagged": g.flagged})  # fmt: skip
            log.warning("%s = %g done", args.effect, m)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "dispersion.json").write_text(json.dumps({"args": vars(args), "rows": rows}, indent=1))
    print(f"{args.effect}, N = {args.n}, {args.copies - 1} model copies per data set, "
          f"alpha = {args.alpha}")  # fmt: skip
    print("| magnitude | data sets | dispersion test rejects | gap family finds a gap | either |")
    print("|---|---|---|---|---|")
    for m in [0.0, *args.magnitudes]:
        sel = [r for r in rows if r["magnitude"] == m]
        k = len(sel)
        a = np.array([r["p_dispersion"] <= args.alpha for r in sel])
        b = np.array([r["gap"] for r in sel])

        def rate(x: np.ndarray, k: int = k) -> str:
            p = x.mean()
            return f"{p:.2f} ± {np.sqrt(p * (1 - p) / k):.2f} ({x.sum()} of {k})"

        print(f"| {m:g} | {k} | {rate(a)} | {rate(b)} | {rate(a | b)} |")


if __name__ == "__main__":
    main()
