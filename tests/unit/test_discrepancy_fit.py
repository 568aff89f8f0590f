"""The 1D effect fit on a stand-in model whose outcome is known in closed form."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from fibersweep.discrepancy.candidates import LIBRARY
from fibersweep.discrepancy.fit import fit_effect


class _ShiftModel:
    """δ of copy k = x_i + value + 0.01 z_ik: an effect that shifts δ by its value."""

    def __init__(self, n: int):
        rng = np.random.default_rng(0)
        self.x = rng.uniform(0.0, 0.5, n)
        self.z = rng.standard_normal((4, n))
        self.calls = 0

    def copies(self, ks, effects=None, rows=None, desc=""):
        return [self.copy(k, effects, rows, desc) for k in ks]

    def copy(self, k, effects=None, rows=None, desc=""):
        self.calls += 1
        v = float((effects or {}).get("pillar_scale", 0.0))
        idx = np.arange(len(self.x)) if rows is None else rows
        return pd.DataFrame({"delta": self.x[idx] + v + 0.01 * self.z[k, idx]})


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_signed_fit_recovers_the_value_whichever_side_the_signature_said(side):
    # truth +0.08 on a signed effect; a signature pointing at -1 is overruled by the one
    # evaluation in the other half. Tolerance 0.01 (5 Brent steps on [0, 0.2]).
    n = 40
    model = _ShiftModel(n)
    observed = pd.DataFrame({"delta": model.x + 0.08})
    base = [model.copy(k) for k in range(2)]
    model.calls = 0
    fit = fit_effect(
        LIBRARY["pillar_scale"],
        model,
        observed,
        base,
        np.arange(n),
        ["delta"],
        {"delta": 1.0},
        max_evals=5,
        side=side,
    )
    assert fit.value == pytest.approx(0.08, abs=0.01)
    assert fit.loss < fit.loss0
    # 2 copies per evaluation: at most 5 Brent evaluations + 1 side check
    assert model.calls <= 2 * 6


def _quadratic_fit(mu: np.ndarray, grid: np.ndarray):
    from fibersweep.discrepancy.estimate import Fit

    prof = tuple((float(v), (v - mu) ** 2) for v in grid)
    return Fit("friction", float(mu.mean()), 0.0, 0.0, (), prof)


class _NoisyShift:
    """δ of copy k = x_i + value + sigma z_ik with its own draws per data set (Monte Carlo
    noise of the copies, common to every value: common random numbers)."""

    def __init__(self, x: np.ndarray, sigma: float, rng: np.random.Generator):
        self.x = x
        self.z = rng.standard_normal((2, len(x)))
        self.sigma = sigma

    def copies(self, ks, effects=None, rows=None, desc=""):
        return [self.copy(k, effects, rows, desc) for k in ks]

    def copy(self, k, effects=None, rows=None, desc=""):
        v = float((effects or {}).get("pillar_scale", 0.0))
        return pd.DataFrame({"delta": self.x + v + self.sigma * self.z[k]})


def _covered(model_cls, n: int, sigma: float, seed: int, observe, name: str) -> int:
    """Of 100 data sets (n fibers, shift 0.08, noise sigma on the data and the copies),
    how many fits' score intervals contain 0.08 (2 copies, 5 Brent evaluations)."""
    from fibersweep.discrepancy.estimate import score_interval

    rng = np.random.default_rng(seed)
    hits = 0
    for _ in range(100):
        x = rng.uniform(0.0, 0.5, n)
        model = model_cls(x, sigma, rng)
        observed = observe(x + 0.08 + sigma * rng.standard_normal(n))
        base = [model.copy(k) for k in range(2)]
        fit = fit_effect(LIBRARY["pillar_scale"], model, observed, base, np.arange(n),
                         [name], {name: 1.0}, max_evals=5, side=1.0)  # fmt: skip
        lo, hi, _, _ = score_interval(fit)
        hits += lo <= 0.08 <= hi
    return hits


