"""Coverage of the refit's 95 % interval on stand-ins with a known truth, at several N.

Stand-ins (no simulator): fiber i has a feature x_i ~ U(0, 0.5); the effect shifts
it by its value (truth 0.08, candidate ``pillar_scale``), and each of the model's
2 copies adds its own noise (common random numbers: the same draws at every value).

- ``shift``: δ = x_i + value + 0.02 z observed (fair CRPS): a smooth per-fiber loss;
- ``class``: only the class is observed, Above when x_i + value + 0.05 z > 0.3
  (fair Brier): every fiber's loss is a step function of the value.

Each data set runs the workflow's fit stages: the halves' fits
(:func:`fibersweep.discrepancy.fit.fold_fits`, 5 evaluations) and the pooled refit
with its interval step (:func:`~fibersweep.discrepancy.fit.pooled_refit`, Brent's
steps on all fibers, ``--refit-evals`` of them). The interval
(:func:`~fibersweep.discrepancy.estimate.score_interval`, the bootstrap over fibers
of the mean loss's minimiser) is then read from its per-fiber losses, and from
those of refits with other designs on the same data set:

- ``mean slope``: the workflow's refit and interval;
- ``t statistic``: the same bootstrap of the quoted value's own read-out (the mean
  slope divided by its standard error per stretch before its zero is found);
- ``fresh data``: the mean-slope read-out on a second, independent data set
  evaluated at the refit's evaluated values (the same design without having been
  chosen on these data: tells the search's adaptive design from the read-out);
- ``search, no step``: the refit without its interval step (the evaluations placed
  at the interval's ends);
- ``grid``, ``grid, no step``: the refit with its Brent steps replaced by values
  evenly over its bounds (:func:`grid_refit`: fixed by the halves' values, each
  fitted on one half, not chosen on the pooled fibers' losses), with and without
  the interval step;
- ``local``, ``local, no step``: the same grid over the halves' mean ± 2.5 times
  their spread (at least 2 % of the range): a fixed design as fine as the search's.

It prints coverage with its Wilson 95 % interval, the spread of the quoted value
over data sets and the bootstrap's mean spread, then how far the grid moves the
quoted value from the search's on the same data sets::

    python scripts/studies/discrepancy/diagnose_interval.py --sets 60 --n 20 60 200
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
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
from fibersweep.discrepancy.fit import (
    _open_end,
    _unbracketed_end,
    _unread_ends,
    fit_effect,
    fold_fits,
    per_fiber_loss,
    pooled_refit,
    refit_bounds,
)
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


#: The ``local`` grid's half-width in units of its scale, and the scale's floor as a
#: fraction of the effect's range. Set a priori (the halves' difference has about
#: twice the pooled value's sd, so ±2.5 differences span about ±3 sd at its
#: median), not tuned.
LOCAL_SPAN, LOCAL_FLOOR = 2.5, 0.02


def grid_values(design: str, halves: list[float], k: int) -> tuple[float, float, list[float]]:
    """A fixed design of ``k`` values evenly over a range, ends included: the refit's
    bounds (``grid``) or the halves' mean ± LOCAL_SPAN times the larger of their spread
    and LOCAL_FLOOR of the effect's range (``local``), inside the bounds."""
    lo, hi = refit_bounds(CAND, halves)
    if design == "local":
        c = float(np.mean(halves))
        scale = max(float(np.ptp(halves)), LOCAL_FLOOR * (CAND.hi - CAND.lo))
        lo, hi = max(lo, c - LOCAL_SPAN * scale), min(hi, c + LOCAL_SPAN * scale)
    pts = [0.5 * (lo + hi)] if k == 1 else [float(v) for v in np.linspace(lo, hi, k)]
    return lo, hi, pts


def grid_refit(model, observed, base, halves, obs, w, refit_evals, design, step) -> Fit:
    """The pooled refit with its evaluations on a fixed grid (:func:`grid_values`)
    instead of Brent's steps, with the workflow's other steps: the kept evaluation
    (the range's end for an unbracketed zero, else the middle of the grid's widest
    gap) and, with ``step``, the interval step (the range's end for an open interval,
    then the closed ends no evaluated value is near). Each is a refit evaluating only
    ``known`` values (``max_evals=0``)."""
    n = len(observed)
    glo, ghi, pts = grid_values(design, halves, refit_evals - 1)
    lo, hi = refit_bounds(CAND, halves)
    tol = 1e-9 * (CAND.hi - CAND.lo)

    def refit(values: list[float]) -> Fit:
        return fit_effect(CAND, model, observed, base, np.arange(n), [obs], w, 0,
                          bounds=(lo, hi), known=values, estimate=True)  # fmt: skip

    known = [*halves, *pts]
    f = refit(known)
    end = _unbracketed_end(replace(f, value=_best(f)), lo, hi, tol)
    if end is None:  # the widest gap of the grid's range
        xs = np.unique(np.clip([glo, ghi, *[v for v, _ in f.evaluations if glo <= v <= ghi]],
                               glo, ghi))  # fmt: skip
        j = int(np.argmax(np.diff(xs)))
        end = float(0.5 * (xs[j] + xs[j + 1]))
    known.append(end)
    f = refit(known)
    if step and (e := _open_end(f, CAND.lo, CAND.hi, tol)):
        known.append(e)
        f = refit(known)
    if step and (ends := _unread_ends(f)):
        f = refit([*known, *ends])
    return f


