"""A test of dispersion: are the measurements spread more widely than the model's copies?

A random effect (start noise, Brownian motion) changes how widely outcomes
spread, not where they sit. The proper scores of :mod:`.scores` see a wider
spread only through the small excess it leaves in a fair CRPS, mixed with every
shift and shape difference. This test looks at the spread alone, through the
probability integral transform (PIT) of each value against its fiber's copies.

For every member j of a row (the observation in column 0, the copies in the
others) and every continuous observable, the randomised leave-one-out PIT

    u_j = (#{l != j: V_l < V_j} + U (#{l != j: V_l = V_j} + 1)) / (k + 1),

with k the defined other members and U uniform on [0, 1], is uniform on [0, 1]
when the members are exchangeable (ties included, thanks to U). A measurement
more widely spread than the copies lands in their tails: u near 0 or 1. The
per-member dispersion score is ``d_j = 12 (u_j - 1/2)^2`` averaged over the
continuous observables: 1 on average under exchangeability, larger for
over-dispersion, smaller for under-dispersion (a measurement that always
sits in the middle of its copies).

The test is the permutation test of :mod:`.scores` on that matrix (column 0
against a random column per fiber), so its null distribution is exact,
whatever the dependence between a fiber's observables; it is one-sided
(over-dispersion), the direction a missing random effect produces.

Naming a random effect: :func:`spread_test` asks, on the held-out
fibers, whether the baseline is over-dispersed (the test above) *and* the
effect's cross-fitted copies reduce the observations' dispersion scores (a
paired bootstrap over fibers); an intersection-union test, so its p is the
larger of the two. A third, two-sided test against the effect's copies is a
gate: an effect fitted too wide on the other half leaves the held-out data
under-dispersed. The per-fiber scores have mean exactly 1 under
exchangeability for any number of copies, so the two ensembles need not be the
same size. The reduction is a paired difference of the two scores, not of their
distances from 1: at a right value ``|mean D_effect - 1|`` sits at its kink,
whose bootstrap is biased upward.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.stats import ttest_1samp

from fibersweep.discrepancy.observables import OBSERVABLES
from fibersweep.discrepancy.scores import (
    PermTest,
    boot_p,
    bootstrap_mean_ci,
    holm,
    permutation_test,
    transform,
)

__all__ = [
    "pit_loo",
    "dispersion_matrix",
    "dispersion_test",
    "SpreadTest",
    "spread_test",
    "shift_test",
]


def pit_loo(V: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Randomised leave-one-out PIT of every member against the rest of its row.

    Parameters
    ----------
    V : ndarray, shape (n, m), float
        NaN where undefined (excluded).
    rng : numpy.random.Generator
        The randomisation of ties.

    Returns
    -------
    ndarray, shape (n, m)
        In [0, 1]; NaN where ``V`` is NaN or fewer than two other members are defined.
    """
    V = np.asarray(V, dtype=np.float64)
    if V.ndim != 2:
        raise ValueError(f"V must be 2D (fibers, members), got shape {V.shape}")
    fin = np.isfinite(V)
    both = fin[:, :, None] & fin[:, None, :]
    less = ((V[:, None, :] < V[:, :, None]) & both).sum(axis=2)
    equal = ((V[:, None, :] == V[:, :, None]) & both).sum(axis=2) - fin  # others only
    k = fin.sum(axis=1, keepdims=True) - 1  # defined others of each member
    u = rng.uniform(size=V.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        P = (less + u * (equal + 1)) / (k + 1)
    P[~fin | (k < 2)] = np.nan
    return P


def dispersion_matrix(
    values: Mapping[str, np.ndarray], rng: np.random.Generator
) -> np.ndarray | None:
    """Per-member dispersion score ``12 (u - 1/2)^2``, averaged over continuous observables.

    Parameters
    ----------
    values : mapping name -> ndarray, shape (n, m)
        From :func:`gap.value_matrices` (column 0 observed).
    rng : numpy.random.Generator

    Returns
    -------
    ndarray, shape (n, m), or None
        Mean 1 under exchangeability; NaN where no continuous observable is
        defined. None when ``values`` holds no continuous observable.
    """
    parts = []
    for name, V in values.items():
        o = OBSERVABLES.get(name)
        if o is None or o.categorical or not o.scored:
            continue
        parts.append(12.0 * (pit_loo(transform(name, V), rng) - 0.5) ** 2)
    if not parts:
        return None
    stack = np.stack(parts)
    cnt = np.isfinite(stack).sum(axis=0)
    with np.errstate(invalid="ignore"):
        return np.where(cnt > 0, np.nansum(stack, axis=0) / np.maximum(cnt, 1), np.nan)


def shift_test(values: Mapping[str, np.ndarray], rng: np.random.Generator) -> float:
    """Is the observation shifted against its copies, whatever its spread?

    For every continuous observable, a one-sample t test of ``u - 1/2`` over the
    fibers, u the observation's randomised PIT among its copies. Under
    exchangeability, and under any symmetric widening (a random effect), ``u - 1/2``
    has mean 0; the t statistic is normalised by the observed spread of u, so a
    wider observation does not make it reject (unlike the permutation test of the
    signed residuals in :func:`gap.assess_gap`, whose null has the copies' spread).
    A shift moves u to one side.

    Returns
    -------
    float
        The smallest Holm-adjusted two-sided p over the continuous observables
        (1 without one, or with fewer than 3 fibers defined).
    """
    ps = []
    for name, V in values.items():
        o = OBSERVABLES.get(name)
        if o is None or o.categorical or not o.scored:
            continue
        u = pit_loo(transform(name, V), rng)[:, 0]
        u = u[np.isfinite(u)]
        if len(u) >= 3 and np.std(u) > 0:
            ps.append(float(ttest_1samp(u - 0.5, 0.0).pvalue))
    return float(np.min(holm(ps))) if ps else 1.0


def dispersion_test(
    values: Mapping[str, np.ndarray],
    rng: np.random.Generator,
    n_perm: int = 4999,
    two_sided: bool = False,
) -> PermTest:
    """Permutation test of over-dispersion of the observations against their copies.

    ``two_sided``: over- or under-dispersion (the check after a random effect
    was fitted: its copies should be neither narrower nor wider than the data).

    Returns
    -------
    PermTest
        ``statistic`` is the mean dispersion score of the observations (1: as
        spread as a copy), ``z`` its standardised excess, ``p_value`` exact
        under exchangeability. p = 1 and n = 0 without continuous observables.
    """
    D = dispersion_matrix(values, rng)
    if D is None:
        return PermTest(np.nan, np.nan, np.nan, 1.0, 0.0, 0)
    return permutation_test(D, rng, n_perm=n_perm, two_sided=two_sided)


@dataclass(frozen=True)
class SpreadTest:
    """Held-out evidence that a random effect matches the data's spread.

    Attributes
    ----------
    reduction : (mean, lo, hi)
        Per-fiber decrease of the observation's dispersion score from the
        baseline's copies to the effect's cross-fitted copies (dimensionless),
        bootstrap 95 %.
    p_over : float
        One-sided permutation p of the baseline's over-dispersion (all fibers).
    p_reduce : float
        One-sided bootstrap p of "no reduction".
    p : float
        ``max(p_over, p_reduce)``: the intersection-union test of "the baseline is
        over-dispersed and the effect reduces it" (level alpha without adjustment).
    calm : PermTest
        Two-sided dispersion test against the effect's held-out copies (a gate:
        an effect fitted too wide leaves the data under-dispersed).
    p_shift : float
        :func:`shift_test` against the effect's held-out copies (a gate: a
        spread is named only where the observations show no shift).
    base_mean, effect_mean : float
        Mean observed dispersion score against each (1: as spread as a copy).
    """

    reduction: tuple[float, float, float]
    p_over: float
    p_reduce: float
    p: float
    calm: PermTest
    base_mean: float
    effect_mean: float
    p_shift: float = 1.0


def spread_test(
    base_values: Mapping[str, np.ndarray],
    effect_values: Mapping[str, np.ndarray],
    rng: np.random.Generator,
    n_perm: int = 4999,
) -> SpreadTest | None:
    """The held-out spread test of a random effect.

    Parameters
    ----------
    base_values, effect_values : mapping name -> ndarray, shape (n, m)
        Observed (column 0) and copies of the same fibers: the baseline's, and
        the effect's cross-fitted copies (each fold simulated at the value fitted
        on the other), from :func:`gap.value_matrices`. The copy counts may differ:
        a dispersion score has mean exactly 1 under exchangeability for any count.
    rng : numpy.random.Generator
    n_perm : int
        Permutations of each dispersion test.

    Returns
    -------
    SpreadTest, or None without a continuous observable.
    """
    DB, DE = dispersion_matrix(base_values, rng), dispersion_matrix(effect_values, rng)
    if DB is None or DE is None:
        return None
    over = permutation_test(DB, rng, n_perm=n_perm)
    calm = permutation_test(DE, rng, n_perm=n_perm, two_sided=True)
    d = DB[:, 0] - DE[:, 0]
    reduction = bootstrap_mean_ci(d, rng)
    p_reduce = boot_p(d, rng)
    with np.errstate(invalid="ignore"):
        mb, me = float(np.nanmean(DB[:, 0])), float(np.nanmean(DE[:, 0]))
    p_shift = shift_test(effect_values, rng)
    return SpreadTest(
        reduction, over.p_value, p_reduce, max(over.p_value, p_reduce), calm, mb, me, p_shift
    )
