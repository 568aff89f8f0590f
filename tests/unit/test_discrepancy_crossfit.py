"""The halves' fits and the pooled refit quote the same estimator (issue 30, item 2).

Stand-in with a known truth: an effect (pillar_hydro's range [0, 3]) that shifts δ by
0.1 x its value, δ observed with noise 0.02 and each copy drawn with its own noise
0.02 (common random numbers across values), 60 fibers in two halves of 30, 2 fit
copies, 5 Brent steps per half and 3 for the pooled refit, as the workflow runs them.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from fibersweep.discrepancy.candidates import LIBRARY
from fibersweep.discrepancy.estimate import Fit, score_interval, slope_estimate
from fibersweep.discrepancy.fit import fit_effect, fold_fits, pooled_refit, refit_bounds

TRUTH = 0.6
CAND = LIBRARY["pillar_hydro"]


class _Shift:
    """δ of copy k of fiber i = x_i + 0.1 value + sigma z_ik (rows honoured)."""

    def __init__(self, x: np.ndarray, sigma: float, rng: np.random.Generator):
        self.x, self.sigma = x, sigma
        self.z = rng.standard_normal((2, len(x)))

    def copies(self, ks, effects=None, rows=None, desc=""):
        return [self.copy(k, effects, rows, desc) for k in ks]

    def copy(self, k, effects=None, rows=None, desc=""):
        v = float((effects or {}).get(CAND.name, 0.0))
        idx = np.arange(len(self.x)) if rows is None else np.asarray(rows)
        return pd.DataFrame({"delta": self.x[idx] + 0.1 * v + self.sigma * self.z[k, idx]})


def _data_set(rng: np.random.Generator, n: int = 60, sigma: float = 0.02):
    x = rng.uniform(0.0, 0.5, n)
    model = _Shift(x, sigma, rng)
    observed = pd.DataFrame({"delta": x + 0.1 * TRUTH + sigma * rng.standard_normal(n)})
    base = [model.copy(k) for k in range(2)]
    perm = rng.permutation(n)
    folds = [np.sort(perm[: n // 2]), np.sort(perm[n // 2 :])]
    return model, observed, base, folds


def _fit_both(seed: int, m: int = 100):
    """Halves' values and the pooled refit (value, interval) on m data sets."""
    rng = np.random.default_rng(seed)
    halves, pooled = [], []
    for _ in range(m):
        model, observed, base, folds = _data_set(rng)
        fits = fold_fits(CAND, model, observed, base, folds, ["delta"], {"delta": 1.0}, 5)
        vals = [f.value for f in fits]
        p = pooled_refit(CAND, model, observed, base, vals, ["delta"], {"delta": 1.0}, 3)
        lo, hi, _, _ = score_interval(p)
        halves.append(vals)
        pooled.append((p.value, lo, hi))
    return np.array(halves), np.array(pooled)


def test_each_half_quotes_the_score_tests_zero_of_its_own_profile():
    model, observed, base, folds = _data_set(np.random.default_rng(1))
    fits = fold_fits(CAND, model, observed, base, folds, ["delta"], {"delta": 1.0}, 5)
    for f, held in zip(fits, folds, strict=True):
        best = min(f.evaluations, key=lambda e: e[1])[0]
        assert f.value == slope_estimate(Fit(f.name, best, f.loss, f.loss0, (), f.profile))
        # fitted on the other half: its profile has one loss per training fiber
        assert len(f.profile[0][1]) == len(observed) - len(held)


def test_halves_are_as_precise_as_the_estimator_allows():
    # Before (issue 30), a half returned the best of its evaluated values, a point on
    # Brent's golden-section grid of [0, 3]: RMSE 0.062, 0.061, 0.061 about the truth
    # 0.6 over 200 halves (seeds 31, 32, 33 of this test); with the score test's zero
    # 0.042, 0.041, 0.042. The pooled refit (60 fibers): 0.034-0.036 both ways. Stated:
    # RMSE < 0.05, about 4 standard errors of the RMSE (5 % relative over 200 halves)
    # above the value measured and 5 below the value before (this fails before the fix).
    halves, pooled = _fit_both(31)
    assert np.sqrt(np.mean((halves - TRUTH) ** 2)) < 0.05
    assert np.sqrt(np.mean((pooled[:, 0] - TRUTH) ** 2)) < 0.045


