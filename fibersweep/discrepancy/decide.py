"""The held-out decision: which effect, if any, explains the gap.

Every fitted candidate is scored on the held-out fibers (not used to fit it)
against the baseline with the same copies (common random numbers). Its
per-fiber improvement of the combined score is bootstrapped; the one-sided
p-value of "no improvement" is Holm-corrected over the candidates. That is the
penalty for the extra parameter: an effect enters the model only if, out of
sample, it beats the baseline by more than the noise floor allows. Then:

- no significant improvement -> "unexplained gap in region R, observable O";
- the best candidate leaves a significant gap, of the score or of the
  signed residual of any observable (one Holm family, as in
  :func:`gap.assess_gap`; the signed test catches a mean shift that a
  zero-mean spread such as start noise can widen the copies around but never
  remove) -> "unexplained" (it is at most a partial explanation);
- another candidate also improves significantly and leaves no significant gap
  -> "ambiguous between A and B" (both are consistent with the data);
- otherwise the best candidate is named.

More than one effect (forward selection, :mod:`.pairs`): when the best
single effect leaves a gap, partners are added to the significant single
effects that leave one (joint fit on the same folds) and scored out of sample.
A set ``{A, B}`` is named when each member's contribution is significant (the
pair beats A alone and beats B alone on the held-out fibers, one Holm family
over all these tests), the pair leaves no significant gap, and no single effect
explains the gap on its own. Where the best single effect is partial a weaker
one may still leave no gap; that single and an explaining set, or two
explaining sets, make the verdict "ambiguous" between them. A weaker single
that explains with no set that does is not named ("unexplained"): where the
best single is partial the gap may hold two effects it looks like. No set that
explains leaves the verdict "unexplained".

Adequacy ("no significant gap left") is checked with the effect at the value
fitted on all fibers (:func:`.stages.refit` refits the significant
candidates), so that a poor fit on one half does not hide a right effect; the
out-of-sample improvement above is what guards against over-fitting.

A random effect (start noise, Brownian motion) widens the outcomes; its
per-fiber score improvement carries its own Monte Carlo noise and is often not
significant where the effect is plain. It has a second, *spread* route: the held-out
spread test (:func:`dispersion.spread_test`: the baseline is over-dispersed and
the effect's cross-fitted copies reduce the observations' dispersion scores),
one more member of the same Holm family per random candidate. It counts only
when the held-out data are not significantly over- or under-dispersed against
the effect's copies and show no shift against them (a t test of the signed
PIT, valid under any widening: :func:`dispersion.shift_test`), two gates. A
random effect is named by this route only when nothing is named by the score
route nor by a set, and with the effect at its pooled value no significant gap
(score or signed residual: a spread cannot remove a shift) and no significant
dispersion, over or under (two-sided), is left. Two random effects passing it are "ambiguous".

The first gate ("is there a gap at all?") is the family-wise test of
:func:`gap.assess_gap` on all fibers; without it nothing is ever named.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from fibersweep.discrepancy.dispersion import SpreadTest
from fibersweep.discrepancy.gap import GapResult, paired_improvement
from fibersweep.discrepancy.scores import PermTest, boot_p, bootstrap_mean_ci, holm

__all__ = ["HeldOut", "SetHeldOut", "Verdict", "adequate", "evaluate_heldout", "decide"]


@dataclass(frozen=True)
class HeldOut:
    """One fitted candidate on the held-out fibers.

    Attributes
    ----------
    name : str
    value : float
    improvement : (mean, lo, hi)
        Per-fiber decrease of the combined score vs the baseline, bootstrap 95 %.
    p_value, p_holm : float
        One-sided bootstrap p of "no improvement", raw and Holm-adjusted.
    significant : bool
    residual : GapResult
        Cross-fitted (out-of-sample) gap with the effect on.
    explains : bool
        Significant, and with the effect at its final value (``final`` when
        given, else ``residual``) no observable's gap nor systematic residual
        remains significant (:func:`adequate`).
    per_fiber : ndarray, shape (n_heldout,)
        Per-fiber improvement (for paired comparisons).
    final : GapResult or None
        Gap on all fibers with the effect at its pooled value.
    spread : SpreadTest or None
        Random effects only: the held-out spread test (:func:`dispersion.spread_test`).
    spread_p_holm : float
        Its p Holm-adjusted in the same family as the score tests (1 for
        effects that are not random).
    spread_significant : bool
        ``spread_p_holm <= alpha``, a positive reduction, and the held-out data
        not significantly over- or under-dispersed against the effect's copies,
        nor shifted (:func:`dispersion.shift_test`).
    final_dispersion : PermTest or None
        Two-sided dispersion test on all fibers with a random effect at its
        pooled value (``explains`` requires it not significant).
    """

    name: str
    value: float
    improvement: tuple[float, float, float]
    p_value: float
    p_holm: float
    significant: bool
    residual: GapResult
    explains: bool
    per_fiber: np.ndarray = field(repr=False)
    final: GapResult | None = field(default=None, repr=False)
    spread: SpreadTest | None = field(default=None, repr=False)
    spread_p_holm: float = 1.0
    spread_significant: bool = False
    final_dispersion: PermTest | None = field(default=None, repr=False)


@dataclass(frozen=True)
class SetHeldOut:
    """A set of effects (forward selection) on the held-out fibers.

    Attributes
    ----------
    values : dict name -> float
        Quoted value of each member: when the set is significant, each member
        refitted on all fibers with the other at the mean of its folds' fits
        (:func:`.pairs.pair_refits`, as a single effect's pooled refit); else the
        mean of the two folds' fits.
    fold_values : dict name -> (float, float)
        The value used to score each fold (fitted on the other one).
    gains : dict name -> (mean, lo, hi)
        Per-fiber improvement of the set over the set without that member
        (held out, bootstrap 95 %): the member's own contribution.
    p_values, p_holm : dict name -> float
        One-sided bootstrap p of "no contribution", raw and Holm-adjusted over
        every member test of every set tried.
    improvement : (mean, lo, hi)
        Per-fiber improvement of the set over the baseline.
    residual : GapResult
        Cross-fitted gap with the set on.
    final : GapResult or None
        Gap on all fibers with the set at ``values`` (None when not checked).
    intervals : dict name -> (lo, hi, open_lo, open_hi)
        95 % interval of each member's refit (:func:`.estimate.score_interval`, a bootstrap;
        empty when the set was not refitted).
    """

    values: dict[str, float]
    fold_values: dict[str, tuple[float, float]]
    gains: dict[str, tuple[float, float, float]]
    p_values: dict[str, float]
    p_holm: dict[str, float]
    improvement: tuple[float, float, float]
    residual: GapResult
    final: GapResult | None = None
    intervals: dict[str, tuple[float, float, bool, bool]] = field(default_factory=dict)

    @property
    def name(self) -> str:
        """Members joined by ' + ' (e.g. 'friction + inlet_speed')."""
        return " + ".join(self.values)

    def significant(self, alpha: float) -> bool:
        """Every member's contribution significant (Holm-adjusted) and positive."""
        return all(self.p_holm[n] <= alpha and self.gains[n][0] > 0 for n in self.values)

    def explains(self, alpha: float) -> bool:
        """Significant and no significant gap left at the pooled values."""
        return self.significant(alpha) and adequate(self.final or self.residual)


