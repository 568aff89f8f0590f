"""Settling the verdict's two-way question on fibers measured for it.

When the verdict leaves two hypotheses (ambiguous between A and B, or the other
cases of :func:`.followup.next_hypotheses`), what-to-measure-next proposes the
starts where they differ most. Fibers measured afterwards (``--followup``), used
by no fit, test the two hypotheses against each other directly; the analysis of
the first fibers is left as it was.

Both hypotheses are simulated at the follow-up fibers' starts (common random
numbers between them; reference and null copies independent), and the fibers
are put to the test of :mod:`.discriminant` (the log-likelihood ratio of A over
B against its distribution under each hypothesis; outcome A, B, neither or
undecided). The test looks along the difference of the two predictions only,
so the winner is then checked on the follow-up fibers as every fitted effect is
on the first ones (:func:`.gap.assess_gap` against its copies): a significant
gap left, and it is not named.

Why not paired comparisons on the first fibers: there each hypothesis was
fitted to the same fibers, and common random numbers favour whichever copies
happen to look like them (:mod:`.decide`); here the hypotheses are fixed
before the follow-up fibers are seen.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from fibersweep.discrepancy.components import copy_values, standardised_values
from fibersweep.discrepancy.copies import CopyMaker, NoiseModel
from fibersweep.discrepancy.decide import Verdict
from fibersweep.discrepancy.discriminant import SettleTest, settle_test
from fibersweep.discrepancy.gap import GapResult, assess_gap, value_matrices
from fibersweep.discrepancy.simulate import Simulator

__all__ = [
    "Settlement",
    "hypothesis_copies",
    "settle",
    "settled_verdict",
]


def hypothesis_copies(
    maker: CopyMaker,
    hypotheses: tuple[Mapping[str, float], Mapping[str, float]],
    copies: int,
    observables: Sequence[str],
    tag: str,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Both hypotheses' copies at the maker's starts (common random numbers).

    Returns
    -------
    values_a, values_b : ndarray, shape (copies, n, c)
    ok_a, ok_b : ndarray of bool, shape (copies, n)
        As :func:`.components.copy_values`.
    """
    (va, oka), (vb, okb) = (
        copy_values(maker.copies(range(copies), dict(h), desc=f"{tag}: {t}"), observables)
        for h, t in zip(hypotheses, "AB", strict=True)
    )
    return va, vb, oka, okb


@dataclass(frozen=True)
class Settlement:
    """The follow-up fibers' answer to the verdict's two-way question.

    Attributes
    ----------
    labels : (str, str)
        The hypotheses, e.g. ('flow.dx = 5 µm', 'off_midplane = 0.068').
    hypotheses : (dict, dict)
        Their effects (name -> value in the fit's scale).
    reason : str
        Why these two (as what-to-measure-next says).
    n : int
        Follow-up fibers.
    observables : tuple of str
        Observables scored (those the follow-up table has).
    test : SettleTest
    simulations : int
    adequacy : GapResult or None
        The winner (outcome A or B) checked on the follow-up fibers against
        all its copies (:func:`.gap.assess_gap`); None otherwise.
    """

    labels: tuple[str, str]
    hypotheses: tuple[dict[str, float], dict[str, float]]
    reason: str
    n: int
    observables: tuple[str, ...]
    test: SettleTest
    simulations: int
    adequacy: GapResult | None = None

    @property
    def outcome(self) -> str:
        return self.test.outcome

    @property
    def settled(self) -> bool:
        """One hypothesis rejected, the other not, and no significant gap left by it."""
        return self.outcome in ("A", "B") and self.adequacy is not None and not self.adequacy.any

    def text(self) -> str:
        """One sentence: what the follow-up fibers say."""
        a, b = self.labels
        pa, pb = self.test.p_values
        tail = f"(p {pa:.2g} for {a}, p {pb:.2g} for {b})"
        if self.outcome in ("A", "B"):
            win, lose = (a, b) if self.outcome == "A" else (b, a)
            if self.settled:
                return (
                    f"the {self.n} follow-up fibers reject {lose} and are consistent with "
                    f"{win} {tail}"
                )
            left = ", ".join(self.adequacy.flagged) if self.adequacy is not None else "?"
            return (
                f"the {self.n} follow-up fibers reject {lose}; {win} is closer to them but "
                f"leaves a significant gap in {left} {tail}"
            )
        if self.outcome == "neither":
            return f"the {self.n} follow-up fibers lie between {a} and {b}, rejecting both {tail}"
        need = self.test.fibers_to_settle
        more = f"; about {need} such fibers would separate them" if need else ""
        return f"the {self.n} follow-up fibers do not separate {a} from {b} {tail}{more}"