def test_pooled_value_sits_with_the_halves_and_inside_its_interval():
    # One estimator for all three values: the pooled value is within 0.03 (1 % of the
    # range) of the halves' span in at least 95 of 100 data sets (measured 100 of 100 on
    # seeds 31-33), and its interval covers the truth at 95 % within the binomial 3 sd of
    # 100 draws, 0.07 (measured 0.91-0.93). On this smooth stand-in the pooled value sat
    # with the halves before the fix too (test_shared_points_keep_... has the case where
    # it did not).
    halves, pooled = _fit_both(32)
    lo_h, hi_h = halves.min(axis=1), halves.max(axis=1)
    inside = (pooled[:, 0] >= lo_h - 0.03) & (pooled[:, 0] <= hi_h + 0.03)
    assert inside.mean() >= 0.95
    assert np.all((pooled[:, 1] <= pooled[:, 0]) & (pooled[:, 0] <= pooled[:, 2]))
    cover = ((pooled[:, 1] <= TRUTH) & (TRUTH <= pooled[:, 2])).mean()
    assert abs(cover - 0.95) <= 0.07


def test_refit_bounds_pad_a_quarter_of_the_range_and_stay_inside_it():
    assert refit_bounds(CAND, [0.64, 0.71]) == pytest.approx((0.0, 0.71 + 0.75))
    assert refit_bounds(CAND, [2.9, 2.5]) == pytest.approx((2.5 - 0.75, 3.0))
    signed = LIBRARY["inlet_speed"]  # [-0.3, 0.3]
    assert refit_bounds(signed, [-0.04, -0.05]) == pytest.approx((-0.2, 0.11))


def test_a_half_that_keeps_the_baseline_stays_at_zero():
    # no effect in the data: a half whose best evaluated value is the baseline quotes 0
    rng = np.random.default_rng(4)
    x = rng.uniform(0.0, 0.5, 40)
    model = _Shift(x, 0.0, rng)
    observed = pd.DataFrame({"delta": x})
    base = [model.copy(k) for k in range(2)]
    folds = [np.arange(0, 40, 2), np.arange(1, 40, 2)]
    fits = fold_fits(CAND, model, observed, base, folds, ["delta"], {"delta": 1.0}, 5)
    assert [f.value for f in fits] == [0.0, 0.0]
    # the same fit as fit_effect with estimate on the training half
    f0 = fit_effect(CAND, model, observed.iloc[folds[1]].reset_index(drop=True),
                    [b.iloc[folds[1]].reset_index(drop=True) for b in base], folds[1],
                    ["delta"], {"delta": 1.0}, 5, estimate=True)  # fmt: skip
    assert f0.value == fits[0].value


class _Class(_Shift):
    """Only the class is seen: Above when δ > 0.3 (every fiber's loss is a step in the
    value: the step-like loss of the simulator's class flips and branch switches)."""

    def copy(self, k, effects=None, rows=None, desc=""):
        d = super().copy(k, effects, rows, desc)["delta"].to_numpy()
        return pd.DataFrame({"class": np.where(d > 0.3, "Above", "Below")})


def _profile(model, observed, rows, grid):
    from fibersweep.discrepancy.fit import per_fiber_loss
    from fibersweep.discrepancy.gap import value_matrices

    obs = observed.iloc[rows].reset_index(drop=True)
    return [
        (float(v), per_fiber_loss(value_matrices(obs, model.copies(range(2), {CAND.name: v},
                                                                   rows), ["class"]),
                                  {"class": 1.0}))
        for v in grid
    ]  # fmt: skip


def _estimate(profile):
    best = profile[int(np.argmin([p[1].mean() for p in profile]))][0]
    return slope_estimate(Fit(CAND.name, best, 0.0, 0.0, (), tuple(profile)))