@dataclass(frozen=True)
class Verdict:
    """The workflow's conclusion.

    Attributes
    ----------
    kind : {'no significant gap', 'named', 'ambiguous', 'unexplained'}
    effects : dict name -> fitted value
        The named effect or set of effects, or the members of every ambiguous
        alternative; empty otherwise.
    observable : str
        The observable with the strongest remaining gap ('' if none).
    region : str
        Where that gap lives ('' if none).
    text : str
        One sentence for the report.
    alternatives : tuple of dict
        For 'ambiguous': each set of effects consistent with the data
        (one updated config each); for 'named': the named set; else empty.
    """

    kind: str
    effects: dict[str, float]
    observable: str = ""
    region: str = ""
    text: str = ""
    alternatives: tuple[dict[str, float], ...] = ()


def adequate(gap: GapResult) -> bool:
    """No significant gap of either kind (score or systematic residual) left."""
    return not gap.any


def _where(region: str) -> str:
    """'in <region>' for the verdict sentence ('everywhere' as is)."""
    return region if region in ("", "everywhere") else f"in {region}"


def evaluate_heldout(
    fits: Mapping[str, float],
    base_scores: Mapping[str, np.ndarray],
    effect_scores: Mapping[str, Mapping[str, np.ndarray]],
    residuals: Mapping[str, GapResult],
    rng: np.random.Generator,
    alpha: float,
    spread: Mapping[str, SpreadTest] | None = None,
) -> list[HeldOut]:
    """Held-out comparison of each fitted effect with the baseline.

    Parameters
    ----------
    fits : mapping name -> fitted value
    base_scores : mapping observable -> ndarray (n_heldout,)
        Weighted observed scores against the baseline copies.
    effect_scores : mapping name -> (observable -> ndarray (n_heldout,))
        The same against the effect's copies.
    residuals : mapping name -> GapResult
        Held-out gap with each effect on.
    spread : mapping name -> SpreadTest, optional
        For the random effects: the held-out spread test. Each adds its p to the
        Holm family of the score tests.
    """
    names = list(fits)
    spread = {n: t for n, t in (spread or {}).items() if n in fits}
    per = {n: paired_improvement(base_scores, effect_scores[n]) for n in names}
    p = [boot_p(per[n], rng) for n in names]
    spread_names = list(spread)
    p_all = np.array(p + [spread[n].p for n in spread_names])
    adj_all = holm(p_all) if len(p_all) else p_all
    p_adj = adj_all[: len(names)]
    spread_adj = dict(zip(spread_names, adj_all[len(names) :], strict=True))
    out = []
    for k, n in enumerate(names):
        mean, lo, hi = bootstrap_mean_ci(per[n], rng)
        sig = bool(p_adj[k] <= alpha and mean > 0)
        extra = {}
        if n in spread:
            t = spread[n]
            extra = dict(
                spread=t,
                spread_p_holm=float(spread_adj[n]),
                spread_significant=bool(
                    spread_adj[n] <= alpha
                    and t.reduction[0] > 0
                    and t.calm.p_value > alpha
                    and t.p_shift > alpha
                ),
            )
        out.append(
            HeldOut(
                name=n,
                value=float(fits[n]),
                improvement=(mean, lo, hi),
                p_value=float(p[k]),
                p_holm=float(p_adj[k]),
                significant=sig,
                residual=residuals[n],
                explains=sig and adequate(residuals[n]),
                per_fiber=per[n],
                **extra,
            )
        )
    return out