def test_score_interval_of_a_real_fit_covers_the_truth_with_copy_noise():
    # The whole fit (fair CRPS against 2 noisy copies per fiber, bounded Brent, 5
    # evaluations) on 100 data sets of 40 fibers with measurement noise 0.02 and copy
    # noise 0.02: the interval from the fit's own evaluations covers the true shift 0.08
    # in 88-99 % of them (binomial 95 % range of 100 draws at 0.95, widened for the
    # read-out of a few evaluated values).
    hits = _covered(_NoisyShift, 40, 0.02, 6, lambda d: pd.DataFrame({"delta": d}), "delta")
    assert 0.88 <= hits / 100 <= 0.99


class _ClassFlip(_NoisyShift):
    """Only the class is observed: Above when x_i + value + sigma z_ik > 0.3 (a step in
    the value for every fiber: the per-fiber loss is piecewise constant)."""

    def copy(self, k, effects=None, rows=None, desc=""):
        d = super().copy(k, effects, rows, desc)["delta"].to_numpy()
        return pd.DataFrame({"class": np.where(d > 0.3, "Above", "Below")})


def test_score_interval_covers_the_truth_when_only_classes_are_seen():
    # The fit of a shift seen only through class flips (fair Brier-type score of 2 copies,
    # 5 Brent evaluations) on 100 data sets of 100 fibers: the interval covers the true
    # 0.08 in 88-99 % of them. (In one measurement on this stand-in, a percentile
    # bootstrap of the argmin over the same evaluations covered it in 84 of 100: the
    # argmin of a step-like mean loss barely moves under resampling.)
    hits = _covered(_ClassFlip, 100, 0.05, 1,
                    lambda d: pd.DataFrame({"class": np.where(d > 0.3, "Above", "Below")}),
                    "class")  # fmt: skip
    assert 0.88 <= hits / 100 <= 0.99


def test_slope_estimate_of_a_quadratic_profile_is_its_minimiser():
    # per-fiber loss (v - mu_i)^2: the mean slope between evaluated values is linear in
    # the midpoint with the same spread everywhere, so the zero of T is mean(mu) exactly,
    # whatever the evaluated values. Tolerance: the read-out grid's step (0.6 / 400).
    from fibersweep.discrepancy.estimate import slope_estimate

    rng = np.random.default_rng(3)
    mu = rng.normal(0.3, 0.1, 50)
    for grid in (np.linspace(0.0, 0.6, 5), np.array([0.0, 0.1, 0.22, 0.41, 0.6])):
        fit = _quadratic_fit(mu, grid)
        fit = type(fit)(fit.name, 0.41, 0.0, 0.0, (), fit.profile)
        assert slope_estimate(fit) == pytest.approx(mu.mean(), abs=0.6 / 400)


def _lucky_profile(rng: np.random.Generator, truth: float, xs: np.ndarray, n: int = 60):
    """Quadratic per-fiber losses around ``truth`` (spread 0.5), plus the step of one fiber
    whose two copies switch branch (contact or not): its loss drops by 40 past 0.85,
    30 times a typical fiber's change, so the best evaluated value is the one past it."""
    from fibersweep.discrepancy.estimate import Fit

    mu = rng.normal(truth, 0.5, n)
    L = (xs[:, None] - mu[None, :]) ** 2
    L[:, 0] -= 40.0 * (xs > 0.85)
    best = float(xs[np.argmin(L.mean(axis=1))])
    return Fit("pillar_hydro", best, 0.0, 0.0, (), tuple(zip(xs, L, strict=True)))


def test_slope_estimate_is_not_pulled_to_one_fibers_lucky_step():
    # The pooled refit's evaluated values in the case (pillar_hydro 0.6: the
    # halves 0.64, 0.71 and Brent's golden-section points of [0, 1.46]); one fiber's step
    # makes 0.902 the best evaluated value, the value reported before. The estimate
    # stays within 0.1 of the truth on average over 200 data sets (measured bias +0.07;
    # the best evaluated value: 0.30) and inside the interval reported with it.
    from fibersweep.discrepancy.estimate import score_interval, slope_estimate

    rng = np.random.default_rng(11)
    xs = np.array([0.0, 0.558, 0.64, 0.71, 0.902, 1.2])
    best, est = [], []
    for _ in range(200):
        fit = _lucky_profile(rng, 0.6, xs)
        e = slope_estimate(fit)
        lo, hi, _, _ = score_interval(type(fit)(fit.name, e, 0.0, 0.0, (), fit.profile))
        assert lo <= e <= hi
        best.append(fit.value)
        est.append(e)
    assert abs(np.mean(est) - 0.6) < 0.1
    assert np.mean(best) - 0.6 > 0.2  # the argmin's bias this stand-in reproduces


