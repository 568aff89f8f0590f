"""One effect's value on each half of the fibers and refitted on all of them.

Cross-fitting (:func:`workflow.cross_fit`) fits an effect on one half of the
fibers and scores the other half with that value; the pooled refit
(:func:`workflow.refit`) fits it again on all fibers, near the halves' values,
and its value is the one the report quotes. All three values are the *same
estimator*: the score test's zero (:func:`fit.slope_estimate`; for a random
effect the dispersion root, :func:`fit.dispersion_root`), i.e.
``fit_effect(..., estimate=True)``.

Before, the halves reported the best evaluated value while the pooled refit
reported the score test's zero. The best evaluated value of a few noisy,
step-like evaluations is one of Brent's golden-section points of the search
range (0.382 and 0.708 of [0, 1] and [0, 3] came back for friction and
pillar_hydro on both halves at once), so the halves were quantised to that grid
and the pooled value, a continuous estimate, lay outside both of them as a
rule (the issue's pillar_hydro: halves 0.71 and 0.64, pooled 0.901). With one
estimator the pooled value sits near the mean of the halves' (exactly there
for a quadratic per-fiber loss and halves of equal size), and the halves'
spread says how well the value is identified.

Cost: a half's value is now in general not one of the points its fit
simulated, so the pooled refit's two starting values (the halves') each need
the training half's fit copies (:meth:`settings.Plan.cost` counts them).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from fibersweep.discrepancy.copies import CopyMaker
from fibersweep.discrepancy.fit import Fit, dispersion_root, fit_effect, slope_estimate
from fibersweep.discrepancy.library import Candidate

__all__ = [
    "fold_fits",
    "refit_bounds",
    "pooled_refit",
    "shared_values",
    "shared_fold_fits",
    "shared_pooled_refit",
]

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
    (``estimate=True``: the same estimator as the pooled refit, issue 30)."""
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
    is not needed Brent takes the step (:func:`fit.fit_effect`, ``bracket_root``).
    Then up to ``settings.INTERVAL_EVALS`` more evaluations read the 95 % interval's
    ends: the effect's range end when the interval is open inside the range, and
    the closed ends no evaluated value is near (``close_interval``).
    ``fixed``: other effects held at these values (a pair's other member,
    :func:`pairfit.pair_refits`); ``base`` must then be copies made with them on.
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


# --- shared values (opt-in: DiscrepancySettings.fit_grid) ------------------------------
#
# The read-out of a step-like loss depends on where it was evaluated, and Brent's
# searches of the two halves and of the pooled refit evaluate different values: on a
# class-only stand-in the pooled value still lay outside both halves in 27-32 % of
# data sets. With every fit evaluating the same values, fixed before the data (so a
# half's design owes nothing to the fibers it scores), the pooled profile at those
# values is the two halves' profiles side by side, free, and a few evaluations on all
# fibers between the grid values around the pooled estimate refine it.


