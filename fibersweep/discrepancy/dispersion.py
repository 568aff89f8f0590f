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

The test is the permutation test of :mod:`.stats` on that matrix (column 0
against a random column per fiber), so its null distribution is exact,
whatever the dependence between a fiber's observables; it is one-sided
(over-dispersion), the direction a missing random effect produces.

Naming a random effect (issue 30): :func:`calibration_gain` compares, on the
held-out fibers, how far the observations' mean dispersion score is from 1
against the baseline's copies and against the effect's cross-fitted copies.
The per-fiber scores are exact-mean-1 under exchangeability for any number of
copies, so the two ensembles need not be the same size. The statistic
``|mean D_base - 1| - |mean D_effect - 1|`` rewards bringing the spread to
the data's, not widening as such: an effect fitted too wide on the other half
makes the held-out data under-dispersed and loses.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from fibersweep.discrepancy.observables import OBSERVABLES
from fibersweep.discrepancy.scores import transform
from fibersweep.discrepancy.stats import PermTest, permutation_test

__all__ = [
    "pit_loo",
    "dispersion_matrix",
    "dispersion_test",
    "observed_dispersion",
    "calibration_gain",
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


def observed_dispersion(
    values: Mapping[str, np.ndarray], rng: np.random.Generator
) -> np.ndarray | None:
    """Per-fiber dispersion score of the observation (column 0 of :func:`dispersion_matrix`).

    Returns
    -------
    ndarray, shape (n,), or None
        Expectation exactly 1 per fiber when the observation is one more copy.
    """
    D = dispersion_matrix(values, rng)
    return None if D is None else D[:, 0]


def _gain(db: np.ndarray, de: np.ndarray) -> np.ndarray:
    """|mean db - 1| - |mean de - 1| over the last axis (fibers)."""
    return np.abs(db.mean(axis=-1) - 1.0) - np.abs(de.mean(axis=-1) - 1.0)


def calibration_gain(
    d_base: np.ndarray, d_effect: np.ndarray, rng: np.random.Generator, n_boot: int = 4000
) -> tuple[tuple[float, float, float], float]:
    """Held-out gain in dispersion calibration of an effect over the baseline.

    Parameters
    ----------
    d_base, d_effect : ndarray, shape (n,)
        Per-fiber observed dispersion scores (:func:`observed_dispersion`) of
        the same held-out fibers against the baseline's and the effect's copies
        (dimensionless, 1 on average when calibrated). Fibers undefined in
        either are left out.
    rng : numpy.random.Generator
    n_boot : int
        Paired bootstrap resamples of the fibers.

    Returns
    -------
    ((gain, lo, hi), p)
        ``gain = |mean d_base - 1| - |mean d_effect - 1|`` (positive: the effect's
        copies match the data's spread better), its percentile 95 % interval, and
        the one-sided bootstrap p of ``gain <= 0`` ((1 + #{gain* <= 0}) / (1 + B));
        NaNs and p = 1 without a defined fiber.
    """
    db, de = np.asarray(d_base, dtype=np.float64), np.asarray(d_effect, dtype=np.float64)
    ok = np.isfinite(db) & np.isfinite(de)
    db, de = db[ok], de[ok]
    if len(db) == 0:
        return (np.nan, np.nan, np.nan), 1.0
    idx = rng.integers(0, len(db), size=(n_boot, len(db)))
    boot = _gain(db[idx], de[idx])
    g = float(_gain(db, de))
    lo, hi = (float(q) for q in np.quantile(boot, [0.025, 0.975]))
    return (g, lo, hi), float((1 + np.sum(boot <= 0.0)) / (1 + n_boot))
