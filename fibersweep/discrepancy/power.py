"""What the workflow cannot see: detection limits by simulation, and look-alike effects.

For a set of starts (the measured ones, or drawn from a config's sweep box) and
the measurement model, every candidate (library effect or declared setting) is
switched on at its probe value ``m_p`` and at ``m_p / 2``, in the candidate's
own value (:mod:`.candidates`; a declared stiffness's limit is the stiffest
fiber detected, :meth:`.candidates.Candidate.setting` of it). An alternative
(a categorical candidate) is on or off: it is simulated once and its "limit"
is 1 when N fibers detect it with the power, else None (the fibers it needs
follow from the same formula). Copy k of the fibers with the effect on plays the
measurement; the baseline copies j != k (common random numbers) are the model.
The gap tests of :func:`gap.assess_gap` give a z-score per test of the family
(score per observable, one-sided; signed residual per component, two-sided);
averaged over the copies k, this is the expected z-vector at that magnitude
and number of fibers.

Scaling (the approximation this rests on, checked in docs/discrepancy.md): the z of a
test grows as ``sqrt(N)`` with the number of fibers, and as ``m ** gamma`` with
the magnitude, gamma read off the two probes (1 for a shift, 2 for a spread
whose variance grows as m², clipped to [0.5, 3]). A power law is only good
near where it was read: a permutation z saturates once a shift is large
against the copies' spread (the shifted column widens its own null), and a
score's excess grows as m² for small shifts but m for large ones. So unless
the limit lies within a factor ``REFINE_FACTOR`` of one of the two magnitudes
it was read from, or between them with at most ``BRACKET_RATIO`` from one to
the other, the effect is simulated again at the limit, and the limit is read
again from two magnitudes: that one and the simulated one nearest to it, each
test's z following its own power law between them (exact at both); at most
``refine`` times. The family detects when
any test passes its Bonferroni threshold at alpha / m (Holm is at least as
powerful): ``P(detect) = 1 - prod_j (1 - P_j)``, with ``P_j = Phi(z_j - z1)``
for a one-sided score test (z1 = Phi^-1(1 - alpha/m); a score better than the
model's never rejects) and ``Phi(|z_j| - z_crit)`` for a two-sided residual
(z_crit = Phi^-1(1 - alpha/2m)). The smallest magnitude
with ``P(detect) >= power`` is the detection limit; the fibers needed for a
magnitude m follow from the same formula. Detection is the first gate only:
naming needs the held-out improvement too (half of the fibers fit, the other
half test), so the limit to *name* an effect is higher.

Look-alikes: the per-fiber effect of a magnitude (copy with the effect minus
the same copy without, averaged over copies, each observable component
divided by its spread among the baseline copies) is a vector over fibers and
observables. Two effects whose vectors are nearly parallel (|cosine| >= 0.9)
move every fiber alike, up to a factor: these observables cannot separate them.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pandas as pd
from scipy.stats import norm

from fibersweep.discrepancy.candidates import Candidate
from fibersweep.discrepancy.copies import CopyMaker
from fibersweep.discrepancy.dispersion import dispersion_test
from fibersweep.discrepancy.gap import (
    assess_gap,
    feature_one_sided,
    feature_vector,
    value_matrices,
)
from fibersweep.discrepancy.observables import OBSERVABLES
from fibersweep.discrepancy.scores import transform

__all__ = [
    "EffectPower",
    "PowerResult",
    "analyse_power",
    "ensemble_factor",
    "pair_exponents",
    "standardised_values",
    "detect_probability",
    "limit_intervals",
    "limit_in_unit",
    "percentile_interval",
]

log = logging.getLogger(__name__)

#: Parallel per-fiber effects beyond this |cosine| make two effects look-alikes.
LOOKALIKE_COSINE = 0.9

#: A limit this factor away from both magnitudes it was read from is read again there,
REFINE_FACTOR = 1.25
#: unless they bracket it within this ratio (an interpolation).
BRACKET_RATIO = 4.0


@dataclass(frozen=True)
class EffectPower:
    """Detection limit of one effect in one direction.

    Attributes
    ----------
    name : str
    probe : float
        Probe magnitude m_p (signed).
    z : tuple of float
        Expected z-vector (family of gap tests) at :attr:`at` with ``n_sim`` fibers.
    gamma : float
        Growth exponent of z with the magnitude: of the strongest test between
        m_p and m_p / 2, used for every test; read at a refined magnitude, that
        of the strongest test between :attr:`at` and :attr:`against` (each
        test then has its own, :meth:`z_of`).
    limit : float or None
        Smallest magnitude (same sign as the probe) detected with the target
        power at ``n`` fibers; None when not within the effect's range.
    one_sided : tuple of bool or None
        Which tests of ``z`` are one-sided (the score tests); None: all two-sided.
    limit_ci : (float or None, float or None) or None
        95 % bootstrap interval of ``limit`` over the simulated starts
        (:func:`limit_intervals`); an end None: beyond the effect's range in
        more than 2.5 % of the resamples. None: not computed.
    dispersion_limit : float or None
        For a random effect: the smallest magnitude the dispersion test alone
        (:mod:`.dispersion`, one-sided at alpha) detects with the target power
        at ``n`` fibers, scaled like ``limit``. None: not a random effect, or
        not within its range.
    boot : tuple of (z, gamma) or (z, gamma, z_against)
        The read-out of each bootstrap resample of the simulated starts
        (:func:`limit_intervals`), for the intervals of derived numbers
        (:meth:`fibers_needed_ci`). Empty: not computed.
    read_at : float or None
        Magnitude (signed) the z-vector was read at, when not the probe: the
        refined read-out near the limit (module docstring). None: the probe.
    against : float or None
        With ``read_at``: the other simulated magnitude (signed) the per-test
        power laws run through.
    z_against : tuple of float
        With ``read_at``: the z-vector at ``against``.
    """

    name: str
    probe: float
    z: tuple[float, ...]
    gamma: float
    limit: float | None
    one_sided: tuple[bool, ...] | None = None
    limit_ci: tuple[float | None, float | None] | None = None
    dispersion_limit: float | None = None
    boot: tuple[tuple, ...] = field(default=(), repr=False)
    read_at: float | None = None
    against: float | None = None
    z_against: tuple[float, ...] = ()

    @property
    def at(self) -> float:
        """Magnitude (signed) the z-vector is read at."""
        return self.probe if self.read_at is None else self.read_at

    def z_of(self, m: float) -> np.ndarray:
        """Expected z-vector at magnitude m (same sign as the probe) with ``n_sim`` fibers.

        Read at the probe: ``z (|m| / |m_p|) ** gamma``. Read at a refined
        magnitude: each test's own power law through its z at :attr:`at` and
        at :attr:`against` (:func:`pair_exponents`), anchored at the larger
        magnitude, where the signal is best measured.
        """
        if self.read_at is None or self.against is None:
            return np.asarray(self.z) * (abs(m) / abs(self.probe)) ** self.gamma
        za, zb = np.asarray(self.z), np.asarray(self.z_against)
        g = pair_exponents(za, self.read_at, zb, self.against)
        if abs(self.against) >= abs(self.read_at):
            return zb * (abs(m) / abs(self.against)) ** g
        return za * (abs(m) / abs(self.read_at)) ** g

    def detect(self, m: float, n_fibers: int, n_sim: int, z_crit: float) -> float:
        """Detection probability at magnitude m (same sign as the probe) and N fibers."""
        if m == 0.0 or np.sign(m) != np.sign(self.probe):
            return 0.0
        z = self.z_of(m) * math.sqrt(n_fibers / n_sim)
        return detect_probability(z, z_crit, self.one_sided)

    def fibers_needed(
        self, m: float, n_sim: int, z_crit: float, power: float, most: int = 100_000
    ) -> int | None:
        """Fewest fibers detecting magnitude m with the target power (None: > most)."""
        if self.detect(m, most, n_sim, z_crit) < power:
            return None
        lo, hi = 1, most
        while lo < hi:
            mid = (lo + hi) // 2
            if self.detect(m, mid, n_sim, z_crit) >= power:
                hi = mid
            else:
                lo = mid + 1
        return lo

    def fibers_needed_ci(
        self, m: float, n_sim: int, z_crit: float, power: float, level: float = 0.95
    ) -> tuple[int | None, int | None] | None:
        """Interval of :meth:`fibers_needed` over the bootstrap resamples of the starts.

        Each resample's read-out (z-vector and exponent, :attr:`boot`) gives its own
        number of fibers; the interval is their percentile interval at ``level``
        (:func:`percentile_interval`). An end None: more than ``most`` fibers (or
        never) in more than (1 - level)/2 of the resamples. None without resamples.
        """
        if not self.boot:
            return None
        ns = []
        for z, gamma, *zb in self.boot:
            eb = replace(self, z=z, gamma=gamma, z_against=zb[0] if zb else self.z_against, boot=())
            k = eb.fibers_needed(m, n_sim, z_crit, power)
            ns.append(math.inf if k is None else float(k))
        lo, hi = percentile_interval(ns, level)
        return (None if lo is None else int(lo), None if hi is None else int(hi))


@dataclass(frozen=True)
class PowerResult:
    """Power analysis of the library at N fibers.

    Attributes
    ----------
    n : int
        Fibers the limits are for.
    n_sim : int
        Fibers simulated (limits are scaled from them).
    alpha, power : float
        Family-wise level and target detection probability.
    z_crit : float
        Bonferroni threshold of one test of the family.
    effects : list of EffectPower
    lookalikes : list of (str, str, float)
        Effect pairs (name@probe) and the |cosine| of their per-fiber effects, >= 0.9.
    cosines : dict (str, str) -> float
        |cosine| of every pair (for the report).
    simulations : int
    """

    n: int
    n_sim: int
    alpha: float
    power: float
    z_crit: float
    effects: list[EffectPower]
    lookalikes: list[tuple[str, str, float]]
    cosines: dict[tuple[str, str], float]
    simulations: int

    def get(self, name: str, sign: float = 1.0) -> EffectPower | None:
        """The entry of ``name`` in the direction of ``sign`` (None if absent)."""
        for e in self.effects:
            if e.name == name and (np.sign(e.probe) == np.sign(sign) or sign == 0):
                return e
        return None

    def fibers_needed(self, name: str, m: float) -> int | None:
        """Fibers that detect ``name`` at magnitude m with the target power."""
        e = self.get(name, m)
        return None if e is None else e.fibers_needed(m, self.n_sim, self.z_crit, self.power)

    def fibers_needed_ci(self, name: str, m: float) -> tuple[int | None, int | None] | None:
        """95 % interval of :meth:`fibers_needed` over the simulated starts (None: not
        computed; an end None: beyond 100 000 fibers)."""
        e = self.get(name, m)
        return None if e is None else e.fibers_needed_ci(m, self.n_sim, self.z_crit, self.power)


def percentile_interval(
    values: Sequence[float], level: float = 0.95
) -> tuple[float | None, float | None]:
    """Percentile interval of bootstrap values that may be infinite (never reached).

    The order statistics at (1 - level)/2 and (1 + level)/2 of the empirical
    distribution (the k-th smallest of n values with k = ceil(n q); no
    interpolation, so an end between a finite and an infinite value, or between
    two infinite ones, is one of them, never NaN). An infinite end is None.
    """
    v = np.sort(np.asarray(values, dtype=np.float64))
    if len(v) == 0:
        return (None, None)
    a = (1.0 - level) / 2.0
    # 1e-9: n q is an integer in exact arithmetic where float rounding would step over it
    k = [math.ceil(len(v) * q - 1e-9) - 1 for q in (a, 1.0 - a)]
    lo, hi = (float(v[min(max(i, 0), len(v) - 1)]) for i in k)
    return (lo if math.isfinite(lo) else None, hi if math.isfinite(hi) else None)


def detect_probability(
    z: np.ndarray, z_crit: float, one_sided: Sequence[bool] | np.ndarray | None = None
) -> float:
    """P(at least one test of the family rejects) for expected z-scores ``z``.

    Parameters
    ----------
    z : ndarray, shape (m,)
        Expected z-score of each test.
    z_crit : float
        Two-sided Bonferroni threshold Phi^-1(1 - alpha / 2m).
    one_sided : sequence of bool, shape (m,), optional
        Tests that reject only for large positive z (default: none). Their
        threshold is Phi^-1(1 - alpha / m), at the same per-test level.

    A two-sided test rejects with probability Phi(|z| - z_crit), a one-sided
    one with Phi(z - z1) (normal approximation, the far tail ignored); tests
    treated as independent.
    """
    z = np.asarray(z, dtype=np.float64)
    side = np.zeros(len(z), bool) if one_sided is None else np.asarray(one_sided, bool)
    if side.shape != z.shape:
        raise ValueError(f"one_sided has shape {side.shape}, z has {z.shape}")
    ok = np.isfinite(z)
    z, side = z[ok], side[ok]
    level = 2.0 * norm.sf(z_crit)  # alpha / m, the per-test level
    z1 = float(norm.isf(level))
    shift = np.where(side, z - z1, np.abs(z) - z_crit)
    miss = np.prod(1.0 - norm.cdf(shift)) if len(z) else 1.0
    return float(1.0 - miss)


def standardised_values(
    copies: Sequence[pd.DataFrame], observables: Sequence[str]
) -> list[np.ndarray]:
    """Each copy as an (n, c) matrix of observable components on their scoring scale.

    Continuous observables: ``transform`` (e.g. log t_pass); categorical: one-hot
    per category. NaN where undefined. Columns in registry order.
    """
    out = []
    for df in copies:
        cols = []
        for name in (o for o in OBSERVABLES if o in observables and OBSERVABLES[o].scored):
            o = OBSERVABLES[name]
            v = o.values(df[name])
            if o.categorical:
                for c in range(o.width):
                    cols.append(np.where(np.isfinite(v), (v == c).astype(float), np.nan))
            else:
                cols.append(transform(name, v))
        out.append(np.column_stack(cols))
    return out


def _cosine(a: np.ndarray, b: np.ndarray) -> float:
    ok = np.isfinite(a) & np.isfinite(b)
    na, nb = np.linalg.norm(a[ok]), np.linalg.norm(b[ok])
    return float(abs(a[ok] @ b[ok]) / (na * nb)) if na > 0 and nb > 0 else 0.0


def _z_of(
    eff: list[pd.DataFrame],
    base: list[pd.DataFrame],
    observables: Sequence[str],
    rng: np.random.Generator,
    n_perm: int = 499,
    n_boot: int = 50,
) -> np.ndarray:
    """Mean feature vector of copy k with the effect vs the baseline copies j != k."""
    K = len(base)
    zs = []
    for k in range(K):
        others = [base[j] for j in range(K) if j != k]
        vals = value_matrices(eff[k], others, observables)
        zs.append(feature_vector(assess_gap(vals, rng, n_perm=n_perm, n_boot=n_boot)))
    return np.mean(zs, axis=0)


def _z_vector(
    maker: CopyMaker,
    base: list[pd.DataFrame],
    effect: dict[str, float],
    rows: np.ndarray,
    observables: Sequence[str],
    rng: np.random.Generator,
) -> tuple[np.ndarray, list[pd.DataFrame]]:
    """Mean feature vector of copy k with the effect vs the baseline copies j != k."""
    eff = maker.copies(range(len(base)), effect, rows, desc=f"power {next(iter(effect))}")
    return _z_of(eff, base, observables, rng), eff


def _z_dispersion(
    eff: list[pd.DataFrame],
    base: list[pd.DataFrame],
    observables: Sequence[str],
    rng: np.random.Generator,
) -> float:
    """Mean z of the dispersion test, copy k with the effect vs the baseline copies j != k."""
    K = len(base)
    zs = []
    for k in range(K):
        vals = value_matrices(eff[k], [base[j] for j in range(K) if j != k], observables)
        zs.append(dispersion_test(vals, rng, n_perm=499).z)
    return float(np.mean(zs))


def ensemble_factor(copies: int, workflow_copies: int) -> float:
    """Scale of a z read with ``copies - 1`` baseline copies to one with ``workflow_copies``.

    sqrt((1 + 1/(copies - 1)) / (1 + 1/workflow_copies)): the copies' own noise in
    the null shrinks with the ensemble the workflow scores against.
    """
    return math.sqrt((1 + 1 / (copies - 1)) / (1 + 1 / workflow_copies))


def _gamma(z_full: np.ndarray, z_half: np.ndarray) -> float:
    """Growth exponent of the strongest test's z with the magnitude (see module docstring)."""
    j = int(np.argmax(np.abs(z_full)))
    a, b = abs(z_full[j]), abs(z_half[j])
    return float(np.clip(math.log2(a / b), 0.5, 3.0)) if a > 3 and b > 0.5 else 1.0


