"""Coverage of the refit's 95 % interval on stand-ins with a known truth, at several N.

Stand-ins (no simulator): fiber i has a feature x_i ~ U(0, 0.5); the effect shifts
it by its value (truth 0.08, candidate ``pillar_scale``), and each of the model's
2 copies adds its own noise (common random numbers: the same draws at every value).

- ``shift``: δ = x_i + value + 0.02 z observed (fair CRPS): a smooth per-fiber loss;
- ``class``: only the class is observed, Above when x_i + value + 0.05 z > 0.3
  (fair Brier): every fiber's loss is a step function of the value.

Each data set runs the workflow's fit stages: the halves' fits
(:func:`fibersweep.discrepancy.fit.fold_fits`, 5 evaluations) and the pooled refit
with its interval step (:func:`~fibersweep.discrepancy.fit.pooled_refit`). The
interval is then read three ways from the refit's per-fiber losses:

- ``mean slope``: :func:`~fibersweep.discrepancy.estimate.score_interval`, the
  bootstrap over fibers of the mean loss's minimiser (the workflow's interval);
- ``t statistic``: the same bootstrap of the quoted value's own read-out (the mean
  slope divided by its standard error per stretch before its zero is found);
- ``fresh data``: the mean-slope read-out on a second, independent data set
  evaluated at the refit's evaluated values (the same design without having been
  chosen on these data: tells the search's adaptive design from the read-out).

It prints coverage with its Wilson 95 % interval, the spread of the quoted value
over data sets and the bootstrap's mean spread::

    python scripts/studies/discrepancy/diagnose_interval.py --sets 60 --n 20 60 200
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from fibersweep.discrepancy.candidates import LIBRARY
from fibersweep.discrepancy.estimate import (
    Fit,
    expanded_tail,
    merged_profile,
    minimiser_ends,
    score_interval,
)
from fibersweep.discrepancy.fit import fold_fits, per_fiber_loss, pooled_refit
from fibersweep.discrepancy.gap import value_matrices

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from common import wilson  # noqa: E402

TRUTH = 0.08
CAND = LIBRARY["pillar_scale"]


class StandIn:
    """The model's copies of one data set: copy k of fiber i shifted by the value,
    with its own noise draws (the same at every value)."""

    def __init__(self, kind: str, x: np.ndarray, rng: np.random.Generator):
        self.kind, self.x = kind, x
        self.z = rng.standard_normal((2, len(x)))

    def observe(self, d: np.ndarray) -> pd.DataFrame:
        if self.kind == "class":
            return pd.DataFrame({"class": np.where(d > 0.3, "Above", "Below")})
        return pd.DataFrame({"delta": d})

    @property
    def sigma(self) -> float:
        return 0.05 if self.kind == "class" else 0.02

    def copies(self, ks, effects=None, rows=None, desc=""):
        v = float((effects or {}).get(CAND.name, 0.0))
        idx = np.arange(len(self.x)) if rows is None else np.asarray(rows)
        return [self.observe(self.x[idx] + v + self.sigma * self.z[k, idx]) for k in ks]


def data_set(kind: str, n: int, rng: np.random.Generator) -> tuple[StandIn, pd.DataFrame]:
    x = rng.uniform(0.0, 0.5, n)
    model = StandIn(kind, x, rng)
    return model, model.observe(x + TRUTH + model.sigma * rng.standard_normal(n))


def one(kind: str, n: int, rng: np.random.Generator) -> dict[str, tuple[float, float, float]]:
    """(value, lo, hi) of each read-out, and the bootstrap's spread, on one data set."""
    model, observed = data_set(kind, n, rng)
    obs = "class" if kind == "class" else "delta"
    base = model.copies(range(2))
    perm = rng.permutation(n)
    folds = [np.sort(perm[: n // 2]), np.sort(perm[n // 2 :])]
    w = {obs: 1.0}
    halves = [f.value for f in fold_fits(CAND, model, observed, base, folds, [obs], w, 5, 1.0)]
    fit = pooled_refit(CAND, model, observed, base, halves, [obs], w, 5)
    out = {}
    x, L = merged_profile(fit)
    counts = np.random.default_rng(0).multinomial(n, np.full(n, 1.0 / n), size=2000)
    a = expanded_tail(n)
    for label, stud in (("mean slope", False), ("t statistic", True)):
        lo_b, hi_b = minimiser_ends(x, L, counts, stud)
        sd = float(np.std(lo_b))
        # as score_interval: a minimum at an end of the evaluated values lies beyond the
        # last stretch's other end
        lo_b = np.where(lo_b >= x[-1], x[-2], lo_b)
        hi_b = np.where(hi_b <= x[0], x[1], hi_b)
        out[label] = (fit.value, float(np.quantile(lo_b, a)), float(np.quantile(hi_b, 1 - a)), sd)
    out["mean slope"] = (fit.value, *score_interval(fit)[:2], out["mean slope"][3])
    fresh, fresh_obs = data_set(kind, n, rng)

    def loss_at(v: float) -> np.ndarray:
        vals = value_matrices(fresh_obs, fresh.copies(range(2), {CAND.name: v}), [obs])
        return per_fiber_loss(vals, w)

    prof = tuple((v, loss_at(v)) for v, _ in fit.profile)
    f2 = Fit(CAND.name, fit.value, 0.0, 0.0, (), prof)
    lo_b, _ = minimiser_ends(*merged_profile(f2), counts)
    out["fresh data"] = (float(np.median(lo_b)), *score_interval(f2)[:2], float(np.std(lo_b)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kinds", nargs="+", default=["shift", "class"], choices=["shift", "class"])
    ap.add_argument("--n", nargs="+", type=int, default=[20, 60, 200])
    ap.add_argument("--sets", type=int, default=60)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    print("| stand-in | N | read-out | covered k/n | coverage [Wilson 95 %] | sd of the value "
          "| mean bootstrap sd | mean width |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|")
    for kind in args.kinds:
        for n in args.n:
            rng = np.random.default_rng([args.seed, n, kind == "class"])
            res = [one(kind, n, rng) for _ in range(args.sets)]
            for label in ("mean slope", "t statistic", "fresh data"):
                r = np.array([d[label] for d in res])
                k = int(((r[:, 1] <= TRUTH) & (TRUTH <= r[:, 2])).sum())
                lo, hi = wilson(k, len(r))
                print(f"| {kind} | {n} | {label} | {k}/{len(r)} | {k / len(r):.2f} "
                      f"[{lo:.2f}, {hi:.2f}] | {r[:, 0].std():.4f} | {r[:, 3].mean():.4f} | "
                      f"{(r[:, 2] - r[:, 1]).mean():.4f} |")  # fmt: skip


if __name__ == "__main__":
    main()