def test_shared_points_keep_the_pooled_value_with_the_halves():
    # Why the pooled value can still lie outside both halves with one estimator: on a
    # step-like loss the read-out depends on where the loss was evaluated, and the
    # halves' and the pooled refit's Brent searches evaluate different values. Class
    # only, 100 fibers, 0.05 noise, 60 data sets: with the workflow's searches the
    # pooled value lay more than 0.03 outside both halves in 27, 30, 32 % of data sets
    # (seeds 7, 8, 9; about as often as before the fix: 31 against 33 % on 40 other
    # data sets); read on the same 7 values (0, 0.5, ..., 3) for both halves and all
    # fibers, in 0, 3, 3 %. Stated: shared values <= 10 %, the searches >= 15 % (the
    # diagnosis, not a target: see docs/validation/discrepancy.md, "Fit uncertainty").
    rng = np.random.default_rng(7)
    grid = np.linspace(0.0, 3.0, 7)
    shared, searched = [], []
    for _ in range(60):
        x = rng.uniform(0.0, 0.5, 100)
        model = _Class(x, 0.05, rng)
        d = x + 0.1 * TRUTH + 0.05 * rng.standard_normal(100)
        observed = pd.DataFrame({"class": np.where(d > 0.3, "Above", "Below")})
        perm = rng.permutation(100)
        folds = [np.sort(perm[:50]), np.sort(perm[50:])]
        prof = [_profile(model, observed, folds[1 - f], grid) for f in range(2)]
        h = [_estimate(p) for p in prof]
        both = [(v, np.concatenate([a, b])) for (v, a), (_, b) in zip(*prof, strict=True)]
        shared.append((*h, _estimate(both)))
        base = [model.copy(k) for k in range(2)]
        fits = fold_fits(CAND, model, observed, base, folds, ["class"], {"class": 1.0}, 5)
        hs = [f.value for f in fits]
        if any(hs):
            p = pooled_refit(CAND, model, observed, base, hs, ["class"], {"class": 1.0}, 3)
            searched.append((*hs, p.value))

    def outside(a):
        a = np.array(a)
        lo, hi = a[:, :2].min(axis=1) - 0.03, a[:, :2].max(axis=1) + 0.03
        return float(((a[:, 2] < lo) | (a[:, 2] > hi)).mean())

    assert outside(shared) <= 0.10
    assert outside(searched) >= 0.15


class _SignedShift(_Shift):
    """The signed effect pillar_scale ([-0.2, 0.2]) shifting δ by its value."""

    def copy(self, k, effects=None, rows=None, desc=""):
        v = float((effects or {}).get("pillar_scale", 0.0))
        idx = np.arange(len(self.x)) if rows is None else np.asarray(rows)
        return pd.DataFrame({"delta": self.x[idx] + v + self.sigma * self.z[k, idx]})


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_signed_halves_find_the_side_and_the_value_whichever_side_the_signature_said(side):
    # truth -0.04 (the inlet_speed in a pair), 60 fibers, noise 0.02, 20 data
    # sets: every half negative (measured: 40 of 40 for either side), halves' RMSE < 0.008
    # (measured 0.0051 and 0.0047, worst half 0.012 off), the pooled value's < 0.006
    # (measured 0.0034 both).
    cand = LIBRARY["pillar_scale"]
    rng = np.random.default_rng(12)
    halves, pooled = [], []
    for _ in range(20):
        x = rng.uniform(0.0, 0.5, 60)
        model = _SignedShift(x, 0.02, rng)
        observed = pd.DataFrame({"delta": x - 0.04 + 0.02 * rng.standard_normal(60)})
        base = [model.copy(k) for k in range(2)]
        perm = rng.permutation(60)
        folds = [np.sort(perm[:30]), np.sort(perm[30:])]
        fits = fold_fits(cand, model, observed, base, folds, ["delta"], {"delta": 1.0}, 5, side)
        vals = [f.value for f in fits]
        halves += vals
        p = pooled_refit(cand, model, observed, base, vals, ["delta"], {"delta": 1.0}, 3)
        pooled.append(p.value)
    halves, pooled = np.array(halves), np.array(pooled)
    assert np.all(halves < 0)
    assert np.sqrt(np.mean((halves + 0.04) ** 2)) < 0.008
    assert np.sqrt(np.mean((pooled + 0.04) ** 2)) < 0.006


def test_plan_counts_the_refits_starting_values_and_interval_ends():
    from fibersweep.discrepancy.candidates import get_candidates
    from fibersweep.discrepancy.settings import DiscrepancySettings, plan_budget

    cands = get_candidates(["friction", "inlet_speed"])
    plan = plan_budget(100, DiscrepancySettings(), cands)
    # 2 refits x ((3 Brent steps + 1 for the halves' values + at most 3 for the
    # interval's ends) x 2 fit copies + 8 copies) x 100 fibers
    assert plan.cost(100)["refits"] == 2 * ((3 + 1 + 3) * 2 + 8) * 100