def pair_exponents(z_a: np.ndarray, m_a: float, z_b: np.ndarray, m_b: float) -> np.ndarray:
    """Each test's growth exponent between two magnitudes, clipped to [0.5, 3].

    ``log(|z_big| / |z_small|) / log(|m_big| / |m_small|)``, the small z floored at
    1e-3 (a test that reads nothing at the small magnitude grows as fast as allowed).
    """
    za, zb = np.abs(np.asarray(z_a, float)), np.abs(np.asarray(z_b, float))
    (z_lo, m_lo), (z_hi, m_hi) = sorted(((za, abs(m_a)), (zb, abs(m_b))), key=lambda t: t[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.log(z_hi / np.maximum(z_lo, 1e-3)) / math.log(m_hi / m_lo)
    return np.clip(np.where(np.isfinite(g), g, 1.0), 0.5, 3.0)


def _read_out(e: EffectPower, z_at: np.ndarray, z_against: np.ndarray) -> EffectPower:
    """``e`` with the z-vectors at its magnitudes: the probe and half of it, or
    ``e.read_at`` and ``e.against`` (refined; :meth:`EffectPower.z_of`)."""
    if e.read_at is None:
        return replace(e, z=tuple(float(x) for x in z_at), gamma=_gamma(z_at, z_against))
    g = pair_exponents(z_at, e.read_at, z_against, e.against)
    big = z_against if abs(e.against) >= abs(e.read_at) else z_at
    return replace(e, z=tuple(float(x) for x in z_at), gamma=float(g[int(np.argmax(np.abs(big)))]),
                   z_against=tuple(float(x) for x in z_against))  # fmt: skip


def limit_intervals(
    effects: Sequence[EffectPower],
    copies: Sequence[tuple[list[pd.DataFrame], list[pd.DataFrame]]],
    base: list[pd.DataFrame],
    candidates: Sequence[Candidate],
    n: int,
    observables: Sequence[str],
    z_crit: float,
    power: float,
    rng: np.random.Generator,
    n_boot: int = 40,
    ens: float = 1.0,
) -> list[EffectPower]:
    """Each limit with a 95 % percentile interval from a bootstrap over the simulated starts.

    The limits come from one set of simulated starts, and one set can be far off.
    Resampling the simulated fibers with replacement (the same rows for every
    copy, effect and magnitude, so each resample is one other set of starts
    drawn from the same ones) and repeating the whole read-out (z-vectors at
    both magnitudes, exponent, limit) gives the spread of the limit that the
    choice of starts causes, with no new simulation.

    Parameters
    ----------
    effects : sequence of EffectPower
        As :func:`analyse_power` found them.
    copies : sequence of (read, against)
        The copies with the effect at the read-out magnitude (the probe, or the
        refined one, :attr:`EffectPower.at`) and at the magnitude its exponent is
        read against (half the probe, or :attr:`EffectPower.against`), one pair
        per entry of ``effects``, over the same simulated rows as ``base``.
    ens : float
        The ensemble-size factor :func:`analyse_power` applied to the z-vectors.
    n_boot : int
        Resamples (40 resolve the 2.5 / 97.5 % points to about one resample).

    Returns
    -------
    list of EffectPower
        ``effects`` with ``limit_ci`` set.
    """
    n_sim = len(base[0])
    by = {c.name: c for c in candidates}
    lims: list[list[float]] = [[] for _ in effects]
    reads: list[list[tuple[tuple[float, ...], float]]] = [[] for _ in effects]
    for _ in range(n_boot):
        idx = rng.integers(0, n_sim, n_sim)
        sub_b = [b.iloc[idx].reset_index(drop=True) for b in base]
        for i, (e, (full, half)) in enumerate(zip(effects, copies, strict=True)):
            sub_f = [d.iloc[idx].reset_index(drop=True) for d in full]
            sub_h = [d.iloc[idx].reset_index(drop=True) for d in half]
            z_full = _z_of(sub_f, sub_b, observables, rng, n_perm=99, n_boot=1) * ens
            z_half = _z_of(sub_h, sub_b, observables, rng, n_perm=99, n_boot=1) * ens
            eb = _read_out(e, z_full, z_half)
            lim = _limit(eb, by[e.name], n, n_sim, z_crit, power)
            lims[i].append(math.inf if lim is None else abs(lim))
            # (z, gamma) read at the probe; a refined read-out adds z_against
            reads[i].append((eb.z, eb.gamma) if e.read_at is None
                            else (eb.z, eb.gamma, eb.z_against))  # fmt: skip
    out = []
    for e, ls, rd in zip(effects, lims, reads, strict=True):
        ci = tuple(None if x is None else math.copysign(x, e.probe)
                   for x in percentile_interval(ls))  # fmt: skip
        out.append(replace(e, limit_ci=ci, boot=tuple(rd)))
    return out


def analyse_power(
    maker: CopyMaker,
    candidates: Sequence[Candidate],
    n: int,
    observables: Sequence[str],
    rng: np.random.Generator,
    n_sim: int | None = None,
    copies: int = 3,
    workflow_copies: int = 8,
    alpha: float = 0.05,
    power: float = 0.8,
    n_boot: int = 0,
    refine: int = 4,
) -> PowerResult:
    """Detection limits and look-alikes of ``candidates`` (see the module docstring).

    Parameters
    ----------
    maker : CopyMaker
        Over the starts the analysis is for (its first ``n_sim`` fibers are simulated).
    n : int
        Fibers the limits are stated for.
    n_sim : int, optional
        Fibers simulated (default all of the maker's, at most 60).
    copies : int
        Copies per magnitude (>= 3: each plays the measurement against the others).
    workflow_copies : int
        Copies the workflow scores against: the z of a test with ``copies - 1``
        ensemble members is scaled by sqrt((1 + 1/(copies-1)) / (1 + 1/workflow_copies)).
    alpha, power : float
    n_boot : int
        Bootstrap resamples of the simulated starts for each limit's interval
        (:func:`limit_intervals`; 0: none). No new simulation.
    refine : int
        Most times a limit far from the magnitudes it was read from is read
        again at the limit (one more simulated magnitude each; module
        docstring). 0: never.
    """
    if copies < 3:
        raise ValueError(f"copies must be >= 3, got {copies}")
    n_sim = min(maker.n, n_sim or 60)
    rows = np.arange(n_sim)
    used0 = maker.sim.used
    certain, later = planned_runs(candidates, n_sim, copies, refine)
    expect = getattr(maker.sim, "expect", None)  # a progress bar's length, where there is one
    if expect is not None:
        expect(certain, later=later)
    base = maker.copies(range(copies), None, rows, desc="power baseline")
    ens = ensemble_factor(copies, workflow_copies)
    g0 = assess_gap(value_matrices(base[0], base[1:], observables), rng, n_perm=99, n_boot=10)
    one_sided = tuple(bool(x) for x in feature_one_sided(g0))
    m_tests = len(one_sided)
    z_crit = float(norm.ppf(1 - alpha / (2 * m_tests)))
    base_std = standardised_values(base, observables)
    spread = np.nanstd(np.stack(base_std), axis=(0, 1))
    spread = np.where(spread > 0, spread, np.nan)
    effects: list[EffectPower] = []
    kept: list[tuple[list[pd.DataFrame], list[pd.DataFrame]]] = []
    # the dispersion test's own stream: the limits of the gap family stay as they were
    drng = np.random.default_rng([n_sim, 8101])
    shifts: dict[str, np.ndarray] = {}
    for cand in candidates:
        for mp in cand.probes:
            z_full, eff = _z_vector(maker, base, {cand.name: mp}, rows, observables, rng)
            if cand.categorical:  # an alternative has no half: it is on or off
                z_half, eff_h = z_full, eff
            else:
                z_half, eff_h = _z_vector(maker, base, {cand.name: mp / 2}, rows, observables,
                                          rng)  # fmt: skip
            z_full, z_half = z_full * ens, z_half * ens
            e = _read_out(EffectPower(cand.name, float(mp), (), 1.0, None, one_sided),
                          z_full, z_half)  # fmt: skip
            lim = _limit(e, cand, n, n_sim, z_crit, power)
            e, lim, pair = _refine(e, lim, (eff, eff_h), z_half, refine, cand, maker, base,
                                   rows, observables, rng, n, z_crit, power, ens)  # fmt: skip
            kept.append(pair)
            d_lim = None
            if cand.random:
                zd_full = _z_dispersion(eff, base, observables, drng) * ens
                zd_half = _z_dispersion(eff_h, base, observables, drng) * ens
                ed = EffectPower(
                    cand.name,
                    float(mp),
                    (zd_full,),
                    _gamma(np.array([zd_full]), np.array([zd_half])),
                    None,
                    (True,),
                )
                # one test alone at alpha: its one-sided threshold z_{1-alpha}
                d_lim = _limit(ed, cand, n, n_sim, float(norm.isf(alpha / 2)), power)
            effects.append(replace(e, limit=lim, dispersion_limit=d_lim))
            diff = np.stack(standardised_values(eff, observables)) - np.stack(base_std)
            cnt = np.isfinite(diff).sum(axis=0)
            d = np.where(cnt > 0, np.nansum(diff, axis=0) / np.maximum(cnt, 1), np.nan)
            shifts[f"{cand.name}@{mp:g}"] = (d / spread).ravel()
    keys = list(shifts)
    cos = {}
    for i, a in enumerate(keys):
        for b in keys[i + 1 :]:
            if a.split("@")[0] != b.split("@")[0]:
                cos[(a, b)] = _cosine(shifts[a], shifts[b])
    look = sorted(
        ((a, b, c) for (a, b), c in cos.items() if c >= LOOKALIKE_COSINE), key=lambda t: -t[2]
    )
    if expect is not None:
        expect(0)  # the re-reads that did not run are no longer "later"
    if n_boot:
        effects = limit_intervals(effects, kept, base, candidates, n, observables, z_crit,
                                  power, rng, n_boot=n_boot, ens=ens)  # fmt: skip
    return PowerResult(
        n=n,
        n_sim=n_sim,
        alpha=alpha,
        power=power,
        z_crit=z_crit,
        effects=effects,
        lookalikes=look,
        cosines=cos,
        simulations=maker.sim.used - used0,
    )


def planned_runs(
    candidates: Sequence[Candidate], n_sim: int, copies: int = 3, refine: int = 4
) -> tuple[int, int]:
    """Runs :func:`analyse_power` asks for: those it always asks for, and at most how many more.

    Copies the maker already holds (the workflow's baseline) are counted too, so a bar
    sized by this may end shorter (:func:`fibersweep.progressbar.finish`).

    Parameters
    ----------
    candidates : sequence of Candidate
    n_sim : int
        Fibers simulated.
    copies : int
        Copies per magnitude.
    refine : int
        Most re-reads of each limit at the limit (one magnitude each).

    Returns
    -------
    (int, int)
        The baseline, each probe and (a numeric candidate's) half of it; and the
        re-reads, which run only where a limit lies far from its magnitudes.
    """
    per = copies * n_sim
    probes = [(c, m) for c in candidates for m in c.probes]
    certain = per * (1 + sum(1 if c.categorical else 2 for c, _ in probes))
    later = per * refine * sum(not c.categorical for c, _ in probes)
    return certain, later


def _refine(
    e: EffectPower,
    lim: float | None,
    pair: tuple[list[pd.DataFrame], list[pd.DataFrame]],
    z_half: np.ndarray,
    times: int,
    cand: Candidate,
    maker: CopyMaker,
    base: list[pd.DataFrame],
    rows: np.ndarray,
    observables: Sequence[str],
    rng: np.random.Generator,
    n: int,
    z_crit: float,
    power: float,
    ens: float,
) -> tuple[EffectPower, float | None, tuple[list[pd.DataFrame], list[pd.DataFrame]]]:
    """Read the limit again where it lies while it is far from its read-out's magnitudes.

    Far: more than ``REFINE_FACTOR`` from both, and not between them within
    ``BRACKET_RATIO``. ``pair`` holds the copies at the probe and at half of it.
    Returns the read-out, its limit and its (read, against) copies.
    """
    sims = {e.probe: (np.asarray(e.z), pair[0]), e.probe / 2.0: (z_half, pair[1])}
    n_sim = len(rows)
    for _ in range(times):
        pair_m = (e.probe, e.probe / 2.0) if e.read_at is None else (e.read_at, e.against)
        lo, hi = sorted(abs(m) for m in pair_m)
        if (
            lim is None
            or any(m / REFINE_FACTOR <= abs(lim) <= m * REFINE_FACTOR for m in (lo, hi))
            or (lo <= abs(lim) <= hi and hi <= BRACKET_RATIO * lo)
        ):
            break  # read close to the limit, or interpolated over a short bracket
        grow = getattr(maker.sim, "expect_more", None)
        if grow is not None:
            grow(len(base) * n_sim)  # a refinement the bar counted as "later" now runs
        z_r, eff_r = _z_vector(maker, base, {cand.name: lim}, rows, observables, rng)
        z_r = z_r * ens
        near = min(sims, key=lambda m: abs(math.log(abs(m) / abs(lim))))
        e = _read_out(replace(e, read_at=float(lim), against=float(near)), z_r, sims[near][0])
        pair = (eff_r, sims[near][1])
        sims[lim] = (z_r, eff_r)
        new = _limit(e, cand, n, n_sim, z_crit, power)
        log.info("power %s@%g: limit %s read at %.3g and %.3g", cand.name, e.probe, new, lim,
                 near)  # fmt: skip
        lim = new
    return e, lim, pair


def _limit(
    e: EffectPower, cand: Candidate, n: int, n_sim: int, z_crit: float, power: float
) -> float | None:
    """Smallest |m| in the probe's direction within the range with P(detect) >= power.

    An alternative (categorical): 1 when it is detected with the power, else None.
    """
    if cand.categorical:
        return 1.0 if e.detect(1.0, n, n_sim, z_crit) >= power else None
    edge = cand.hi if e.probe > 0 else cand.lo
    if e.detect(edge, n, n_sim, z_crit) < power:
        return None
    lo, hi = 0.0, abs(edge)
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if e.detect(math.copysign(mid, e.probe), n, n_sim, z_crit) >= power:
            hi = mid
        else:
            lo = mid
    return math.copysign(hi, e.probe)


def limit_in_unit(cand: Candidate, e: EffectPower) -> dict[str, Any]:
    """A declared candidate's detection limit in its setting's unit ({} for an effect).

    Returns
    -------
    dict
        ``setting``: the limit as a sentence ("flexibility detected for
        fiber.young_modulus <= 5.1e+05 Pa [2.09e+05, 4.25e+06]"); ``unit``;
        ``limit_setting`` and ``limit_ci_setting``: the limit and its 95 % interval
        in the unit, low end first (None where not within the range);
        ``unseen``: what may be present unseen, from the interval's end farther
        from the baseline ("flexibility of fiber.young_modulus >= 1.4e+06 Pa");
        ``probe_setting``: the value the power was probed at, in the unit (a
        categorical candidate: its alternative). A stiffness of the ``rigid``
        scale runs backwards: a larger value is a softer fiber, so its limit is
        the stiffest fiber detected.
    """
    if cand.is_effect:
        return {}
    probe = {"probe_setting": cand.setting(e.probe)}
    if cand.categorical:
        seen = e.limit is not None
        text = (f"detected with {cand.key} = {cand.choice}" if seen
                else f"{cand.key} = {cand.choice} not detected with these fibers")  # fmt: skip
        unseen = None if seen else f"{cand.key} = {cand.choice}"
        return {"setting": text, "unit": cand.unit, "limit_setting": None, "unseen": unseen,
                **probe}  # fmt: skip
    if e.limit is None:
        return {
            "setting": "not detected within its range", "unit": cand.unit,
            "limit_setting": None, "unseen": f"{cand.key} anywhere in its range", **probe,
        }  # fmt: skip
    value = cand.setting(e.limit)
    ci = None
    unseen = None
    if e.limit_ci is not None:
        ends = [cand.setting(x) if x is not None else None for x in e.limit_ci]
        ci = ends[::-1] if cand.scale == "rigid" else ends
        far = e.limit_ci[1]
        if cand.scale == "rigid":
            unseen = (f"flexibility of {cand.key} >= {cand.show_value(far)}" if far is not None
                      else f"flexibility of {cand.key} anywhere in its range")  # fmt: skip
        else:
            unseen = (f"{cand.key} up to {cand.show_value(far)}" if far is not None
                      else f"{cand.key} anywhere in its range")  # fmt: skip
    if cand.scale == "rigid":
        text = f"flexibility detected for {cand.key} <= {cand.show_value(e.limit)}"
    else:
        side = "above" if e.probe > 0 else "below"
        text = f"detected {side} {cand.key} = {cand.show_value(e.limit)}"
    if ci is not None:
        text += " [" + ", ".join(f"{x:.3g}" if x is not None else "out of range" for x in ci)
        text += "]"
    return {
        "setting": text, "unit": cand.unit, "limit_setting": value,
        "limit_ci_setting": ci, "unseen": unseen, **probe,
    }  # fmt: skip
