"""Fitting one effect: its value on each half of the fibers and refitted on all of them.

Fit (:func:`fit_effect`): the parameter minimises the combined score of the
fit fibers' observations against ``fit_copies`` copies made with the effect on
(common random numbers, so the baseline value 0 is one more point of the same
curve): bounded Brent minimisation (:func:`scipy.optimize.minimize_scalar`)
over the effect's interval (for a signed effect the half its signature
points to, unless one evaluation at a fifth of the other half beats the
baseline there) within a fixed number of simulated evaluations; the baseline
value 0 is always a candidate, so a fit never does worse than no effect.

Cross-fitting (:func:`fold_fits`) fits an effect on one half of the fibers
and scores the other half with that value; the pooled refit
(:func:`pooled_refit`) fits it again on all fibers, near the halves' values,
and its value is the one the report quotes with its 95 % interval. All three
values are the *same estimator*: the score test's zero
(:func:`.estimate.slope_estimate`; for a random effect the dispersion root,
:func:`.estimate.dispersion_root`), i.e. ``fit_effect(..., estimate=True)``.
A categorical candidate (an alternative value, ``Candidate.categorical``) is
not scanned: its value is 1 where the alternative scores better than the
baseline on the fit fibers, else 0, and its held-out improvement decides.
With one estimator the pooled value sits near the mean of the halves' (exactly
there for a quadratic per-fiber loss and halves of equal size), and the
halves' spread says how well the value is identified.

Cost: a half's value is in general not one of the points its fit simulated,
so the pooled refit's two starting values (the halves') each need the training
half's fit copies (:meth:`.settings.Plan.cost` counts them).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np
import pandas as pd
from scipy.optimize import minimize_scalar

from fibersweep.discrepancy.candidates import Candidate
from fibersweep.discrepancy.copies import CopyMaker
from fibersweep.discrepancy.dispersion import dispersion_matrix
from fibersweep.discrepancy.estimate import (
    Fit,
    dispersion_root,
    merged_profile,
    score_interval,
    slope_estimate,
)
from fibersweep.discrepancy.gap import value_matrices
from fibersweep.discrepancy.scores import score_matrix

__all__ = ["fit_effect", "fold_fits", "per_fiber_loss", "pooled_refit", "refit_bounds"]

log = logging.getLogger(__name__)


def per_fiber_loss(values: Mapping[str, np.ndarray], weights: Mapping[str, float]) -> np.ndarray:
    """Per-fiber combined score, shape (n,): its mean is :func:`combined_loss`.

    A fiber whose score of an observable is undefined (NaN) gets that
    observable's mean score, so that the mean over fibers is unchanged.
    """
    tot: np.ndarray | None = None
    for name, V in values.items():
        s = score_matrix(name, V)[:, 0]
        tot = np.zeros(len(s)) if tot is None else tot
        w = weights.get(name, 0.0)
        if w == 0.0 or not np.isfinite(s).any():
            continue
        tot = tot + w * np.where(np.isfinite(s), s, np.nanmean(s))
    return tot if tot is not None else np.zeros(0)


def _unbracketed_end(fit: Fit, lo: float, hi: float, tol: float) -> float | None:
    """The search range's end to evaluate so that the estimate's root is bracketed.

    Brent searches the loss for its best evaluated value, and on a flat, noisy loss it
    often stops short of the root the pooled refit quotes, which then sits at the
    highest (lowest) evaluated value with the interval open there, the truth beyond
    it. A random effect (``fit.dispersion``): its dispersion root, when the data are
    still more spread than the copies at the highest value evaluated. A shift effect:
    :func:`.estimate.slope_estimate`, when it lies at the highest (lowest) evaluated
    value, the score test's T still negative (positive) there, i.e. the loss still
    falling toward the range's end. One more evaluation at that end brackets the root
    (or shows it lies beyond: the interval's end is then open).

    Parameters
    ----------
    fit : Fit
        The fit so far (best evaluated value, profile, dispersion scores).
    lo, hi : float
        The search range, in the units of the value.
    tol : float
        Values closer than this to an end count as that end (units of the value).

    Returns
    -------
    float or None
        ``hi`` or ``lo``, or None when the root is bracketed (or the fit kept 0).
    """
    if fit.dispersion:
        top, D = max(fit.dispersion, key=lambda p: p[0])
        return hi if top < hi - tol and float(np.nanmean(D)) > 1.0 else None
    if fit.value == 0.0 or len(fit.profile) < 3:
        return None
    x, _ = merged_profile(fit)
    if len(x) < 3:
        return None
    est = slope_estimate(fit)
    if est >= x[-1] - tol and x[-1] < hi - tol:
        return hi
    if est <= x[0] + tol and x[0] > lo + tol:
        return lo
    return None


def fit_effect(
    cand: Candidate,
    maker: CopyMaker,
    observed: pd.DataFrame,
    base_copies: Sequence[pd.DataFrame],
    rows: np.ndarray,
    observables: Sequence[str],
    weights: Mapping[str, float],
    max_evals: int,
    side: float = 0.0,
    bounds: tuple[float, float] | None = None,
    fixed: Mapping[str, float] | None = None,
    stage: str = "fit",
    known: Sequence[float] = (),
    estimate: bool = False,
    bracket_root: bool = False,
    close_interval: bool = True,
) -> Fit:
    """Fit the value of one effect on the fit fibers.

    Parameters
    ----------
    observed : DataFrame
        Measured table restricted to ``rows``.
    base_copies : sequence of DataFrame
        The baseline copies 0..fit_copies-1 restricted to ``rows`` (the value 0).
    max_evals : int
        Simulated evaluations allowed (each is len(rows) x fit_copies runs); one
        more for the side check of a signed effect. 0: no search, only the
        baseline and the ``known`` values are evaluated.
    side : float
        For a signed effect, the sign of the best-matching probe (0: search both).
    bounds : (lo, hi), optional
        Search interval instead of the candidate's (e.g. around earlier fits).
    fixed : mapping name -> value, optional
        Effects held at these values while ``cand`` is fitted (forward selection:
        the effects already chosen). ``base_copies`` must then be copies made with
        these effects on (the value 0 of ``cand``).
    stage : str
        Label the simulations are counted under (``Simulator.used_by_stage``).
    known : sequence of float
        Values evaluated before the search and not counted in ``max_evals``:
        values whose runs the copy maker already holds (the pooled refit passes
        the two halves' values: each half was simulated there, one by its fit,
        the other by its cross-fitted copies), so they cost no simulation.
    estimate : bool
        Report :func:`.estimate.slope_estimate` (the zero of the score test's T,
        smoothed over every evaluated value) instead of the best evaluated value:
        the value a report quotes. For a random effect, the value where the data
        are as spread as its copies (:func:`.estimate.dispersion_root`).
        With ``bracket_root`` (the pooled refit, :func:`pooled_refit`)
        its search keeps one of the ``max_evals`` evaluations (when it has more
        than one): when Brent stops short of the root (:func:`_unbracketed_end`:
        the score test's zero at the highest or lowest evaluated value, or for a
        random effect the data still more spread than the copies at its highest
        value), the range's end is evaluated, so that the root is bracketed.
        Otherwise Brent takes the kept step: its path depends only on the
        (cached) losses, so it is the fit without the bracket. The halves' fits
        do not bracket: it would change which random effects the held-out spread
        test names. ``loss`` stays the loss at the best evaluated value.
    close_interval : bool
        With ``bracket_root``: after the search, when the quoted value's interval
        (:func:`.estimate.score_interval`) is open at an evaluated value inside the effect's
        range, away from 0, one evaluation beyond ``max_evals`` goes to that range
        end (:func:`_open_end`); then the interval's closed ends that no evaluated
        value is near are evaluated (:func:`_unread_ends`, at most two more: at
        most ``settings.INTERVAL_EVALS`` in all), and the value is read again over
        all of them.
    """
    k_fit = len(base_copies)
    # The signature suggests the sign of a signed effect; one evaluation at a fifth
    # of the other half checks it (a weak signature can point the wrong way).
    check_side = bounds is None and cand.signed and side != 0.0
    # evaluations allowed beyond the baseline (a list: the interval step adds to it)
    budget = [max_evals + int(check_side) + len(set(known) - {0.0})]
    label = [stage]  # the interval step's runs are counted as "interval"
    vals0 = value_matrices(observed, base_copies, observables)
    per: dict[float, np.ndarray] = {0.0: per_fiber_loss(vals0, weights)}
    seen: dict[float, float] = {0.0: float(np.mean(per[0.0]))}
    # a random effect: each fiber's dispersion score at every value, with the same
    # randomisation of the PIT at every value (common random numbers)
    disp: dict[float, np.ndarray] = {}

    def _disp(vals: Mapping[str, np.ndarray]) -> np.ndarray | None:
        D = dispersion_matrix(vals, np.random.default_rng(20301))
        return None if D is None else D[:, 0]

    if cand.random and (d0 := _disp(vals0)) is not None:
        disp[0.0] = d0

    def loss(v: float) -> float:
        v = float(v)
        for u, lu in seen.items():  # avoid re-simulating (nearly) the same point
            if abs(u - v) <= 1e-9 * max(1.0, abs(v)):
                return lu
        if len(seen) - 1 >= budget[0]:
            # Budget spent: this point is unknown; report the worst seen so Brent moves away.
            return max(seen.values())
        copies = maker.copies(
            range(k_fit),
            {**(fixed or {}), cand.name: v},
            rows,
            desc=f"{label[0]} {cand.name}={v:.4g}",
        )
        vals = value_matrices(observed, copies, observables)
        per[v] = per_fiber_loss(vals, weights)
        seen[v] = float(np.mean(per[v]))
        if disp and (dv := _disp(vals)) is not None:
            disp[v] = dv
        return seen[v]

    for v in known:
        loss(v)
    if cand.categorical:
        # an alternative is compared with the config's value, never scanned: its value
        # is 1 where it scores better than the baseline on these fibers, else 0
        budget[0] = max(budget[0], 1)
        loss(1.0)
        best = 1.0 if seen[1.0] < seen[0.0] else 0.0
        profile = tuple((float(u), per[u]) for u in sorted(per))
        return Fit(cand.name, best, seen[best], seen[0.0], tuple(sorted(seen.items())), profile)
    lo, hi = bounds if bounds is not None else (cand.lo, cand.hi)
    if check_side:
        # Brent then searches the better half with the evaluations it was given.
        # at a fifth of the other half: for a loss convex in the value with its minimum
        # at v*, loss(c) < loss(0) roughly when c < 2 v*, so a check close to 0 still
        # sees a small effect on that side
        if loss(0.2 * (cand.lo if side > 0 else cand.hi)) < seen[0.0]:
            side = -side
        lo, hi = (0.0, cand.hi) if side > 0 else (cand.lo, 0.0)
    # the pooled refit's estimate keeps one of its evaluations to bracket its root (below)
    bracket = int(bracket_root and estimate and max_evals > 1)

    def search(steps: int) -> None:
        minimize_scalar(
            loss,
            bounds=(lo, hi),
            method="bounded",
            options={"maxiter": steps, "xatol": 1e-3 * (cand.hi - cand.lo)},
        )

    if max_evals > 0:  # 0: only the known values
        search(max_evals - bracket)

    def result() -> Fit:
        best = min(seen, key=lambda p: (seen[p], abs(p)))
        log.info("fit %s: %.4g (loss %.4g vs baseline %.4g)",
                 cand.name, best, seen[best], seen[0.0])  # fmt: skip
        profile = tuple((float(u), per[u]) for u in sorted(per))
        fit = Fit(cand.name, float(best), float(seen[best]), float(seen[0.0]),
                  tuple(sorted(seen.items())), profile)  # fmt: skip
        if len(disp) >= 2:  # its interval is the dispersion test's (score_interval)
            fit = replace(fit, dispersion=tuple((float(u), disp[u]) for u in sorted(disp)))
        return fit

    fit = result()
    if bracket and (end := _unbracketed_end(fit, lo, hi, 1e-9 * (cand.hi - cand.lo))) is not None:
        loss(end)  # the kept evaluation (no simulation when the end was evaluated)
        fit = result()
    elif bracket:
        # not needed: Brent takes the kept step. Its path depends only on the losses,
        # which are cached, so it repeats its steps without simulating and adds one.
        search(max_evals)
        fit = result()
    fit = _estimated(fit, estimate)
    close = bracket and close_interval
    label[0] = "interval"
    if close and (end := _open_end(fit, cand.lo, cand.hi, 1e-9 * (cand.hi - cand.lo))):
        budget[0] += 1  # one evaluation beyond max_evals, only for an open interval
        loss(end)
        fit = _estimated(result(), estimate)
    if close and (ends := _unread_ends(fit)):
        budget[0] += len(ends)  # at most two more: the interval's ends
        for e in ends:
            loss(e)
        fit = _estimated(result(), estimate)
    return fit


def _estimated(fit: Fit, estimate: bool) -> Fit:
    """``fit`` with the value a report quotes (``estimate``; see :func:`fit_effect`)."""
    best = fit.value
    if estimate and fit.dispersion:
        # a random effect: the value at which the data are as spread as the copies
        fit = replace(fit, value=dispersion_root(fit))
        log.info("fit %s: dispersion root %.4g (best evaluated %.4g)", fit.name, fit.value, best)
    elif estimate:
        fit = replace(fit, value=slope_estimate(fit))
        log.info("fit %s: estimate %.4g (best evaluated %.4g)", fit.name, fit.value, best)
    return fit


def _unread_ends(fit: Fit) -> list[float]:
    """The closed ends of the quoted value's interval that no evaluated value is near.

    Between evaluated values the test's T is an interpolation (per-fiber slopes, or
    linear between the dispersion scores), and an end read from it is only as good as
    the interpolation over that stretch, which is poor over a long stretch between
    evaluated values. Evaluating the ends puts the test's own evaluations where it
    decides.

    Returns
    -------
    list of float
        The closed ends farther than a twentieth of the evaluated range from every
        evaluated value (closer ones would be merged with it,
        :func:`.estimate.merged_profile`).
    """
    pts = fit.dispersion or fit.profile
    if len(pts) < 2:
        return []
    xs = np.array([p[0] for p in pts])
    tol = (xs.max() - xs.min()) / 20.0
    lo, hi, open_lo, open_hi = score_interval(fit)
    return [float(e) for e, o in ((lo, open_lo), (hi, open_hi))
            if not o and np.abs(xs - e).min() > tol]  # fmt: skip


def _open_end(fit: Fit, lo: float, hi: float, tol: float) -> float | None:
    """The effect's range end to evaluate so that an open interval can close.

    The test of :func:`.estimate.score_interval` is read only between evaluated
    values, so an interval that is still accepting at the highest (lowest) evaluated
    value is cut there and marked open, although the truth may lie further out.
    Evaluating the range end, on the side away from the baseline 0, extends the test
    there: it rejects somewhere between (a closed end) or the interval runs to the
    range end.

    Parameters
    ----------
    fit : Fit
        The quoted fit (value, profile or dispersion scores).
    lo, hi : float
        The effect's range (units of the value).
    tol : float
        Values closer than this to an end count as that end.

    Returns
    -------
    float or None
        ``hi`` or ``lo``; None when the interval is closed, open only toward 0, or
        already open at the range end.
    """
    pts = fit.dispersion or fit.profile
    if len(pts) < 2:
        return None
    i_lo, i_hi, open_lo, open_hi = score_interval(fit)
    xs = [p[0] for p in pts]
    if open_hi and i_hi > 0.0 and max(xs) < hi - tol:
        return hi
    if open_lo and i_lo < 0.0 and min(xs) > lo + tol:
        return lo
    return None


#: Half-width added on each side of the halves' values for the pooled refit's search,
#: as a fraction of the effect's range.
REFIT_PAD = 0.25


def fold_fits(
    cand: Candidate,
    maker: CopyMaker,
    observed: pd.DataFrame,
    base: Sequence[pd.DataFrame],
    folds: Sequence[np.ndarray],
    observables: Sequence[str],
    weights: Mapping[str, float],
    max_evals: int,
    side: float = 0.0,
) -> list[Fit]:
    """The effect fitted on each training half: fit f on ``folds[1 - f]``, to score fold f.

    Parameters
    ----------
    observed : DataFrame
        All measured fibers (index 0..n-1).
    base : sequence of DataFrame
        The baseline copies used by the fits (all fibers; the fit copies only).
    folds : sequence of two ndarray of int
        The halves.
    side : float
        Sign of the best-matching probe of a signed effect (0: search both).

    Returns
    -------
    list of Fit
        One per fold, each with ``value`` the score test's zero (``estimate=True``).
    """
    return _per_half(cand, maker, observed, base, folds, observables, weights, max_evals,
                     side=side)  # fmt: skip


def _per_half(cand, maker, observed, base, folds, observables, weights, max_evals, **kw):
    """``fit_effect`` on each training half ``folds[1 - f]``, with the score test's zero
    (``estimate=True``: the same estimator as the pooled refit)."""
    fits = []
    for f in range(len(folds)):
        train = np.asarray(folds[1 - f])
        fits.append(
            fit_effect(
                cand,
                maker,
                observed.iloc[train].reset_index(drop=True),
                [b.iloc[train].reset_index(drop=True) for b in base],
                train,
                observables,
                weights,
                max_evals,
                estimate=True,
                **kw,
            )
        )
    return fits


def refit_bounds(cand: Candidate, values: Sequence[float]) -> tuple[float, float]:
    """Search range of the pooled refit: the halves' values widened by
    :data:`REFIT_PAD` of the effect's range on each side, clipped to the range."""
    pad = REFIT_PAD * (cand.hi - cand.lo)
    return max(cand.lo, min(values) - pad), min(cand.hi, max(values) + pad)