def settle(
    sim: Simulator,
    noise: NoiseModel,
    hypotheses: tuple[Mapping[str, float], Mapping[str, float]],
    labels: tuple[str, str],
    reason: str,
    table: pd.DataFrame,
    starts: np.ndarray,
    observables: Sequence[str],
    rng: np.random.Generator,
    seed: int = 0,
    copies: int = 24,
    alpha: float = 0.05,
    n_perm: int = 4999,
) -> Settlement:
    """Simulate both hypotheses at the follow-up fibers' starts and test them.

    Parameters
    ----------
    sim : Simulator
    noise : NoiseModel
        Measurement model of the copies (start and outcome noise).
    hypotheses : (mapping, mapping)
        The two sets of effects (fixed: fitted on the first fibers).
    labels, reason : as :class:`Settlement`
    table : DataFrame
        The follow-up fibers (observed columns by observable name).
    starts : ndarray, shape (n, 3)
        Their starts: theta0 [deg], y0 [/h_obs], length [/l_obs].
    observables : sequence of str
        Observables to score (present in ``table``).
    copies : int
        Copies per hypothesis and fiber: a third for the reference means, the
        rest for the null distributions (>= 6).
    rng : Generator
        For the test's null draws and the winner's permutations.
    seed : int
        Seeds the copies (the same seed gives the same copies).
    alpha : float
        Level of each one-sided test and of the winner's gap test.
    n_perm : int
        Permutations of the winner's gap test.

    Returns
    -------
    Settlement
    """
    if copies < 6:
        raise ValueError(f"copies must be >= 6, got {copies}")
    k_ref = copies // 3
    used0 = sim.used
    # common random numbers between A and B; reference and null copies are independent
    maker = CopyMaker(starts, noise, seed + 15485863, sim)
    cps = [
        maker.copies(range(copies), dict(h), desc=f"follow-up: {tag}")
        for h, tag in zip(hypotheses, "AB", strict=True)
    ]
    (va, oka), (vb, okb) = (copy_values(c, observables) for c in cps)
    x = standardised_values([table], observables)[0]
    test = settle_test(x, va[:k_ref], vb[:k_ref], va[k_ref:], vb[k_ref:], rng, alpha,
                       ok=(oka[:k_ref], okb[:k_ref], oka[k_ref:], okb[k_ref:]))  # fmt: skip
    adequacy = None
    if test.outcome in ("A", "B"):
        win = cps[0 if test.outcome == "A" else 1]
        adequacy = assess_gap(value_matrices(table, win, observables), rng, alpha=alpha,
                              n_perm=n_perm)  # fmt: skip
    return Settlement(
        labels=labels,
        hypotheses=(dict(hypotheses[0]), dict(hypotheses[1])),
        reason=reason,
        n=len(starts),
        observables=tuple(observables),
        test=test,
        simulations=sim.used - used0,
        adequacy=adequacy,
    )


def settled_verdict(verdict: Verdict, st: Settlement) -> Verdict:
    """The verdict after the follow-up fibers.

    An ambiguous verdict between exactly these two alternatives becomes "named"
    when the follow-up fibers reject one and the other leaves no significant gap
    on them (:attr:`Settlement.settled`); any other verdict
    (and any other outcome) stands, and the report gives the settlement beside it.
    """
    alts = [dict(a) for a in verdict.alternatives]
    if verdict.kind != "ambiguous" or not st.settled or alts != list(st.hypotheses):
        return verdict
    win = st.hypotheses[0 if st.outcome == "A" else 1]
    label = st.labels[0 if st.outcome == "A" else 1]
    text = f"{label}: {st.text()}. On the first fibers alone: {verdict.text}"
    return Verdict("named", dict(win), verdict.observable, verdict.region, text, (dict(win),))