def shared_values(cand: Candidate, side: float, k: int) -> np.ndarray:
    """The k values every fit of ``cand`` evaluates, fixed before the data.

    Geometric towards 0 (each half the next: effect sizes worth naming span an
    order of magnitude or more, and the interpolated score test is read between
    neighbours): an unsigned effect gets hi / 2^(k-1) ... hi; a signed one k - 1
    such values on the side its signature points to (``side``) and one at a fifth
    of the other end (the side check of :func:`fit.fit_effect`); with no side,
    half of them on each side.

    Returns
    -------
    ndarray, sorted, without 0.
    """
    if k < 1:
        raise ValueError(f"k must be >= 1, got {k}")

    def geo(end: float, m: int) -> np.ndarray:
        return end * 2.0 ** -np.arange(m - 1, -1, -1, dtype=np.float64) if m > 0 else np.zeros(0)

    if not cand.signed:
        vals = geo(cand.hi, k)
    elif side != 0.0 and k >= 2:
        end, other = (cand.hi, cand.lo) if side > 0 else (cand.lo, cand.hi)
        vals = np.append(geo(end, k - 1), 0.2 * other)
    else:
        vals = np.concatenate([geo(cand.hi, (k + 1) // 2), geo(cand.lo, k // 2)])
    return np.sort(vals)


def shared_fold_fits(
    cand: Candidate,
    maker: CopyMaker,
    observed: pd.DataFrame,
    base: Sequence[pd.DataFrame],
    folds: Sequence[np.ndarray],
    observables: Sequence[str],
    weights: Mapping[str, float],
    values: np.ndarray,
) -> list[Fit]:
    """As :func:`fold_fits`, each half evaluated at ``values`` only (no search).

    Costs what a half's Brent search with a side check costs when ``values`` has
    ``max_evals + 1`` entries.
    """
    bounds = (min(float(values.min()), 0.0), max(float(values.max()), 0.0))
    return _per_half(cand, maker, observed, base, folds, observables, weights, 0,
                     bounds=bounds, known=[float(v) for v in values])  # fmt: skip


def _side_by_side(
    parts: Sequence[tuple[tuple[float, np.ndarray], ...]], folds: Sequence[np.ndarray], n: int
) -> dict[float, np.ndarray]:
    """Per-fiber arrays of all n fibers at the values every part has; part f covers the
    fibers of ``folds[1 - f]`` (its training half), in their order."""
    common = set.intersection(*(set(v for v, _ in p) for p in parts))
    out = {}
    for v in sorted(common):
        arr = np.full(n, np.nan)
        for f, p in enumerate(parts):
            arr[np.asarray(folds[1 - f])] = dict(p)[v]
        out[v] = arr
    return out


def _quoted(
    name: str, profile: Mapping[float, np.ndarray], disp: Mapping[float, np.ndarray]
) -> Fit:
    """A Fit over the given per-fiber losses (and dispersion scores), its value the
    score test's zero (the dispersion root where there are dispersion scores)."""
    means = {v: float(np.mean(L)) for v, L in profile.items()}
    best = min(means, key=lambda v: (means[v], abs(v)))
    fit = Fit(
        name,
        float(best),
        means[best],
        means.get(0.0, means[best]),
        tuple(sorted(means.items())),
        tuple(sorted(profile.items())),
        tuple(sorted(disp.items())) if len(disp) >= 2 else (),
    )
    value = dispersion_root(fit) if fit.dispersion else slope_estimate(fit)
    return Fit(name, value, fit.loss, fit.loss0, fit.evaluations, fit.profile, fit.dispersion)


def shared_pooled_refit(
    cand: Candidate,
    maker: CopyMaker,
    observed: pd.DataFrame,
    base: Sequence[pd.DataFrame],
    halves: Sequence[Fit],
    folds: Sequence[np.ndarray],
    observables: Sequence[str],
    weights: Mapping[str, float],
    max_evals: int,
) -> Fit:
    """The pooled refit of halves fitted at shared values (:func:`shared_fold_fits`).

    Its profile at the shared values is the two halves' side by side (no
    simulation); its estimate there is refined by ``max_evals`` evenly spaced
    values on all fibers across two grid intervals around it (from the grid value
    below its insertion point to the one after the next), and the value quoted is
    the score test's zero over all of these values. Evenly spaced, not a Brent
    search: on the smooth stand-in, golden-section points there biased the value
    (-0.026 for a truth of 0.6) and cut the interval's coverage to 0.71.
    """
    n = len(observed)
    prof = _side_by_side([h.profile for h in halves], folds, n)
    disp = (
        _side_by_side([h.dispersion for h in halves], folds, n)
        if all(h.dispersion for h in halves)
        else {}
    )
    first = _quoted(cand.name, prof, disp)
    if first.value == 0.0 or max_evals <= 0:
        return first
    # evenly spaced values on all fibers across the two grid intervals around it
    grid = np.array(sorted(prof))
    at = int(np.searchsorted(grid, first.value))
    lo, hi = float(grid[max(at - 1, 0)]), float(grid[min(at + 1, len(grid) - 1)])
    if hi - lo <= 0.0:
        return first
    new = [float(v) for v in np.linspace(lo, hi, max_evals + 2)[1:-1] if float(v) not in prof]
    ref = fit_effect(cand, maker, observed, base, np.arange(n), observables, weights, 0,
                     bounds=(lo, hi), stage="refit", known=new, estimate=True)  # fmt: skip
    prof.update({v: L for v, L in ref.profile if v != 0.0})
    disp.update({v: D for v, D in ref.dispersion if v != 0.0} if disp else {})
    return _quoted(cand.name, prof, disp)
