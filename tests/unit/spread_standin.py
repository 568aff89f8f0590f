"""Gaussian stand-in of the whole decision for random effects (tests only)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from fibersweep.discrepancy.decide import Verdict, decide
from fibersweep.discrepancy.library import get_candidates
from fibersweep.discrepancy.settings import DiscrepancySettings, plan_budget
from fibersweep.discrepancy.workflow import Run, cross_fit, noise_floor, rank, refit

SIGMA = 0.02  # sd of δ of a copy without start noise
SHIFT = 0.2  # δ shift per unit of inlet_speed


class SpreadModel:
    """δ of copy k of fiber i = x_i + SHIFT v_inlet + SIGMA sqrt(1 + v_sn^2) z_ik.

    start_noise widens the outcome (a random effect), inlet_speed shifts it; the
    draws z_ik are fixed per data set (common random numbers across values), as the
    copy maker's seeds are.
    """

    def __init__(self, x: np.ndarray, rng: np.random.Generator, m: int = 40):
        self.x = x
        self.z = rng.standard_normal((m, len(x)))

    def copies(self, ks, effects=None, rows=None, desc=""):
        return [self.copy(k, effects, rows, desc) for k in ks]

    def copy(self, k, effects=None, rows=None, desc=""):
        e = effects or {}
        sn, sh = float(e.get("start_noise", 0.0)), float(e.get("inlet_speed", 0.0))
        idx = np.arange(len(self.x)) if rows is None else np.asarray(rows)
        d = self.x[idx] + SHIFT * sh + SIGMA * np.sqrt(1.0 + sn**2) * self.z[k, idx]
        return pd.DataFrame({"delta": d})


def observed(x: np.ndarray, hidden: dict, rng: np.random.Generator) -> pd.DataFrame:
    """Measured-like table: δ drawn as one more copy with the hidden effects, plus the
    localisation features."""
    sn, sh = float(hidden.get("start_noise", 0.0)), float(hidden.get("inlet_speed", 0.0))
    d = x + SHIFT * sh + SIGMA * np.sqrt(1.0 + sn**2) * rng.standard_normal(len(x))
    n = len(x)
    return pd.DataFrame({"delta": d, "theta0": rng.uniform(-90, 90, n), "y0": x,
                         "length": np.full(n, 1.0), "contact": np.zeros(n)})  # fmt: skip


def verdict(hidden: dict, library: list[str], n: int, seed: int, n_perm: int = 499):
    """The workflow's stages (no pairs) on one stand-in data set; returns (Verdict, State)."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(0.0, 0.5, n)
    model = SpreadModel(x, rng)
    obs = observed(x, hidden, rng)
    s = DiscrepancySettings(n_perm=n_perm, pairs=0, seed=seed)
    cands = get_candidates(library)
    plan = plan_budget(n, s, cands)
    run_rng = np.random.default_rng([seed, 11])
    perm = run_rng.permutation(n)
    folds = [np.sort(perm[: n // 2]), np.sort(perm[n // 2 :])]
    run = Run(s, plan, cands, obs, ("delta",), folds, run_rng, model)
    st = noise_floor(run)
    if st.gap.any:
        st = refit(cross_fit(rank(st)))
    v: Verdict = decide(st.gap, list(st.heldout), st.region_text, run_rng, s.alpha, [])
    return v, st