def _best(f: Fit) -> float:
    """The best evaluated value (what ``fit_effect`` holds before its estimate)."""
    return min(f.evaluations, key=lambda p: (p[1], abs(p[0])))[0]


def one(
    kind: str, n: int, rng: np.random.Generator, refit_evals: int = 5
) -> dict[str, tuple[float, float, float]]:
    """(value, lo, hi) of each read-out, and the bootstrap's spread, on one data set
    (``refit_evals``: the pooled refit's evaluations after the halves' values)."""
    model, observed = data_set(kind, n, rng)
    obs = "class" if kind == "class" else "delta"
    base = model.copies(range(2))
    perm = rng.permutation(n)
    folds = [np.sort(perm[: n // 2]), np.sort(perm[n // 2 :])]
    w = {obs: 1.0}
    halves = [f.value for f in fold_fits(CAND, model, observed, base, folds, [obs], w, 5, 1.0)]
    fit = pooled_refit(CAND, model, observed, base, halves, [obs], w, refit_evals)
    out = {}
    for label, design, step in (
        ("search, no step", "search", False),
        ("grid", "grid", True),
        ("grid, no step", "grid", False),
        ("local", "local", True),
        ("local, no step", "local", False),
    ):
        if design == "search":
            f = fit_effect(CAND, model, observed, base, np.arange(n), [obs], w, refit_evals,
                           bounds=refit_bounds(CAND, halves), known=halves, estimate=True,
                           bracket_root=True, close_interval=False)  # fmt: skip
        else:
            f = grid_refit(model, observed, base, halves, obs, w, refit_evals, design, step)
        x, L = merged_profile(f)
        c = np.random.default_rng(0).multinomial(n, np.full(n, 1.0 / n), size=2000)
        sd = float(np.std(minimiser_ends(x, L, c)[0]))
        out[label] = (f.value, *score_interval(f)[:2], sd)
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


READOUTS = ("mean slope", "t statistic", "fresh data", "search, no step", "grid",
            "grid, no step", "local", "local, no step")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kinds", nargs="+", default=["shift", "class"], choices=["shift", "class"])
    ap.add_argument("--n", nargs="+", type=int, default=[20, 60, 200])
    ap.add_argument("--sets", type=int, default=60)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument(
        "--refit-evals",
        type=int,
        default=5,
        help="the pooled refit's evaluations (the workflow's: fit_evals - 2 = 3)",
    )
    ap.add_argument("--moved", default="local", choices=READOUTS,
                    help="the read-out whose value is compared with the search's")  # fmt: skip
    args = ap.parse_args()
    print("| stand-in | N | read-out | covered k/n | coverage [Wilson 95 %] | sd of the value "
          "| mean bootstrap sd | mean width |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|")
    shifts = []  # how far the workflow's design moves the quoted value from the search's
    for kind in args.kinds:
        for n in args.n:
            rng = np.random.default_rng([args.seed, n, kind == "class"])
            res = [one(kind, n, rng, args.refit_evals) for _ in range(args.sets)]
            for label in READOUTS:
                r = np.array([d[label] for d in res])
                k = int(((r[:, 1] <= TRUTH) & (TRUTH <= r[:, 2])).sum())
                lo, hi = wilson(k, len(r))
                print(f"| {kind} | {n} | {label} | {k}/{len(r)} | {k / len(r):.2f} "
                      f"[{lo:.2f}, {hi:.2f}] | {r[:, 0].std():.4f} | {r[:, 3].mean():.4f} | "
                      f"{(r[:, 2] - r[:, 1]).mean():.4f} |")  # fmt: skip
            d = np.array([x[args.moved][0] - x["mean slope"][0] for x in res])
            sd = np.array([x["mean slope"][0] for x in res]).std()
            shifts.append(f"| {kind} | {n} | {d.mean():+.4f} | {np.abs(d).mean():.4f} | "
                         f"{np.abs(d).max():.4f} | {np.abs(d).mean() / sd:.2f} |")  # fmt: skip
    print(f"\n| stand-in | N | quoted value, {args.moved} - search: mean | mean abs | max abs "
          "| mean abs / sd of the value |")  # fmt: skip
    print("|---|---|---|---|---|---|")
    print("\n".join(shifts))


if __name__ == "__main__":
    main()
