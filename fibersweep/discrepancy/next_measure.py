"""What to measure next: where one fiber separates two hypotheses most, and how many would do.

Two hypotheses (e.g. the two effects of an ambiguous verdict at their fitted
values, or one effect at its two fold values when the halves disagree;
:func:`.followup.next_hypotheses`) are simulated at a grid of candidate starts
(θ0, y0, L spanning the measured range) with the same copies (common random
numbers, measurement noise included). Per start and observable component
(:mod:`.components`) the *discrimination* is

    D = |mean_k (x_A,k - x_B,k)| / s

(its square debiased by the variance of that mean over the k copies, averaged
before it is clipped at 0), with s the component's spread among the copies of
both hypotheses (noise of one measured fiber); a start's D is the root sum of
squares over its components. Two copies per start are enough to rank the grid,
not to size the measurement: the best of many noisy estimates overstates itself
(the winner's curse; on the flow-grid case 2.5 per fiber at the best start
against 0.2-0.3 from 16 new copies there).

So the ``CONFIRM_STARTS`` best starts are measured again: at ``CONFIRM_POINTS``
points each, uniform within ``WINDOW`` start-noise sd of the start (where a
fiber measured "at" it lands), with as many new copies per point as the
follow-up test uses, scored by that test's own statistic (the log-likelihood
ratio λ of :mod:`.discriminant`). A start's separation per fiber is
(g_A - g_B) / sd, λ's mean under each hypothesis over its sd, and the fibers
to settle it, shared over these starts, are those for which each of the
follow-up test's one-sided tests rejects the false hypothesis with the target
power (:func:`.discriminant.fibers_to_settle`). The count at the measured
starts (``fibers_to_separate_measured``) is of another kind, for comparison
only: the grid's two-copy D averaged over the measured starts, for a two-sided
test with known predictions, ``ceil(((z_{1 - alpha/2} + z_power) / D)²)``
(:func:`fibers_to_separate`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence

import numpy as np
from scipy.stats import norm

from fibersweep.discrepancy.components import component_names
from fibersweep.discrepancy.copies import CopyMaker, NoiseModel
from fibersweep.discrepancy.discriminant import fibers_to_settle, noise_spread, window_separation
from fibersweep.discrepancy.result import Discrimination, Suggestion
from fibersweep.discrepancy.settle import hypothesis_copies
from fibersweep.discrepancy.simulate import Simulator

__all__ = [
    "CONFIRM_POINTS",
    "CONFIRM_STARTS",
    "WINDOW",
    "discriminate",
    "fibers_to_separate",
    "hypothesis_label",
    "start_grid",
    "window_points",
]


#: Half-width of the window around a proposed start, in start-noise sd: the fibers
#: measured "at" a start are those whose measured start falls within it.
WINDOW = 3.0


#: Points per best start, and best starts, where what-to-measure-next measures the
#: separation again with the follow-up test's statistic.
CONFIRM_POINTS = 8


CONFIRM_STARTS = 5


def start_grid(starts: np.ndarray, n_theta: int = 5, n_y: int = 8, n_len: int = 3) -> np.ndarray:
    """A regular grid spanning the measured starts; an axis that does not vary keeps its value.

    Returns
    -------
    ndarray, shape (g, 3)
        theta0 [deg], y0 [/h_obs], length [/l_obs].
    """
    s = np.asarray(starts, dtype=np.float64)
    axes = []
    for j, k in enumerate((n_theta, n_y, n_len)):
        lo, hi = float(np.nanmin(s[:, j])), float(np.nanmax(s[:, j]))
        axes.append(np.linspace(lo, hi, k) if hi - lo > 1e-9 else np.array([lo]))
    g = np.meshgrid(*axes, indexing="ij")
    return np.column_stack([a.ravel() for a in g])


def fibers_to_separate(d: float, alpha: float, power: float) -> int | None:
    """Fibers for which a two-sided test with known predictions separates two hypotheses.

    ``ceil(((z_{1 - alpha/2} + z_power) / d)²)``, with ``d`` the discrimination of
    one fiber (its predictions' difference over its noise). None when ``d`` is not
    finite or not above 1e-9.
    """
    if not np.isfinite(d) or d <= 1e-9:
        return None
    z = norm.ppf(1 - alpha / 2) + norm.ppf(power)
    return int(math.ceil((z / d) ** 2))


def hypothesis_label(effects: Mapping[str, float]) -> str:
    """``name = value`` of each effect, joined by ' + ' ('baseline' for none)."""
    return " + ".join(f"{k} = {v:.3g}" for k, v in effects.items()) or "baseline"


def _shift2(xa: np.ndarray, xb: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Unbiased squared standardised shift per point and component, shape (points, c).

    Paired (common random numbers) per-copy differences; their mean squared, less the
    noise of that mean (its variance). Unclipped: negative where noise exceeds the
    shift. Average before clipping at 0; clipping each point first biases the average
    up (four-fold for a shift of 0.5 noise sd with two copies).
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        delta = (xa - xb) / s
        cnt = np.isfinite(delta).sum(axis=0)
        mean = np.where(cnt > 0, np.nansum(delta, axis=0) / np.maximum(cnt, 1), np.nan)
        ss = np.nansum((delta - mean) ** 2, axis=0)
        var = np.where(cnt > 1, ss / np.maximum(cnt - 1, 1) / np.maximum(cnt, 1), 0.0)
    diff = np.where(np.isfinite(mean), mean, 0.0)
    return diff**2 - np.where(np.isfinite(var), var, 0.0)


def window_points(
    centres: np.ndarray, noise: NoiseModel, m: int, rng: np.random.Generator, width: float = WINDOW
) -> np.ndarray:
    """``m`` starts uniform within ``width`` start-noise sd of each centre.

    Returns
    -------
    ndarray, shape (len(centres) * m, 3)
        Centre j's points are rows j*m .. j*m + m - 1.
    """
    c = np.repeat(np.asarray(centres, dtype=np.float64), m, axis=0)
    half = width * np.array([noise.theta0, noise.y0, noise.length])
    return c + rng.uniform(-1.0, 1.0, size=c.shape) * half


def discriminate(
    sim: Simulator,
    noise: NoiseModel,
    hypotheses: tuple[Mapping[str, float], Mapping[str, float]],
    starts: np.ndarray,
    observables: Sequence[str],
    seed: int = 0,
    copies: int = 2,
    grid: np.ndarray | None = None,
    top: int = 8,
    alpha: float = 0.05,
    power: float = 0.8,
    show: Callable[[Mapping[str, float]], str] | None = None,
    confirm: int = CONFIRM_POINTS,
    confirm_starts: int = CONFIRM_STARTS,
    confirm_copies: int = 24,
) -> Discrimination:
    """Rank candidate starts by how well one fiber there separates the hypotheses.

    Parameters
    ----------
    sim : Simulator
    noise : NoiseModel
        Measurement model (start and outcome noise) of the copies.
    hypotheses : (mapping, mapping)
        The two sets of effects to separate.
    starts : ndarray, shape (n, 3)
        Measured starts (the grid spans them; also scored for the comparison).
    observables : sequence of str
        Observables that would be measured.
    copies : int
        Copies per hypothesis and grid start (>= 2): enough to rank them.
    show : callable, optional
        ``{name: value} -> text`` for the two labels (each value in its
        candidate's unit); default ``name = value``.
    confirm, confirm_starts, confirm_copies : int
        The ``confirm_starts`` best grid starts are measured again at ``confirm``
        points each, uniform within ``WINDOW`` start-noise sd (where a fiber
        measured "at" the start lands), with ``confirm_copies`` new copies per
        point and hypothesis, scored by the follow-up test's own statistic
        (:func:`.discriminant.window_separation`): their separation per fiber
        and the fibers to settle are those of :func:`.discriminant.settle_test`
        (``confirm`` 0: the grid's estimates, optimistic by the winner's curse).
    """
    label = show or hypothesis_label
    if copies < 2:
        raise ValueError(f"copies must be >= 2, got {copies}")
    g = start_grid(starts) if grid is None else np.asarray(grid, dtype=np.float64)
    pts = np.vstack([g, np.asarray(starts, dtype=np.float64)])
    used0 = sim.used
    xa, xb, _, _ = hypothesis_copies(CopyMaker(pts, noise, seed + 104729, sim), hypotheses,
                                     copies, observables, "next")  # fmt: skip
    raw = _shift2(xa, xb, noise_spread(xa, xb))  # (points, components), unclipped
    ng = len(g)
    d = np.sqrt(np.clip(raw[:ng], 0.0, None).sum(axis=1))  # ranks the grid
    order = np.argsort(-d)[:top]
    d_best = d[order]
    need = fibers_to_separate(float(np.sqrt(max(raw[order].sum(axis=1).mean(), 0.0))), alpha, power)
    window = None
    if confirm and len(order):
        order = order[:confirm_starts]
        k_ref = max(confirm_copies, 6) // 3
        w = window_points(g[order], noise, confirm, np.random.default_rng([seed, 104743]))
        wa, wb, oka, okb = hypothesis_copies(CopyMaker(w, noise, seed + 104759, sim), hypotheses,
                                             max(confirm_copies, 6), observables,
                                             "next: confirm")  # fmt: skip
        sep = []  # per start: g_A, g_B, sd_A, sd_B
        for j in range(len(order)):
            sl = slice(j * confirm, (j + 1) * confirm)
            ok = (oka[:k_ref, sl], okb[:k_ref, sl], oka[k_ref:, sl], okb[k_ref:, sl])
            sep.append(window_separation(wa[:k_ref, sl], wb[:k_ref, sl], wa[k_ref:, sl],
                                         wb[k_ref:, sl], ok=ok))  # fmt: skip
        sep = np.nan_to_num(np.array(sep))  # a side without two valid copies: no separation
        gap = sep[:, 0] - sep[:, 1]
        sd = np.sqrt((sep[:, 2] ** 2 + sep[:, 3] ** 2) / 2)
        d_best = np.where(sd > 0, np.clip(gap, 0.0, None) / np.where(sd > 0, sd, 1.0), 0.0)
        resort = np.argsort(-d_best, kind="stable")
        order, d_best = order[resort], d_best[resort]
        # fibers shared equally over these starts: all their points at once, as the
        # follow-up test scores them (its noise floor is over all its fibers)
        ok = (oka[:k_ref], okb[:k_ref], oka[k_ref:], okb[k_ref:])
        g_a, g_b, sd_a, sd_b = window_separation(wa[:k_ref], wb[:k_ref], wa[k_ref:],
                                                 wb[k_ref:], ok=ok)  # fmt: skip
        need = fibers_to_settle(g_a - g_b, sd_a, sd_b, alpha, power,
                                k_null=max(confirm_copies, 6) - k_ref)  # fmt: skip
        window = WINDOW * np.array([noise.theta0, noise.y0, noise.length])
    names = component_names(observables)
    best = []
    for i, di in zip(order, d_best, strict=True):
        j = int(np.argmax(raw[i]))  # the component that separates most there, on the grid
        best.append(
            Suggestion(
                float(g[i, 0]),
                float(g[i, 1]),
                float(g[i, 2]),
                float(di),
                names[j],
                float(np.nanmean(xa[:, i, j])),
                float(np.nanmean(xb[:, i, j])),
            )  # fmt: skip
        )
    meas2 = raw[ng:].sum(axis=1)
    d_m = float(np.sqrt(max(np.mean(meas2), 0.0))) if len(meas2) else 0.0
    return Discrimination(
        labels=(label(hypotheses[0]) or "baseline", label(hypotheses[1]) or "baseline"),
        grid=g,
        d=d,
        best=best,
        fibers_to_settle=need,
        fibers_to_separate_measured=fibers_to_separate(d_m, alpha, power),
        simulations=sim.used - used0,
        window=window,
    )
