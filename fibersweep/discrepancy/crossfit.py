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
from fibersweep.discrepancy.fit import Fit, fit_effect
from fibersweep.discrepancy.library import Candidate

__all__ = ["fold_fits", "refit_bounds", "pooled_refit"]

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
                side=side,
                estimate=True,  # the same estimator as the pooled refit (issue 30)
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
) -> Fit:
    """The effect refitted on all fibers within :func:`refit_bounds` of the halves' values.

    The halves' values are evaluated first (``known``), then ``max_evals`` Brent
    steps; the value is the score test's zero over every evaluated value.
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
        stage="refit",
        known=[float(v) for v in values],
        estimate=True,
    )