def test_slope_estimate_keeps_a_baseline_fit_at_zero():
    from fibersweep.discrepancy.estimate import Fit, slope_estimate

    prof = tuple((v, np.full(10, 1.0 + v)) for v in (0.0, 0.2, 0.4))
    assert slope_estimate(Fit("friction", 0.0, 1.0, 1.0, (), prof)) == 0.0


class _Spread:
    """A random effect on δ: copy k of fiber i = x_i + 0.02 sqrt(1 + v^2) z_ik (start noise
    widening the outcome; common random numbers: the same z_ik at every value v)."""

    def __init__(self, x: np.ndarray, rng: np.random.Generator, m: int = 8):
        self.x = x
        self.z = rng.standard_normal((m, len(x)))

    def copies(self, ks, effects=None, rows=None, desc=""):
        return [self.copy(k, effects, rows, desc) for k in ks]

    def copy(self, k, effects=None, rows=None, desc=""):
        v = float((effects or {}).get("start_noise", 0.0))
        idx = np.arange(len(self.x)) if rows is None else rows
        return pd.DataFrame({"delta": self.x[idx] + 0.02 * np.sqrt(1 + v**2) * self.z[k, idx]})


def _spread_case(rng: np.random.Generator, truth: float = 2.5, n: int = 60):
    """One stand-in data set of start noise ``truth``: fibers at x_i ~ U(0, 0.5), the
    :class:`_Spread` model (its copies' draws), the observed δ with the effect, and the
    model's 8 baseline copies. Draws in that order from ``rng``."""
    x = rng.uniform(0.0, 0.5, n)
    model = _Spread(x, rng)
    observed = pd.DataFrame({"delta": x + 0.02 * np.sqrt(1 + truth**2) * rng.standard_normal(n)})
    return model, observed, [model.copy(k) for k in range(8)]


def test_random_effect_is_fitted_where_the_data_are_as_spread_as_its_copies():
    # start_noise = 2.5 on the stand-in: 60 data sets of 60 fibers, 8 copies, 5 Brent
    # steps, as the workflow fits a random lead. The quoted value is the crossing of 1 by
    # the mean dispersion score (exact for any number of copies at the truth); its
    # interval from the t test of that score. Stated: mean within 0.3 of 2.5 (measured
    # 2.53, sd 0.45), coverage of the 95 % interval 0.85-1.0 (measured 57 of 60;
    # binomial 3 sd of 60 draws at 0.95 is 0.08), no fit at 0.
    from fibersweep.discrepancy.estimate import score_interval

    rng = np.random.default_rng(21)
    vals, hits = [], 0
    for _ in range(60):
        model, observed, base = _spread_case(rng)
        fit = fit_effect(LIBRARY["start_noise"], model, observed, base, np.arange(60),
                         ["delta"], {"delta": 1.0}, max_evals=5, estimate=True)  # fmt: skip
        lo, hi, _, _ = score_interval(fit)
        assert lo <= fit.value <= hi
        vals.append(fit.value)
        hits += lo <= 2.5 <= hi
    assert abs(np.mean(vals) - 2.5) < 0.3
    assert 0.85 <= hits / 60 <= 1.0
    assert min(vals) > 0.0


