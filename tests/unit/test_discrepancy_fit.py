"""The 1D effect fit on a stand-in model whose outcome is known in closed form."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from fibersweep.discrepancy.fit import fit_effect
from fibersweep.discrepancy.library import LIBRARY


class _ShiftModel:
    """δ of copy k = x_i + value + 0.01 z_ik: an effect that shifts δ by its value."""

    def __init__(self, n: int):
        rng = np.random.default_rng(0)
        self.x = rng.uniform(0.0, 0.5, n)
        self.z = rng.standard_normal((4, n))
        self.calls = 0

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
    from fibersweep.discrepancy.fit import Fit

    prof = tuple((float(v), (v - mu) ** 2) for v in grid)
    return Fit("friction", float(mu.mean()), 0.0, 0.0, (), prof)


def test_bootstrap_interval_of_a_quadratic_profile_matches_the_analytic_one():
    # per-fiber loss (v - mu_i)^2: the fitted value is mean(mu), its standard error
    # sd(mu) / sqrt(n); the parabola through three evaluated values is exact, so five
    # values suffice. Width within 10 % of 2 x 1.96 x SE (2000 resamples).
    from fibersweep.discrepancy.fit import bootstrap_interval

    rng = np.random.default_rng(3)
    n = 50
    mu = rng.normal(0.3, 0.1, n)
    lo, hi = bootstrap_interval(_quadratic_fit(mu, np.linspace(0.0, 0.6, 5)), rng)
    se = mu.std() / np.sqrt(n)
    assert lo < mu.mean() < hi
    assert hi - lo == pytest.approx(2 * 1.96 * se, rel=0.10)
    assert (lo + hi) / 2 == pytest.approx(mu.mean(), abs=0.3 * se)
    # a fit that reports its best evaluated value (0.3) gets an interval around that value
    from dataclasses import replace

    lo2, hi2 = bootstrap_interval(replace(_quadratic_fit(mu, np.linspace(0.0, 0.6, 5)),
                                          value=0.3), rng)  # fmt: skip
    assert lo2 < 0.3 < hi2 and hi2 - lo2 == pytest.approx(hi - lo, rel=0.10)


def test_bootstrap_interval_covers_the_truth_at_its_level():
    # 200 data sets of 40 fibers: the 95 % interval covers the true 0.3 in 90-99 % of them
    from fibersweep.discrepancy.fit import bootstrap_interval

    rng = np.random.default_rng(4)
    grid = np.linspace(0.0, 0.6, 5)
    hits = 0
    for _ in range(200):
        lo, hi = bootstrap_interval(_quadratic_fit(rng.normal(0.3, 0.1, 40), grid), rng, 500)
        hits += lo <= 0.3 <= hi
    assert 0.90 <= hits / 200 <= 0.99
