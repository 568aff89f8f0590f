"""A pair's members get the single effect's refit and interval (issue 30, item 2).

Stand-in with a known truth (friction 0.5 + inlet_speed 0.05, coupled as on the
simulator: friction moves δ and slows the pass a little, a faster inlet only speeds
it up), δ and t_pass observed with noise and each copy drawn with noise of its own
(common random numbers across values), 60 fibers in two folds, 2 fit copies, the
workflow's joint fit (2 rounds, 5 Brent steps) on each fold and
:func:`pairs.pair_refits` (3 Brent steps), as :func:`pairs.forward_pairs` runs
them.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from fibersweep.discrepancy.candidates import LIBRARY
from fibersweep.discrepancy.estimate import score_interval
from fibersweep.discrepancy.fit import fold_fits
from fibersweep.discrepancy.pairs import SelectionInput, joint_fit, pair_refits

TRUTH = {"friction": 0.5, "inlet_speed": 0.05}
SD_DELTA, SD_LOG_T = 0.02, 0.02
OBS = ("delta", "t_pass")


class _NoisyPair:
    """Copy k of fiber i: δ = x_i + 0.1 f + 0.02 z, t_pass = T_i (1 + 0.04 f) / (1 + s)
    e^{0.02 z'} (rows honoured; the same z at every value)."""

    def __init__(self, x: np.ndarray, t: np.ndarray, rng: np.random.Generator):
        self.x, self.t = x, t
        self.z = rng.standard_normal((2, 2, len(x)))

    def copies(self, ks, effects=None, rows=None, desc=""):
        return [self.copy(k, effects, rows, desc) for k in ks]

    def copy(self, k, effects=None, rows=None, desc=""):
        e = effects or {}
        f, s = float(e.get("friction", 0.0)), float(e.get("inlet_speed", 0.0))
        i = np.arange(len(self.x)) if rows is None else np.asarray(rows)
        return pd.DataFrame(
            {
                "delta": self.x[i] + 0.1 * f + SD_DELTA * self.z[0, k, i],
                "t_pass": self.t[i] * (1 + 0.04 * f) / (1 + s) * np.exp(SD_LOG_T * self.z[1, k, i]),
            }
        )


def _pair_fit(rng: np.random.Generator, n: int = 60):
    """One data set: the forward step's fits of the true pair; (values, intervals)."""
    x, t = rng.uniform(0.0, 0.5, n), rng.uniform(0.5, 2.0, n)
    model = _NoisyPair(x, t, rng)
    f, s = TRUTH["friction"], TRUTH["inlet_speed"]
    observed = pd.DataFrame(
        {
            "delta": x + 0.1 * f + SD_DELTA * rng.standard_normal(n),
            "t_pass": t * (1 + 0.04 * f) / (1 + s) * np.exp(SD_LOG_T * rng.standard_normal(n)),
        }
    )
    perm = rng.permutation(n)
    folds = [np.sort(perm[: n // 2]), np.sort(perm[n // 2 :])]
    first, second = LIBRARY["inlet_speed"], LIBRARY["friction"]
    w = {"delta": 1.0, "t_pass": 1.0}
    base = model.copies(range(2))
    single = fold_fits(first, model, observed, base, folds, OBS, w, 5, side=1.0)
    inp = SelectionInput(
        observed=observed, folds=folds, fold_values={}, base_values={}, single_values={},
        weights=w, observables=OBS, copies=2, fit_copies=2, fit_evals=5, alpha=0.05,
        n_perm=99, rounds=2, refit_evals=3,
    )  # fmt: skip
    per_fold = [
        joint_fit(first, second, {first.name: single[f_].value, second.name: 0.0},
                  folds[1 - f_], inp, model)  # fmt: skip
        for f_ in range(2)
    ]
    fold = {m: [pf[m] for pf in per_fold] for m in TRUTH}
    fits = []
    values, ivs = pair_refits((second, first), fold, inp, model, fits.append)
    return values, ivs, fits


def test_each_member_gets_the_single_effects_interval_of_its_refit():
    values, ivs, fits = _pair_fit(np.random.default_rng(5))
    assert [f.name for f in fits] == ["friction", "inlet_speed"]
    for fit in fits:
        # the same read-out as a single effect's pooled refit: score_interval of its fit,
        # which holds the quoted value
        assert ivs[fit.name] == score_interval(fit)
        lo, hi, _, _ = ivs[fit.name]
        assert lo <= values[fit.name] == fit.value <= hi


def test_pair_intervals_cover_the_truth():
    # 100 data sets (seed 40): each member's interval covers its truth at 95 % within
    # the binomial 3 sd of 100 draws, 0.065 (stated 0.07); measured 0.93 (friction)
    # and 0.97 (inlet_speed), on seed 41 0.97 and 0.93. The quoted values are unbiased
    # to within 2 standard errors of their mean over the 100 sets (measured: within
    # 1). With inlet_speed refitted first, friction held at its folds' mean (0.062
    # low), inlet_speed came out 0.0025 low (7 standard errors) and covered 0.90 and
    # 0.79 (seeds 40, 41): pairs.pair_refits' order.
    rng = np.random.default_rng(40)
    vals = {m: [] for m in TRUTH}
    cover = {m: [] for m in TRUTH}
    for _ in range(100):
        values, ivs, _ = _pair_fit(rng)
        for m, truth in TRUTH.items():
            vals[m].append(values[m])
            cover[m].append(ivs[m][0] <= truth <= ivs[m][1])
    for m, truth in TRUTH.items():
        v = np.array(vals[m])
        assert abs(np.mean(cover[m]) - 0.95) <= 0.07, (m, np.mean(cover[m]))
        assert abs(v.mean() - truth) <= 2 * v.std(ddof=1) / np.sqrt(len(v)) + 1e-4, m


def test_report_table_shows_each_members_interval():
    from fibersweep.discrepancy.report_text import _fits

    st = {
        "set": "inlet_speed + friction", "values": {"inlet_speed": 0.049, "friction": 0.51},
        "halves": {"inlet_speed": [0.047, 0.052], "friction": [0.44, 0.46]},
        "interval95": {"inlet_speed": [0.043, 0.056], "friction": [0.43, 0.6]},
        "interval95_open": {"inlet_speed": [False, False], "friction": [False, True]},
        "gains": {m: {"mean": 0.3, "lo95": 0.1, "hi95": 0.5} for m in TRUTH},
        "p_holm": {"inlet_speed": 0.001, "friction": 0.002}, "explains": True,
    }  # fmt: skip
    sig = [{"effect": "inlet_speed", "probe": 0.15, "cosine": 0.9, "strength": 3.0}]
    text = "\n".join(_fits({"signatures": sig, "heldout": [], "sets": [st]}))
    assert "inlet_speed = 0.049 [0.043, 0.056] (0.047, 0.052)" in text
    assert "friction = 0.51 [0.43, ≥ 0.6] (0.44, 0.46)" in text
    # which ranked effects were fitted, from the plan in the summary's settings
    plan = {"candidates": 3, "tied": 2}
    text = "\n".join(_fits({"signatures": sig, "heldout": [], "sets": [], "settings": plan}))
    assert "The 3 best matches with a positive cosine are fitted, and up to 2 more" in text
    assert "more whose cosine" not in "\n".join(_fits({"signatures": sig, "heldout": [], "sets": [],
                                           "settings": {"candidates": 3, "tied": 0}}))  # fmt: skip
    # a set that was not refitted (not significant) has no interval
    del st["interval95"], st["interval95_open"]
    assert "inlet_speed = 0.049 (0.047, 0.052)" in "\n".join(
        _fits({"signatures": sig, "heldout": [], "sets": [st]})
    )


def test_plan_counts_the_pair_refits():
    # per pair: each member's refit is the other member alone (its value 0), the two
    # folds' values, refit_evals Brent steps and up to INTERVAL_EVALS evaluations for the
    # interval's ends on all fibers, fit_copies copies each
    from fibersweep.discrepancy.candidates import get_candidates
    from fibersweep.discrepancy.settings import INTERVAL_EVALS, DiscrepancySettings, plan_budget

    plan = plan_budget(100, DiscrepancySettings(), get_candidates())
    joint = 2 * plan.pair_rounds * (plan.fit_evals + 2) * plan.fit_copies * 50
    held = 3 * plan.copies * 100
    refits = 2 * (3 + plan.refit_evals + INTERVAL_EVALS) * plan.fit_copies * 100
    assert plan.cost(100)["pairs"] == plan.pairs * (joint + held + refits)