def test_pooled_refit_brackets_a_random_effects_root():
    # The halves of a random effect often come back low (their Brent search of the flat
    # score loss stops below the dispersion root: on the simulator a half returned 3.09,
    # the golden point 0.618 x 5, for a truth of 3.68). Here the halves are 1.4 and 1.7
    # for a truth of 2.5 (60 data sets of 60 fibers, 8 copies, 3 Brent steps in the
    # refit range [0.15, 2.95]). Without a bracket the root was read at the highest
    # evaluated value in 38 of 60 (seed 61; 35 on seed 62) and the interval covered
    # 2.5 in 0 of 60; keeping one step for the range's end, the interval covered it in
    # 50 and 53 of 60 (seeds 61, 62), mean 2.40 and 2.42. Stated: with the bracket
    # coverage >= 0.70 (3 binomial sd of 60 draws below the 0.85 measured) and the mean
    # within 0.25 of the truth; without it, coverage <= 0.10. The root beyond 2.95 (the
    # range's end) stays out of reach: 7 of 60 still sat at the end.
    from fibersweep.discrepancy.estimate import score_interval
    from fibersweep.discrepancy.fit import refit_bounds

    cand = LIBRARY["start_noise"]
    halves = [1.4, 1.7]
    out = {}
    for bracket in (False, True):
        rng = np.random.default_rng(61)
        vals, hits = [], 0
        for _ in range(60):
            model, observed, base = _spread_case(rng)
            fit = fit_effect(cand, model, observed, base, np.arange(60), ["delta"], {"delta": 1.0},
                             3, bounds=refit_bounds(cand, halves), known=halves, estimate=True,
                             bracket_root=bracket)  # fmt: skip
            lo, hi, _, _ = score_interval(fit)
            vals.append(fit.value)
            hits += lo <= 2.5 <= hi
        out[bracket] = (np.mean(vals), hits / 60)
    assert out[True][1] >= 0.70 and abs(out[True][0] - 2.5) <= 0.25
    assert out[False][1] <= 0.10


class _Friction:
    """A shift effect near the top of its range: copy k of fiber i = x_i + 0.1 v + 0.02 z_ik
    (friction v in [0, 1]; common random numbers: the same z_ik at every value)."""

    def __init__(self, x: np.ndarray, rng: np.random.Generator):
        self.x = x
        self.z = rng.standard_normal((2, len(x)))

    def copies(self, ks, effects=None, rows=None, desc=""):
        return [self.copy(k, effects, rows, desc) for k in ks]

    def copy(self, k, effects=None, rows=None, desc=""):
        v = float((effects or {}).get("friction", 0.0))
        return pd.DataFrame({"delta": self.x + 0.1 * v + 0.02 * self.z[k]})


def _refit_coverage(
    truth: float, halves: list[float], bracket: bool, close: bool = False, seed: int = 71
) -> tuple[float, int, list]:
    """Pooled refits of 60 stand-in data sets (40 fibers, 2 copies, 3 Brent steps): the
    mean quoted value, how many 95 % score intervals hold ``truth``, the fits. ``close``:
    the steps after the search that read the interval's ends (off: the bracket alone)."""
    from fibersweep.discrepancy.estimate import score_interval
    from fibersweep.discrepancy.fit import refit_bounds

    cand = LIBRARY["friction"]
    rng = np.random.default_rng(seed)
    vals, hits, fits = [], 0, []
    for _ in range(60):
        x = rng.uniform(0.0, 0.5, 40)
        model = _Friction(x, rng)
        observed = pd.DataFrame({"delta": x + 0.1 * truth + 0.02 * rng.standard_normal(40)})
        base = [model.copy(k) for k in range(2)]
        fit = fit_effect(cand, model, observed, base, np.arange(40), ["delta"], {"delta": 1.0},
                         3, bounds=refit_bounds(cand, halves), known=halves, estimate=True,
                         bracket_root=bracket, close_interval=close)  # fmt: skip
        lo, hi, _, _ = score_interval(fit)
        vals.append(fit.value)
        fits.append(fit)
        hits += lo <= truth <= hi
    return float(np.mean(vals)), hits, fits


def test_pooled_refit_brackets_a_shift_effects_root_near_the_range_end():
    # As on the simulator (scripts/studies/discrepancy/study_coverage.py: every friction miss had a
    # truth of
    # 0.89-0.97, 28 of 32 intervals open at the top): the halves 0.70 and 0.76 for a
    # truth of 0.93, refit range [0.45, 1.0]. Brent's 3 steps stop at 0.87 with the
    # loss still falling; without the bracket the estimate sat there in all 60 data
    # sets and no interval held 0.93 (0 of 60). Keeping one step for the range's end:
    # 54, 54, 51, 54 of 60 (seeds 71-74), mean 0.97 (the zero of T is read between
    # 0.87 and 1.0 only). Stated: with the bracket coverage >= 0.78 (0.90 measured less
    # 3 binomial sd of 60 draws, 0.12), without it <= 0.10.
    mean_off, hits_off, _ = _refit_coverage(0.93, [0.70, 0.76], bracket=False)
    mean_on, hits_on, _ = _refit_coverage(0.93, [0.70, 0.76], bracket=True)
    assert hits_off / 60 <= 0.10
    assert hits_on / 60 >= 0.78
    assert abs(mean_on - 0.93) < abs(mean_off - 0.93) + 0.05