def decide(
    gap: GapResult,
    heldout: Sequence[HeldOut],
    region: str,
    rng: np.random.Generator,
    alpha: float,
    sets: Sequence[SetHeldOut] = (),
    show: Callable[[Mapping[str, float]], str] | None = None,
    declared: Sequence[str] = (),
) -> Verdict:
    """Apply the decision rule of the module docstring.

    Parameters
    ----------
    gap : GapResult
        Gap on all fibers against the baseline.
    heldout : sequence of HeldOut
        Fitted candidates on the held-out fibers.
    region : str
        Description of where the baseline gap lives.
    sets : sequence of SetHeldOut
        Sets of effects tried by forward selection (only used when no single
        effect explains the gap).
    show : callable, optional
        ``{name: value} -> text`` for the verdict (each value in its candidate's
        unit, :func:`.candidates.show_values`); default ``name = value``.
    declared : sequence of str
        Names of the declared candidates (``--candidate``): an unexplained verdict
        says that neither the library nor these improved the held-out fibers.
    """
    show = show or _values_text
    if not gap.any:
        return Verdict(
            "no significant gap",
            {},
            text=f"No observable differs from the baseline beyond its noise floor "
            f"(Holm, alpha = {alpha:g}).",
        )
    top_obs = gap.flagged[0]
    sig = [h for h in heldout if h.significant]
    good_sets = sorted((st for st in sets if st.explains(alpha)), key=lambda st: -st.improvement[0])
    best_single = max(sig, key=lambda h: h.improvement[0]) if sig else None
    if good_sets and not (best_single is not None and best_single.explains):
        # sets are tried where the best single leaves a gap; another single that
        # explains is then as consistent with the data as the set
        lone = sorted((h for h in sig if h.explains), key=lambda h: -h.improvement[0])
        if lone:
            return _mixed_verdict(lone, good_sets, top_obs, region, show)
        return _set_verdict(good_sets, top_obs, region, show)
    spread = sorted(
        (h for h in heldout if h.spread_significant and h.explains and h.spread is not None),
        key=lambda h: h.spread_p_holm,
    )
    if spread and not any(h.explains for h in sig):
        return _spread_verdict(spread, top_obs, region)
    if not sig:
        return Verdict(
            "unexplained",
            {},
            top_obs,
            region,
            f"Unexplained gap {_where(region)}, observable {top_obs}: "
            f"{_none_of(declared)} improves the held-out fibers significantly.",
        )
    best = max(sig, key=lambda h: h.improvement[0])
    if not best.explains:
        left = best.final or best.residual
        rest = left.flagged
        obs = rest[0] if rest else top_obs
        what = []
        if left.significant:
            what.append(f"a significant gap in {', '.join(left.significant)}")
        if left.biased:
            what.append(f"a significant systematic residual in {', '.join(left.biased)}")
        # a weaker single that leaves no gap, with no set that explains, is not named:
        # where the best one is partial the gap may hold two effects it looks like
        weaker = [h.name for h in sig if h.explains]
        also = (
            f" {', '.join(weaker)} alone leaves no significant gap but improves the "
            "held-out fibers less, and no set of two effects explains the gap."
            if weaker
            else ""
        )
        return Verdict(
            "unexplained",
            {},
            obs,
            region,
            f"Unexplained gap {_where(region)}, observable {obs}: the best effect, "
            f"{show({best.name: best.value})}, improves the held-out fibers but leaves "
            f"{' and '.join(what) or 'a significant gap'}.{also}",
        )
    # A rival that also leaves no significant gap is just as consistent with the data.
    # (A paired comparison of the two is not used: with common random numbers it is
    # precise enough to resolve the two fits' small parameter errors, which would
    # then pick a look-alike by chance.)
    rivals = [h for h in sig if h is not best and h.explains]
    if rivals:
        other = max(rivals, key=lambda h: h.improvement[0])
        return Verdict(
            "ambiguous",
            {best.name: best.value, other.name: other.value},
            top_obs,
            region,
            f"Ambiguous between {show({best.name: best.value})} and "
            f"{show({other.name: other.value})}: with either, no significant gap is left.",
            ({best.name: best.value}, {other.name: other.value}),
        )
    return Verdict(
        "named",
        {best.name: best.value},
        top_obs,
        region,
        f"{show({best.name: best.value})} explains the gap (held-out improvement "
        f"{best.improvement[0]:.2g} [{best.improvement[1]:.2g}, {best.improvement[2]:.2g}], "
        "no significant gap left).",
        ({best.name: best.value},),
    )


