"""The refit's 95 % interval: a bootstrap over the fibers of the mean loss's minimiser.

Stand-ins with a known truth: per-fiber quadratic losses (v - mu_i)^2, whose minimiser
is mean(mu), so the interval must be Student's mean(mu) ± t SE(mu); plus the read-out's
edge cases (open ends, a flat minimum, a step-like loss).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import t as student_t

from fibersweep.discrepancy.estimate import (
    Fit,
    bootstrap_minimisers,
    expanded_tail,
    minimiser_ends,
    score_interval,
)


def _quadratic_fit(mu: np.ndarray, grid, value: float | None = None) -> Fit:
    prof = tuple((float(v), (v - mu) ** 2) for v in grid)
    return Fit("friction", float(mu.mean() if value is None else value), 0.0, 0.0, (), prof)


def _symmetric(rng: np.random.Generator, n: int, centre: float, sd: float) -> np.ndarray:
    """n values placed symmetrically about ``centre``: a sample without skewness, so
    the bootstrap's distribution of its mean is symmetric too."""
    h = rng.normal(0.0, sd, n // 2)
    return centre + np.concatenate([h, -h])


def test_expanded_tail_is_students_interval_read_as_a_percentile():
    # Phi(-sqrt(n / (n - 1)) t_{n-1}(0.975)): 0.0159 at n = 20, toward 0.025 as n grows
    assert expanded_tail(20) == pytest.approx(0.0159, abs=1e-4)
    assert expanded_tail(200) == pytest.approx(0.0240, abs=1e-4)
    assert expanded_tail(100_000) == pytest.approx(0.025, abs=1e-4)
    with pytest.raises(ValueError, match="at least 2"):
        expanded_tail(1)


@pytest.mark.parametrize("n", [20, 60, 200])
@pytest.mark.parametrize("grid", [[0.0, 0.15, 0.3, 0.45, 0.6], [0.0, 0.08, 0.21, 0.45, 0.6]])
def test_interval_of_a_quadratic_profile_is_students(n, grid):
    # Each fiber's slope between evaluated values is 2 (midpoint - mu_i), linear in the
    # midpoint, so every resample's minimiser is its mean of mu exactly, on any
    # evaluated values: the interval is the expanded percentile interval of a
    # bootstrapped mean, Student's mean ± t SE for a sample without skewness. Tolerance
    # 0.2 SE on each end: the Monte Carlo error of a 1.6 % quantile of 4000 resamples
    # is 0.05 SE (sqrt(p (1 - p) / B) / phi(z_p)), 0.2 SE four of those.
    rng = np.random.default_rng(3 + n)
    mu = _symmetric(rng, n, 0.3, 0.1)
    lo, hi, open_lo, open_hi = score_interval(_quadratic_fit(mu, np.array(grid)))
    se = mu.std(ddof=1) / np.sqrt(n)
    half = student_t.ppf(0.975, n - 1) * se
    assert lo == pytest.approx(mu.mean() - half, abs=0.2 * se)
    assert hi == pytest.approx(mu.mean() + half, abs=0.2 * se)
    assert not open_lo and not open_hi


def test_interval_covers_the_truth_at_its_level():
    # 200 data sets of 20 normal per-fiber minima mu_i ~ N(0.3, 0.1): coverage of 0.3
    # within 0.90-0.99 (0.95 ± 3 binomial sd of 200 draws, 0.046). No factor: the
    # expanded percentile's tail follows from n. 1000 resamples (not 4000) keep the
    # test fast; their Monte Carlo error is part of what the coverage measures.
    rng = np.random.default_rng(4)
    grid = np.linspace(0.0, 0.6, 5)
    hits = 0
    for _ in range(200):
        fit = _quadratic_fit(rng.normal(0.3, 0.1, 20), grid)
        lo, hi, _, _ = score_interval(fit, n_boot=1000)
        hits += lo <= 0.3 <= hi
    assert 0.90 <= hits / 200 <= 0.99


def test_interval_covers_the_truth_of_skewed_minima():
    # Skewed per-fiber minima (mu_i = 0.2 + exponential of mean 0.1, 60 fibers, 200 data
    # sets): the percentile interval follows the skewness of the mean's distribution.
    # Coverage of the true mean 0.3 within 0.90-0.99, as above (1000 resamples).
    rng = np.random.default_rng(14)
    grid = np.array([0.0, 0.1, 0.25, 0.4, 0.6])
    hits = 0
    for _ in range(200):
        fit = _quadratic_fit(0.2 + rng.exponential(0.1, 60), grid)
        lo, hi, _, _ = score_interval(fit, n_boot=1000)
        hits += lo <= 0.3 <= hi
    assert 0.90 <= hits / 200 <= 0.99


def test_interval_is_deterministic():
    # the resamples are drawn from a seed made of the profile: the same fit, the same interval
    mu = np.random.default_rng(5).normal(0.3, 0.1, 30)
    fit = _quadratic_fit(mu, np.linspace(0.0, 0.6, 5))
    assert score_interval(fit) == score_interval(_quadratic_fit(mu.copy(), np.linspace(0, 0.6, 5)))


def test_interval_is_open_where_the_minimisers_pile_at_an_end():
    # The truth far beyond the evaluated values 0, 0.15, ..., 0.6: every resample's
    # minimiser is the highest one, which shows only that the loss falls from 0.45 to
    # 0.6, so the interval runs from 0.45 and is open at the top.
    mu = np.random.default_rng(6).normal(1.5, 0.05, 40)
    lo, hi, open_lo, open_hi = score_interval(_quadratic_fit(mu, np.linspace(0.0, 0.6, 5), 0.6))
    assert lo == pytest.approx(0.45) and hi == 0.6 and open_hi and not open_lo
    # mirrored: the loss still falls at the lowest value
    fit = _quadratic_fit(-mu + 0.6, np.linspace(0.0, 0.6, 5), 0.0)
    lo, hi, open_lo, open_hi = score_interval(fit)
    assert lo == 0.0 and hi == pytest.approx(0.15) and open_lo and not open_hi


def test_interval_is_open_where_the_evaluated_values_stop():
    # the minimum near the edge of the searched range (mean(mu) about 0.55, SE 0.016):
    # more than the tail's share of resamples minimise at 0.6, the end, so it is open there
    mu = np.random.default_rng(5).normal(0.55, 0.1, 40)
    lo, hi, open_lo, open_hi = score_interval(_quadratic_fit(mu, np.linspace(0.0, 0.6, 5)))
    assert open_hi and hi == pytest.approx(0.6) and not open_lo and lo < 0.55


def test_a_flat_minimum_is_in_the_interval_whole():
    # Per-fiber loss constant on [0.2, 0.4] (no fiber changes there), rising outside.
    # The mean slope is negative at the midpoint 0.15, 0 at 0.25 and 0.35, positive at
    # 0.45: the mean loss's minimum is the whole stretch [0.25, 0.35] between the flat
    # midpoints, in every resample, so that is the interval (exact read-out: 1e-12).
    rng = np.random.default_rng(8)
    grid = np.array([0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    w = rng.uniform(0.5, 1.5, 30)
    prof = tuple((float(v), w * (max(0.2 - v, 0.0, v - 0.4) * 10) ** 2) for v in grid)
    lo, hi, open_lo, open_hi = score_interval(Fit("friction", 0.3, 0.0, 0.0, (), prof))
    assert lo == pytest.approx(0.25, abs=1e-12) and hi == pytest.approx(0.35, abs=1e-12)
    assert not open_lo and not open_hi


def test_interval_holds_the_value_of_a_step_like_loss():
    # Flat on [0, 0.3], then a drop every fiber shares between 0.3 and 0.4, the highest
    # evaluated value: the loss still falls there in every resample, so the interval runs
    # from 0.3 (where the fall starts) and is open at the top, holding the quoted value.
    rng = np.random.default_rng(2)
    n = 40
    base = rng.uniform(1.0, 2.0, n)
    prof = [(x, base.copy()) for x in (0.0, 0.1, 0.2, 0.3)]
    prof.append((0.4, base - rng.uniform(0.5, 1.0, n)))
    fit = Fit("friction", 0.4, float(prof[-1][1].mean()), float(base.mean()), (), tuple(prof))
    lo, hi, open_lo, open_hi = score_interval(fit)
    assert lo == pytest.approx(0.3) and hi == 0.4 and open_hi and not open_lo


@pytest.mark.parametrize("studentise", [True, False])
def test_exact_read_out_matches_the_grid(studentise):
    # minimiser_ends reads Λ's minimum exactly; bootstrap_minimisers on a grid of 4001
    # points must agree within one grid step (plus round-off) on resampled random
    # profiles, smooth and (the mean slope) step-like. A step-like profile's t statistic
    # is +-1e6 where no fiber's slope varies, and the grid's trapezoid rule across such a
    # kink is off by more than a step: there the exact read-out is the reference.
    rng = np.random.default_rng(12)
    for _ in range(20):
        n, k = 25, int(rng.integers(2, 8))
        x = np.sort(rng.uniform(0.0, 1.0, k))
        mu = rng.normal(0.5, 0.3, n)
        L = (x[:, None] - mu[None, :]) ** 2 * rng.uniform(0.5, 2.0, n)
        if rng.random() < 0.5 and not studentise:
            L = np.round(L * 3) / 3  # step-like, with flat stretches
        counts = rng.multinomial(n, np.full(n, 1.0 / n), size=50)
        v = np.linspace(x[0], x[-1], 4001)
        i_lo, i_hi = bootstrap_minimisers(x, L, counts, v, studentise)
        lo, hi = minimiser_ends(x, L, counts, studentise)
        step = (x[-1] - x[0]) / 4000 + 1e-12
        assert np.all(np.abs(v[i_lo] - lo) <= step) and np.all(np.abs(v[i_hi] - hi) <= step)
