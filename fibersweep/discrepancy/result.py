"""What a workflow run found, as the report receives it: the result, and what to measure next.

The workflow (:mod:`.workflow`) computes every number and test the report shows
and carries it in a :class:`DiscrepancyResult` (what to measure next, when it
ran, as a :class:`Discrimination`, :mod:`.next_measure`); the report
(:mod:`.report`, :mod:`.report_text`, :mod:`.report_followup`,
:mod:`.report_figures`) formats and writes them, and computes none.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from fibersweep.discrepancy.decide import HeldOut, SetHeldOut, Verdict
from fibersweep.discrepancy.estimate import Fit
from fibersweep.discrepancy.gap import GapResult
from fibersweep.discrepancy.localise import Region
from fibersweep.discrepancy.scores import PermTest
from fibersweep.discrepancy.settings import DiscrepancySettings, Plan
from fibersweep.discrepancy.signatures import Signature

__all__ = ["DiscrepancyResult", "Discrimination", "Suggestion"]


@dataclass
class DiscrepancyResult:
    """Everything the report needs.

    Attributes
    ----------
    verdict : Verdict
    gap : GapResult
        The gap per observable against the baseline copies (all fibers).
    descriptive : dict
        Descriptive measures of the gap (:func:`.gap.describe`).
    region, region_by_observable : Region, dict of str -> Region
        Where the gap lives: all observables, and each flagged observable.
    signatures : list of Signature
        The candidates ranked by signature.
    fits : list of Fit
        Every fit: per half, pooled refits, pair members.
    heldout : list of HeldOut
        The held-out evaluation of each fitted candidate (and its refit).
    sets : list of SetHeldOut
        Pairs tried by forward selection.
    heldout_before : GapResult or None
        The held-out gap before any effect (the full gap: every fiber is held out once).
    plan : Plan
    simulations, failed_runs : int
        Runs made, and runs that failed.
    failed_by_stage : dict of str -> int
    seconds : float
        Wall time of the analysis [s].
    observed : DataFrame
        Measured fibers, index 0..n-1.
    baseline_copies : list of DataFrame
        The baseline copies (the noise floor).
    effect_copies : dict of str -> list of DataFrame
        Copies with each fitted effect or set (held-out or final).
    heldout_rows : ndarray of int, shape (n,)
        Fibers scored out of sample (all of them, by cross-fitting).
    weights : dict of str -> float
        Observable weights (the gap in copy-spread units is excess x weight).
    settings : DiscrepancySettings
    observables : tuple of str
        The measured observables scored.
    extra : dict
        ``fold_values`` and ``intervals`` (the fits per half, the refits' 95 %
        intervals), the follow-ups (:func:`.followup.followup`: ``power`` with
        ``power_fibers``, ``next`` and ``next_reason``, or why they were skipped;
        :func:`.followup.settle_followup`: ``settle``, ``verdict_first``), runs
        and seconds by stage.
    gap_per_fiber : ndarray, shape (n,)
        Each fiber's gap over all observables (:func:`.gap.combined_excess`: its
        excess scores times the observables' weights) [copy-spread units].
    dispersion : dict of str -> PermTest
        The dispersion test (:func:`.dispersion.dispersion_test`) of the data
        against the baseline copies (``'baseline'``) and against the copies of each
        random library effect simulated on every fiber (its name); outside the
        Holm family of the gap (:func:`.stages.dispersion`).
    """

    verdict: Verdict
    gap: GapResult
    descriptive: dict[str, Any]
    region: Region
    region_by_observable: dict[str, Region]
    signatures: list[Signature]
    fits: list[Fit]
    heldout: list[HeldOut]
    sets: list[SetHeldOut]
    heldout_before: GapResult | None
    plan: Plan
    simulations: int
    failed_runs: int
    failed_by_stage: dict[str, int]
    seconds: float
    observed: pd.DataFrame
    baseline_copies: list[pd.DataFrame]
    effect_copies: dict[str, list[pd.DataFrame]]
    heldout_rows: np.ndarray  # fibers scored out of sample (all of them, by cross-fitting)
    weights: dict[str, float]
    settings: DiscrepancySettings
    observables: tuple[str, ...]
    extra: dict[str, Any] = field(default_factory=dict)
    gap_per_fiber: np.ndarray = field(default_factory=lambda: np.zeros(0))
    dispersion: dict[str, PermTest] = field(default_factory=dict)


@dataclass(frozen=True)
class Suggestion:
    """One start worth measuring.

    Attributes
    ----------
    theta0, y0, length : float
        Start [deg], [/h_obs], [/l_obs].
    d : float
        Discrimination (standardised prediction difference) of one fiber there.
    observable : str
        The component that discriminates most there.
    a, b : float
        The two hypotheses' mean predictions of that component (its scoring scale).
    """

    theta0: float
    y0: float
    length: float
    d: float
    observable: str
    a: float
    b: float


@dataclass(frozen=True)
class Discrimination:
    """Where two hypotheses differ most.

    Attributes
    ----------
    labels : (str, str)
        The hypotheses, e.g. ('inlet_speed = -0.06', 'off_midplane = 0.1').
    grid : ndarray, shape (g, 3)
        Candidate starts.
    d : ndarray, shape (g,)
        Discrimination of one fiber at each start (``copies`` copies).
    best : list of Suggestion
        The best starts, most discriminating first (by the window's estimate).
    fibers_to_settle : int or None
        Fibers within the window of the best starts that settle it: the follow-up
        test's (:func:`.discriminant.fibers_to_settle`; without the window's
        copies, :func:`fibers_to_separate` of the best grid starts' mean D²).
        None when nothing discriminates.
    fibers_to_separate_measured : int or None
        A rough count at the measured starts, for comparison:
        :func:`fibers_to_separate` of their mean D².
    simulations : int
    window : ndarray, shape (3,), or None
        Half-width (θ0 [deg], y0 [/h_obs], L [/l_obs]) of the window around each
        best start within which its ``d`` and ``fibers_to_settle`` hold; None: at the
        start itself, from the grid's copies.
    """

    labels: tuple[str, str]
    grid: np.ndarray
    d: np.ndarray
    best: list[Suggestion]
    fibers_to_settle: int | None
    fibers_to_separate_measured: int | None
    simulations: int
    window: np.ndarray | None = None
