"""The discrepancy workflow: noise floor, gap, localisation, ranking, fit, held-out decision.

:func:`run_discrepancy` is the library entry point of ``fibersweep discrepancy``.
It simulates (1) ``copies`` jittered baseline copies of every measured fiber,
(2) tests the gap per observable against them, (3) localises it, (4) probes,
ranks and fits the library's effects on a fit split, (5) compares the fitted
effects with the baseline on the held-out split and decides. The simulation
count is planned up front and never exceeds ``budget``.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pandas as pd

from fibersweep.discrepancy.copies import CopyMaker
from fibersweep.discrepancy.decide import HeldOut, Verdict, decide, evaluate_heldout
from fibersweep.discrepancy.fit import Fit, Signature, fit_effect, rank_effects
from fibersweep.discrepancy.gap import (
    GapResult,
    assess_gap,
    describe,
    feature_vector,
    observable_weights,
    value_matrices,
    weighted_loss,
)
from fibersweep.discrepancy.library import Candidate, get_candidates
from fibersweep.discrepancy.localise import FEATURES, Region, find_region
from fibersweep.discrepancy.noise import NoiseModel
from fibersweep.discrepancy.schema import MeasuredData
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.errors import InputError
from fibersweep.fiber.settings import FiberSettings
from fibersweep.flow.field import FlowField

__all__ = ["DiscrepancySettings", "DiscrepancyResult", "Plan", "plan_budget", "run_discrepancy"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class DiscrepancySettings:
    """Knobs of the workflow.

    Attributes
    ----------
    copies : int
        Jittered baseline copies per fiber (the noise floor); also the copies
        per held-out evaluation.
    fit_copies : int
        Copies per fiber per fit evaluation.
    candidates : int
        Effects fitted (the best-matching signatures).
    fit_evals : int
        Simulated evaluations per 1D fit.
    holdout : float
        Fraction of fibers held out for the decision.
    alpha : float
        Family-wise error rate of every test.
    budget : int or None
        Most simulations in total; None = what the plan needs.
    seed : int
    workers : int
    effects : tuple of str or None
        Library subset to consider (None = all).
    noise : NoiseModel
    n_perm : int
        Permutations per gap test.
    """

    copies: int = 4
    fit_copies: int = 2
    candidates: int = 3
    fit_evals: int = 5
    holdout: float = 0.5
    alpha: float = 0.05
    budget: int | None = None
    seed: int = 0
    workers: int = 2
    effects: tuple[str, ...] | None = None
    noise: NoiseModel = field(default_factory=NoiseModel)
    n_perm: int = 4999

    def __post_init__(self) -> None:
        checks = {
            "copies": self.copies >= 2,
            "fit_copies": self.fit_copies >= 1,
            "candidates": self.candidates >= 1,
            "fit_evals": self.fit_evals >= 1,
            "holdout": 0.1 <= self.holdout <= 0.9,
            "alpha": 0.0 < self.alpha < 0.5,
            "workers": self.workers >= 1,
        }
        for name, ok in checks.items():
            if not ok:
                raise InputError(f"discrepancy.{name}: invalid value {getattr(self, name)!r}")
        if self.budget is not None and self.budget < 1:
            raise InputError(f"discrepancy.budget: must be >= 1, got {self.budget}")


@dataclass(frozen=True)
class Plan:
    """How many simulations each step may use."""

    copies: int
    fit_copies: int
    candidates: int
    fit_evals: int
    probes: int
    n_fit: int
    n_heldout: int

    def cost(self, n: int) -> dict[str, int]:
        """Runs per step for n fibers."""
        return {
            "baseline": n * self.copies,
            "probes": self.probes * self.n_fit,
            "fits": self.candidates * self.fit_evals * self.fit_copies * self.n_fit,
            "heldout": self.candidates * self.copies * self.n_heldout,
        }

    def total(self, n: int) -> int:
        return sum(self.cost(n).values())


def plan_budget(n: int, s: DiscrepancySettings, candidates: list[Candidate]) -> Plan:
    """The most thorough plan within the budget (shrinks fits first, the noise floor last).

    Raises
    ------
    InputError
        If even the smallest plan (2 copies, one candidate, one evaluation) does not fit.
    """
    n_held = max(1, int(round(n * s.holdout)))
    n_fit = n - n_held
    probes = sum(len(c.probes) for c in candidates)
    plan = Plan(s.copies, s.fit_copies, min(s.candidates, len(candidates)), s.fit_evals,
                probes, n_fit, n_held)  # fmt: skip
    if s.budget is None:
        return plan
    shrink = [
        ("fit_evals", 3), ("fit_copies", 1), ("candidates", 2), ("fit_evals", 2),
        ("copies", 3), ("candidates", 1), ("fit_evals", 1), ("copies", 2),
    ]  # fmt: skip
    for attr, v in shrink:
        if plan.total(n) <= s.budget:
            return plan
        if getattr(plan, attr) > v:
            plan = replace(plan, **{attr: v})
    if plan.total(n) <= s.budget:
        return plan
    raise InputError(
        f"budget: {s.budget} simulations are too few for {n} fibers; the smallest plan "
        f"needs {plan.total(n)} ({plan.cost(n)})"
    )


@dataclass
class DiscrepancyResult:
    """Everything the report needs."""

    verdict: Verdict
    gap: GapResult
    descriptive: dict[str, Any]
    region: Region
    region_by_observable: dict[str, Region]
    signatures: list[Signature]
    fits: list[Fit]
    heldout: list[HeldOut]
    heldout_before: GapResult | None
    plan: Plan
    simulations: int
    failed_runs: int
    seconds: float
    observed: pd.DataFrame
    baseline_copies: list[pd.DataFrame]
    effect_copies: dict[str, list[pd.DataFrame]]
    heldout_rows: np.ndarray
    weights: dict[str, float]
    settings: DiscrepancySettings
    observables: tuple[str, ...]
    extra: dict[str, Any] = field(default_factory=dict)


def _features(table: pd.DataFrame) -> np.ndarray:
    cols = []
    for name in FEATURES:
        if name == "contact":
            cols.append(
                table["contact"].to_numpy(dtype=np.float64)
                if "contact" in table
                else np.zeros(len(table))
            )
        else:
            cols.append(table[name].to_numpy(dtype=np.float64))
    return np.column_stack(cols)


def _combined_excess(gap: GapResult, weights: dict[str, float]) -> np.ndarray:
    tot = None
    for name, e in gap.per_fiber.items():
        v = np.where(np.isfinite(e), e, 0.0) * weights.get(name, 0.0)
        tot = v if tot is None else tot + v
    return tot if tot is not None else np.zeros(0)


def _subset(dfs: list[pd.DataFrame], rows: np.ndarray) -> list[pd.DataFrame]:
    return [d.iloc[rows].reset_index(drop=True) for d in dfs]


def run_discrepancy(
    measured: MeasuredData,
    field_: FlowField,
    fiber: FiberSettings,
    settings: DiscrepancySettings | None = None,
    progress: bool = True,
) -> DiscrepancyResult:
    """Run the whole workflow (see the module docstring).

    Parameters
    ----------
    measured : MeasuredData
        Validated measurements.
    field_ : FlowField
        Baseline flow field.
    fiber : FiberSettings
        Baseline fiber settings (its ``effects`` must be empty or are the baseline).
    settings : DiscrepancySettings
    progress : bool
        tqdm progress bars.
    """
    s = settings or DiscrepancySettings()
    t0 = time.perf_counter()
    candidates = get_candidates(s.effects)
    n = len(measured)
    if n < 8:
        raise InputError(f"measured: {n} fibers are too few for a held-out split (need >= 8)")
    plan = plan_budget(n, s, candidates)
    log.info("plan: %s, total %d runs", plan.cost(n), plan.total(n))
    obs_names = tuple(o for o in measured.observed)
    observed = measured.table.reset_index(drop=True)
    rng = np.random.default_rng([s.seed, 11])
    perm = rng.permutation(n)
    held = np.sort(perm[: plan.n_heldout])
    fit_rows = np.sort(perm[plan.n_heldout :])

    with Simulator(field_, fiber, workers=s.workers, budget=s.budget, progress=progress) as sim:
        maker = CopyMaker(measured.starts, s.noise, s.seed, sim)
        # (1) noise floor: jittered baseline copies
        base = [maker.copy(k, None, desc=f"baseline copy {k + 1}/{plan.copies}")
                for k in range(plan.copies)]  # fmt: skip
        values = value_matrices(observed, base, obs_names)
        weights = observable_weights(values)
        # (2) gap per observable
        gap = assess_gap(values, rng, alpha=s.alpha, n_perm=s.n_perm)
        desc = describe(values)
        # (3) where it lives
        X = _features(observed)
        region = find_region(X, _combined_excess(gap, weights))
        by_obs = {o: find_region(X, gap.per_fiber[o]) for o in gap.significant}
        region_text = by_obs[gap.significant[0]].describe() if gap.any else region.describe()

        signatures: list[Signature] = []
        fits: list[Fit] = []
        heldout: list[HeldOut] = []
        before_ho: GapResult | None = None
        effect_copies: dict[str, list[pd.DataFrame]] = {}
        if gap.any:
            # (4) rank by signature on the fit split, fit the best few there
            base_fit = _subset(base, fit_rows)
            signatures = rank_effects(
                feature_vector(gap), candidates, maker, base_fit, fit_rows, obs_names,
                probe_copy=plan.copies + 1, rng=rng,
            )  # fmt: skip
            chosen = [sg for sg in signatures if sg.cosine > 0][: plan.candidates]
            obs_fit = observed.iloc[fit_rows].reset_index(drop=True)
            for sg in chosen:
                cand = next(c for c in candidates if c.name == sg.name)
                fits.append(
                    fit_effect(cand, maker, obs_fit, base_fit[: plan.fit_copies], fit_rows,
                               obs_names, weights, plan.fit_evals)  # fmt: skip
                )
            # (5) held-out comparison
            obs_ho = observed.iloc[held].reset_index(drop=True)
            base_ho = _subset(base, held)
            v_before = value_matrices(obs_ho, base_ho, obs_names)
            before_ho = assess_gap(v_before, rng, alpha=s.alpha, n_perm=s.n_perm)
            base_scores = weighted_loss(v_before, weights)
            eff_scores, residuals, fitted = {}, {}, {}
            for f in fits:
                if f.value == 0.0:
                    continue  # the fit kept the baseline: nothing to add
                cps = [maker.copy(k, {f.name: f.value}, held, desc=f"held-out {f.name}")
                       for k in range(plan.copies)]  # fmt: skip
                effect_copies[f.name] = cps
                v_after = value_matrices(obs_ho, cps, obs_names)
                eff_scores[f.name] = weighted_loss(v_after, weights)
                residuals[f.name] = assess_gap(v_after, rng, alpha=s.alpha, n_perm=s.n_perm)
                fitted[f.name] = f.value
            heldout = evaluate_heldout(fitted, base_scores, eff_scores, residuals, rng, s.alpha)
        verdict = decide(gap, heldout, region_text, rng, s.alpha)
        used, failed = sim.used, sim.failed

    return DiscrepancyResult(
        verdict=verdict,
        gap=gap,
        descriptive=desc,
        region=region,
        region_by_observable=by_obs,
        signatures=signatures,
        fits=fits,
        heldout=heldout,
        heldout_before=before_ho,
        plan=plan,
        simulations=used,
        failed_runs=failed,
        seconds=time.perf_counter() - t0,
        observed=observed,
        baseline_copies=base,
        effect_copies=effect_copies,
        heldout_rows=held,
        weights=weights,
        settings=s,
        observables=obs_names,
    )
