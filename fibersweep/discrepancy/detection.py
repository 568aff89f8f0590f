"""Detection by the gap tests: the read-out of expected z-vectors, limits, fibers to detect.

A power analysis (:mod:`.power`) reads the expected z-vector of the gap tests'
family (score per observable, one-sided; signed residual per component,
two-sided) at a magnitude of an effect, with ``n_sim`` simulated fibers. This
module says what N fibers would detect from it.

Scaling (the approximation this rests on, checked in docs/discrepancy.md): the z of a
test grows as ``sqrt(N)`` with the number of fibers, and as ``m ** gamma`` with
the magnitude, gamma read off two magnitudes (1 for a shift, 2 for a spread
whose variance grows as m², clipped to [0.5, 3]; :func:`growth_exponent`). Read
at a refined magnitude (:mod:`.power`), each test's z follows its own power law
between the two magnitudes it was read at, exact at both (:func:`pair_exponents`).

The family detects when any test passes its Bonferroni threshold at alpha / m
(Holm is at least as powerful): ``P(detect) = 1 - prod_j (1 - P_j)``, with
``P_j = Phi(z_j - z1)`` for a one-sided score test (z1 = Phi^-1(1 - alpha/m); a
score better than the model's never rejects) and ``Phi(|z_j| - z_crit)`` for a
two-sided residual (z_crit = Phi^-1(1 - alpha/2m)); :func:`detect_probability`.
The smallest magnitude with ``P(detect) >= power`` is the detection limit
(:func:`detection_limit`); the fibers that detect a magnitude m follow from the
same formula (:meth:`EffectPower.fibers_to_detect`). Detection is the first gate
only: naming needs the held-out improvement too (half of the fibers fit, the
other half test), so the limit to *name* an effect is higher.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from scipy.stats import norm

from fibersweep.discrepancy.candidates import Candidate

__all__ = [
    "EffectPower",
    "PowerResult",
    "detect_probability",
    "detection_limit",
    "ensemble_factor",
    "growth_exponent",
    "limit_in_unit",
    "pair_exponents",
    "percentile_interval",
    "read_out",
]


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
        (:func:`.power.limit_intervals`); an end None: beyond the effect's range in
        more than 2.5 % of the resamples. None: not computed.
    dispersion_limit : float or None
        For a random effect: the smallest magnitude the dispersion test alone
        (:mod:`.dispersion`, one-sided at alpha) detects with the target power
        at ``n`` fibers, scaled like ``limit``. None: not a random effect, or
        not within its range.
    boot : tuple of (z, gamma) or (z, gamma, z_against)
        The read-out of each bootstrap resample of the simulated starts
        (:func:`.power.limit_intervals`), for the intervals of derived numbers
        (:meth:`fibers_to_detect_ci`). Empty: not computed.
    read_at : float or None
        Magnitude (signed) the z-vector was read at, when not the probe: the
        refined read-out near the limit (:mod:`.power`). None: the probe.
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

    def fibers_to_detect(
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

    def fibers_to_detect_ci(
        self, m: float, n_sim: int, z_crit: float, power: float, level: float = 0.95
    ) -> tuple[int | None, int | None] | None:
        """Interval of :meth:`fibers_to_detect` over the bootstrap resamples of the starts.

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
            k = eb.fibers_to_detect(m, n_sim, z_crit, power)
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

    def fibers_to_detect(self, name: str, m: float) -> int | None:
        """Fibers that detect ``name`` at magnitude m with the target power."""
        e = self.get(name, m)
        return None if e is None else e.fibers_to_detect(m, self.n_sim, self.z_crit, self.power)

    def fibers_to_detect_ci(self, name: str, m: float) -> tuple[int | None, int | None] | None:
        """95 % interval of :meth:`fibers_to_detect` over the simulated starts (None: not
        computed; an end None: beyond 100 000 fibers)."""
        e = self.get(name, m)
        return None if e is None else e.fibers_to_detect_ci(m, self.n_sim, self.z_crit, self.power)


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


def ensemble_factor(copies: int, workflow_copies: int) -> float:
    """Scale of a z read with ``copies - 1`` baseline copies to one with ``workflow_copies``.

    sqrt((1 + 1/(copies - 1)) / (1 + 1/workflow_copies)): the copies' own noise in
    the null shrinks with the ensemble the workflow scores against.
    """
    return math.sqrt((1 + 1 / (copies - 1)) / (1 + 1 / workflow_copies))


def growth_exponent(z_full: np.ndarray, z_half: np.ndarray) -> float:
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


def read_out(e: EffectPower, z_at: np.ndarray, z_against: np.ndarray) -> EffectPower:
    """``e`` with the z-vectors at its magnitudes: the probe and half of it, or
    ``e.read_at`` and ``e.against`` (refined; :meth:`EffectPower.z_of`)."""
    if e.read_at is None:
        return replace(e, z=tuple(float(x) for x in z_at), gamma=growth_exponent(z_at, z_against))
    g = pair_exponents(z_at, e.read_at, z_against, e.against)
    big = z_against if abs(e.against) >= abs(e.read_at) else z_at
    return replace(e, z=tuple(float(x) for x in z_at), gamma=float(g[int(np.argmax(np.abs(big)))]),
                   z_against=tuple(float(x) for x in z_against))  # fmt: skip


def detection_limit(
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