def _spread_verdict(good: Sequence[HeldOut], top_obs: str, region: str) -> Verdict:
    """A random effect named by its held-out spread gain, or ambiguous between two."""
    if len(good) > 1:
        a, b = good[0], good[1]
        return Verdict(
            "ambiguous",
            {a.name: a.value, b.name: b.value},
            top_obs,
            region,
            f"Ambiguous between {a.name} = {a.value:.3g} and {b.name} = {b.value:.3g}: "
            "each matches the data's spread out of sample and leaves no significant gap.",
            ({a.name: a.value}, {b.name: b.value}),
        )
    h = good[0]
    t = h.spread
    assert t is not None
    return Verdict(
        "named",
        {h.name: h.value},
        top_obs,
        region,
        f"{h.name} = {h.value:.3g} explains the gap as a spread (held-out mean dispersion "
        f"score {t.base_mean:.2f} against the baseline, {t.effect_mean:.2f} with the effect; "
        f"p_Holm {h.spread_p_holm:.2g}; no significant gap nor dispersion left).",
        ({h.name: h.value},),
    )


def _none_of(declared: Sequence[str]) -> str:
    """'no effect of the library' (and, when declared, 'nor the declared candidate X')."""
    if not declared:
        return "no effect of the library"
    many = "candidates" if len(declared) > 1 else "candidate"
    return f"no effect of the library nor the declared {many} {', '.join(declared)}"


def _values_text(values: Mapping[str, float]) -> str:
    return " + ".join(f"{n} = {v:.3g}" for n, v in values.items())


def _mixed_verdict(
    lone: Sequence[HeldOut],
    good: Sequence[SetHeldOut],
    top_obs: str,
    region: str,
    show: Callable[[Mapping[str, float]], str] = _values_text,
) -> Verdict:
    """Ambiguous between single effects and sets of effects that each explain the gap."""
    alts = tuple({h.name: h.value} for h in lone) + tuple(dict(st.values) for st in good)
    union: dict[str, float] = {}
    for a in alts:
        union.update(a)
    parts = [show(a) if len(a) == 1 else f"({show(a)})" for a in alts]
    return Verdict(
        "ambiguous",
        union,
        top_obs,
        region,
        f"Ambiguous between {' and '.join(parts)}: with each, no significant gap is left "
        "(one effect alone or a set of two; a measurement that separates them decides).",
        alts,
    )


def _set_verdict(
    good: Sequence[SetHeldOut],
    top_obs: str,
    region: str,
    show: Callable[[Mapping[str, float]], str] = _values_text,
) -> Verdict:
    """Named set, or ambiguous between sets that each explain the gap."""
    best = good[0]
    if len(good) > 1:
        alts = tuple(dict(st.values) for st in good)
        union: dict[str, float] = {}
        for a in alts:
            union.update(a)
        return Verdict(
            "ambiguous",
            union,
            top_obs,
            region,
            "Ambiguous between "
            + " and ".join(f"({show(a)})" for a in alts)
            + ": with either set, no significant gap is left.",
            alts,
        )
    gains = ", ".join(f"{n} {best.gains[n][0]:.2g}" for n in best.values)
    return Verdict(
        "named",
        dict(best.values),
        top_obs,
        region,
        f"{show(best.values)} together explain the gap: each member's own held-out "
        f"contribution is significant ({gains}) and no significant gap is left.",
        (dict(best.values),),
    )