def test_shift_bracket_keeps_the_step_for_brent_when_the_root_is_bracketed():
    from fibersweep.discrepancy.fit import refit_bounds

    # A truth between the halves (0.6; halves 0.55, 0.65): the root is bracketed by
    # Brent's steps in most data sets and the kept step goes back to Brent, which repeats
    # its cached steps and takes one more (same run count). A data set where the bracket
    # is not needed gets the unbracketed fit exactly (same evaluated values and value).
    # Measured: 59 vs 58 of 60 (seed 71) covered. Stated: coverage >= 0.85 either way
    # (0.95 less 3 binomial sd of 60, 0.08); never more than the budget's evaluated
    # values (the baseline, the 2 halves, 3 steps).
    _, hits_off, off = _refit_coverage(0.6, [0.55, 0.65], bracket=False)
    _, hits_on, on = _refit_coverage(0.6, [0.55, 0.65], bracket=True)
    assert hits_off / 60 >= 0.85 and hits_on / 60 >= 0.85
    same = 0
    end = refit_bounds(LIBRARY["friction"], [0.55, 0.65])[1]
    for f0, f1 in zip(off, on, strict=True):
        assert len(f1.evaluations) <= 1 + 2 + 3
        if end not in dict(f1.evaluations):  # not bracketed: the unbracketed fit
            assert f1.evaluations == f0.evaluations and f1.value == f0.value
            same += 1
    assert same > 0


def test_pooled_refit_reads_an_open_interval_at_the_effects_range_end():
    # Halves far below the truth (0.55, 0.60 for 0.95: refit range [0.30, 0.85]): the
    # bracket evaluates 0.85, the loss still falls there and every evaluated value is
    # rejected. Without the interval step no interval held 0.95 (0 of 60, seed 71);
    # with it, the effect's range end 1.0 is evaluated and the test reads the stretch
    # up to it: 56 of 60 (0.93). Stated: >= 0.80 (0.93 less 4 binomial sd of 60, 0.13);
    # never more than INTERVAL_EVALS evaluations beyond the unclosed fit's.
    from fibersweep.discrepancy.settings import INTERVAL_EVALS

    _, hits_off, off = _refit_coverage(0.95, [0.55, 0.60], bracket=True, close=False)
    mean_on, hits_on, on = _refit_coverage(0.95, [0.55, 0.60], bracket=True, close=True)
    assert hits_off == 0
    assert hits_on / 60 >= 0.80
    assert abs(mean_on - 0.95) < 0.05
    for f0, f1 in zip(off, on, strict=True):
        assert len(f0.evaluations) < len(f1.evaluations) <= len(f0.evaluations) + INTERVAL_EVALS


def test_interval_step_evaluates_only_closed_ends_no_value_is_near():
    # The interval's closed ends are evaluated unless an evaluated value lies within a
    # twentieth of the evaluated range (it would be merged with it): a quadratic profile
    # evaluated at 0, 0.3, 0.6 has its ends at mean(mu) ± t SE, both far from them.
    from fibersweep.discrepancy.estimate import score_interval
    from fibersweep.discrepancy.fit import _unread_ends

    mu = np.random.default_rng(9).normal(0.3, 0.2, 40)
    fit = _quadratic_fit(mu, np.array([0.0, 0.3, 0.6]))
    lo, hi, _, _ = score_interval(fit)
    assert _unread_ends(fit) == [lo, hi]
    near = _quadratic_fit(mu, np.array([0.0, lo + 0.01, 0.3, 0.6]))
    assert _unread_ends(near) == [score_interval(near)[1]]
