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
and number of fibers. What N fibers detect from it (the power-law scaling in N
and the magnitude, the detection probability of the family, the limit and the
fibers to detect a magnitude): :mod:`.detection`.

A power law is only good near where it was read: a permutation z saturates once
a shift is large against the copies' spread (the shifted column widens its own
null), and a score's excess grows as m² for small shifts but m for large ones.
So unless the limit lies within a factor ``REFINE_FACTOR`` of one of the two
magnitudes it was read from, or between them with at most ``BRACKET_RATIO`` from
one to the other, the effect is simulated again at the limit, and the limit is
read again from two magnitudes: that one and the simulated one nearest to it,
each test's z following its own power law between them (exact at both); at most
``refine`` times.

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
from dataclasses import replace

import numpy as np
import pandas as pd
from scipy.stats import norm

from fibersweep.discrepancy.candidates import Candidate
from fibersweep.discrepancy.components import standardised_values
from fibersweep.discrepancy.copies import CopyMaker
from fibersweep.discrepancy.detection import (
    EffectPower,
    PowerResult,
    detection_limit,
    ensemble_factor,
    growth_exponent,
    percentile_interval,
    read_out,
)
from fibersweep.discrepancy.dispersion import dispersion_test
from fibersweep.discrepancy.gap import (
    assess_gap,
    feature_one_sided,
    feature_vector,
    value_matrices,
)

__all__ = [
    "BRACKET_RATIO",
    "LOOKALIKE_COSINE",
    "REFINE_FACTOR",
    "analyse_power",
    "limit_intervals",
    "planned_runs",
]


log = logging.getLogger(__name__)

#: Parallel per-fiber effects beyond this |cosine| make two effects look-alikes.
LOOKALIKE_COSINE = 0.9

#: A limit this factor away from both magnitudes it was read from is read again there,
REFINE_FACTOR = 1.25
#: unless they bracket it within this ratio (an interpolation).
BRACKET_RATIO = 4.0


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
            eb = read_out(e, z_full, z_half)
            lim = detection_limit(eb, by[e.name], n, n_sim, z_crit, power)
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
    unread: list[str] | None = None,
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
    # the probes' own batches still to come: a re-read never takes the runs they need
    ahead = sum(1 if c.categorical else 2 for c in candidates for _ in c.probes) * copies * n_sim
    for cand in candidates:
        for mp in cand.probes:
            ahead -= (1 if cand.categorical else 2) * copies * n_sim
            z_full, eff = _z_vector(maker, base, {cand.name: mp}, rows, observables, rng)
            if cand.categorical:  # an alternative has no half: it is on or off
                z_half, eff_h = z_full, eff
            else:
                z_half, eff_h = _z_vector(maker, base, {cand.name: mp / 2}, rows, observables,
                                          rng)  # fmt: skip
            z_full, z_half = z_full * ens, z_half * ens
            e = read_out(EffectPower(cand.name, float(mp), (), 1.0, None, one_sided),
                          z_full, z_half)  # fmt: skip
            lim = detection_limit(e, cand, n, n_sim, z_crit, power)
            e, lim, pair = _refine(e, lim, (eff, eff_h), z_half, refine, cand, maker, base,
                                   rows, observables, rng, n, z_crit, power, ens,
                                   unread, ahead)  # fmt: skip
            kept.append(pair)
            d_lim = None
            if cand.random:
                zd_full = _z_dispersion(eff, base, observables, drng) * ens
                zd_half = _z_dispersion(eff_h, base, observables, drng) * ens
                ed = EffectPower(
                    cand.name,
                    float(mp),
                    (zd_full,),
                    growth_exponent(np.array([zd_full]), np.array([zd_half])),
                    None,
                    (True,),
                )
                # one test alone at alpha: its one-sided threshold z_{1-alpha}
                d_lim = detection_limit(ed, cand, n, n_sim, float(norm.isf(alpha / 2)), power)
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
    unread: list[str] | None = None,
    reserve: int = 0,
) -> tuple[EffectPower, float | None, tuple[list[pd.DataFrame], list[pd.DataFrame]]]:
    """Read the limit again where it lies while it is far from its read-out's magnitudes.

    Far: more than ``REFINE_FACTOR`` from both, and not between them within
    ``BRACKET_RATIO``. ``pair`` holds the copies at the probe and at half of it.
    Returns the read-out, its limit and its (read, against) copies. A re-read
    that the simulator's budget has no room for, besides the ``reserve`` runs
    the other probes still need, is not made (noted in ``unread``).
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
        if len(base) * n_sim > getattr(maker.sim, "remaining", math.inf) - reserve:
            log.info("power %s@%g: not read again at %.3g (budget)", cand.name, e.probe, lim)
            if unread is not None:
                unread.append(f"{cand.name}@{e.probe:g}")
            break
        grow = getattr(maker.sim, "expect_more", None)
        if grow is not None:
            grow(len(base) * n_sim)  # a refinement the bar counted as "later" now runs
        z_r, eff_r = _z_vector(maker, base, {cand.name: lim}, rows, observables, rng)
        z_r = z_r * ens
        near = min(sims, key=lambda m: abs(math.log(abs(m) / abs(lim))))
        e = read_out(replace(e, read_at=float(lim), against=float(near)), z_r, sims[near][0])
        pair = (eff_r, sims[near][1])
        sims[lim] = (z_r, eff_r)
        new = detection_limit(e, cand, n, n_sim, z_crit, power)
        log.info("power %s@%g: limit %s read at %.3g and %.3g", cand.name, e.probe, new, lim,
                 near)  # fmt: skip
        lim = new
    return e, lim, pair