def pooled_refit(
    cand: Candidate,
    maker: CopyMaker,
    observed: pd.DataFrame,
    base: Sequence[pd.DataFrame],
    values: Sequence[float],
    observables: Sequence[str],
    weights: Mapping[str, float],
    max_evals: int,
    fixed: Mapping[str, float] | None = None,
) -> Fit:
    """The effect refitted on all fibers within :func:`refit_bounds` of the halves' values.

    The halves' values are evaluated first (``known``), then ``max_evals`` Brent
    steps; the value is the score test's zero over every evaluated value. That
    zero is bracketed: one of the steps is kept for the range's end when the zero
    lies at the highest (lowest) value evaluated, the loss still falling toward
    the end, or for a random effect (its value the dispersion root) when the data
    are still more spread than the copies at the highest value evaluated; when it
    is not needed Brent takes the step (:func:`fit_effect`, ``bracket_root``).
    Then up to ``settings.INTERVAL_EVALS`` more evaluations read the 95 % interval's
    ends: the effect's range end when the interval is open inside the range, and
    the closed ends no evaluated value is near (``close_interval``).
    ``fixed``: other effects held at these values (a pair's other member,
    :func:`.pairs.pair_refits`); ``base`` must then be copies made with them on.
    """
    return fit_effect(
        cand,
        maker,
        observed,
        base,
        np.arange(len(observed)),
        observables,
        weights,
        max_evals,
        bounds=refit_bounds(cand, values),
        fixed=fixed,
        stage="refit",
        known=[float(v) for v in values],
        estimate=True,
        bracket_root=True,
    )
