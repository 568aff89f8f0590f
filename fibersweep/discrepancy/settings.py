"""Settings of the discrepancy workflow and how a simulation budget is split.

:class:`DiscrepancySettings` holds the knobs; :func:`plan_budget` turns a
budget of simulations into a :class:`Plan` (copies per fiber, fit steps,
refits) for a given number of measured fibers and candidates.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from fibersweep.discrepancy.candidates import LIBRARY, Candidate, get_candidates
from fibersweep.discrepancy.copies import NoiseModel
from fibersweep.errors import InputError

__all__ = [
    "DiscrepancySettings",
    "Plan",
    "plan_budget",
    "INTERVAL_EVALS",
    "MODEL_COST",
    "PAIR_FIRSTS",
    "TIE_COSINE",
]

#: Most evaluations a searched pooled refit adds after its search to read its 95 %
#: interval's ends (:func:`.fit.fit_effect`, ``close_interval``): the range end when
#: the interval is open, then its two ends.
INTERVAL_EVALS = 3

#: Significant single effects, each leaving a gap, that forward selection adds
#: partners to (:func:`.stages.pairs`), best held-out improvement first. The
#: ``pairs`` of a plan are shared out among them in turn, so the cost is the same
#: as with one. Two: the single effect that helps most out of sample may be a
#: look-alike of the pair's true first member, barely ahead of it.
PAIR_FIRSTS = 2

#: Time of a run of each fiber integrator relative to a rigid run, for the plan's
#: estimate of a declared candidate that switches the model (:meth:`Plan.runs_of`).
#: ros2: 1.31, measured on configs/quick.yaml, 12 starts of its sweep box,
#: E = 5.6e5 Pa (the probe of fiber.young_modulus=1e4..3e7) against rigid, one worker,
#: two rounds (scripts/benchmarks/bench_candidate_cost.py). bdf2 (fixed step): 3, an
#: upper estimate, not measured (``--model bead-spring`` of the same script measures
#: it). ros34pw2 is taken as ros2's (one LU per step; more stages, larger steps).
MODEL_COST = {"midpoint": 1.0, "bdf2": 3.0, "ros2": 1.3, "ros34pw2": 1.3}


def switch_cost(switch: tuple[tuple[str, object], ...]) -> tuple[str, float]:
    """The model a candidate's switch runs (with its integrator) and its run's cost.

    Parameters
    ----------
    switch : tuple of (key, value)
        Settings a candidate sets (``fiber.model``, ``fiber.integrator``).

    Returns
    -------
    (str, float)
        ``"model/integrator"`` (``""`` when the switch keeps the config's model) and
        the time of one of its runs relative to a rigid run (:data:`MODEL_COST`).
    """
    from fibersweep.config.fiber import FiberSettings

    sw = dict(switch)
    if "fiber.model" not in sw:
        return "", 1.0
    st = FiberSettings.model_validate(
        {"model": sw["fiber.model"], **({"integrator": sw["fiber.integrator"]}
                                        if "fiber.integrator" in sw else {})}
    )  # fmt: skip
    return f"{st.model}/{st.integrator}", MODEL_COST.get(st.integrator, 1.0)

#: Largest shortfall of a signature's cosine below the best one's for the effect to
#: be fitted beyond the ``candidates`` best (``DiscrepancySettings.tied`` more at
#: most; :func:`.signatures.choose_candidates`). The four slowing effects
#: (friction, pillar_hydro, off_midplane, inlet_speed) match a slowing gap within
#: 0.1-0.2 of each other, in an order that the noise of a hundred fibers sets, and
#: an effect that is not fitted is never named.
TIE_COSINE = 0.2


@dataclass(frozen=True)
class DiscrepancySettings:
    """Knobs of the workflow.

    Attributes
    ----------
    copies : int
        Jittered baseline copies per fiber (the noise floor); also the copies
        per held-out evaluation. 8 by default: against fewer copies the
        per-fiber improvement of a spread effect (start noise) is too noisy to
        be confirmed out of sample.
    fit_copies : int
        Copies per fiber per fit evaluation.
    random_fit_copies, random_copies : int or None
        The same two counts for an effect that draws random numbers per run
        (``Candidate.random``: start noise, Brownian motion), whose copies carry
        Monte Carlo noise of their own: with the usual fit copies a half is
        often fitted to 0, which leaves its fibers unimproved, and with the
        usual held-out copies that noise dominates the per-fiber improvement.
        Only for the candidate whose signature matches the gap best (see
        :class:`Plan`). None: ``copies`` and 2 x ``copies``.
    candidates : int
        Effects fitted (the best-matching signatures).
    tied : int
        Most effects fitted beyond ``candidates`` whose signature matches the gap
        within ``TIE_COSINE`` of the best (0: none).
    fit_evals : int
        Simulated evaluations per 1D fit.
    refits : int
        Significant candidates refitted on all fibers for the adequacy check.
    pairs : int
        Pairs tried by forward selection (0: none), shared out in turn among the
        ``PAIR_FIRSTS`` best significant single effects that leave a gap.
    power_fibers : int
        Fibers simulated by the power analysis when the verdict is "no significant
        gap" or "unexplained" (:mod:`.power`; 0: none).
    next_copies : int
        Copies per hypothesis and start of what-to-measure-next
        (:mod:`.next_measure`; 0: none), run when the verdict is ambiguous or a
        fit is weakly identified.
    settle_copies : int
        Copies per hypothesis and follow-up fiber when follow-up fibers test
        the verdict's two hypotheses (:mod:`.settle`): a third for the
        hypotheses' means, the rest for the test's null distributions.
    alpha : float
        Family-wise error rate of every test.
    budget : int or None
        Most simulations in total; None = what the plan needs.
    seed : int
    workers : int
    executor : str
        Where the simulations run: 'local' (process pool) or 'dask'.
    scheduler : str or None
        Dask scheduler address (dask only; None starts a local cluster).
    effects : tuple of str or None
        Library subset to consider (None = all).
    declared : tuple of Candidate
        Candidates from any setting (:mod:`.declared`), considered besides the
        library's; a name that is also a library effect is refused.
    noise : NoiseModel
    n_perm : int
        Permutations per gap test.
    """

    copies: int = 8
    fit_copies: int = 2
    random_fit_copies: int | None = None
    random_copies: int | None = None
    candidates: int = 3
    tied: int = 2
    fit_evals: int = 5
    refits: int = 2
    pairs: int = 3
    power_fibers: int = 40
    next_copies: int = 2
    settle_copies: int = 24
    alpha: float = 0.05
    budget: int | None = None
    seed: int = 0
    workers: int = 2
    executor: str = "local"
    scheduler: str | None = None
    effects: tuple[str, ...] | None = None
    declared: tuple[Candidate, ...] = ()
    noise: NoiseModel = field(default_factory=NoiseModel)
    n_perm: int = 4999

    @property
    def n_random_fit_copies(self) -> int:
        """``random_fit_copies`` with its default resolved."""
        if self.random_fit_copies is not None:
            return self.random_fit_copies
        return max(self.fit_copies, self.copies)

    @property
    def n_random_copies(self) -> int:
        """``random_copies`` with its default resolved."""
        return self.random_copies if self.random_copies is not None else 2 * self.copies

    def __post_init__(self) -> None:
        checks = {
            "copies": self.copies >= 2,
            "fit_copies": self.fit_copies >= 2,  # the fair scores need two members
            # a fit's baseline is the first copies of the noise floor
            "random_fit_copies": self.fit_copies <= self.n_random_fit_copies <= self.copies,
            "random_copies": self.n_random_copies >= self.copies,
            "candidates": self.candidates >= 1,
            "tied": self.tied >= 0,
            "fit_evals": self.fit_evals >= 1,
            "refits": self.refits >= 1,
            "pairs": self.pairs >= 0,
            "power_fibers": self.power_fibers == 0 or self.power_fibers >= 8,
            "next_copies": self.next_copies in (0,) or self.next_copies >= 2,
            "settle_copies": self.settle_copies >= 6,
            "alpha": 0.0 < self.alpha < 0.5,
            "workers": self.workers >= 1,
        }
        for name, ok in checks.items():
            if not ok:
                raise InputError(f"discrepancy.{name}: invalid value {getattr(self, name)!r}")
        if self.budget is not None and self.budget < 1:
            raise InputError(f"discrepancy.budget: must be >= 1, got {self.budget}")
        for c in self.declared:
            if c.is_effect or c.name in LIBRARY:
                raise InputError(
                    f"discrepancy.candidates: {c.name} is a library effect; "
                    f"consider it with --effect {c.name}"
                )

    def candidates_of(self) -> list[Candidate]:
        """The candidates considered: the library's (``effects``), then the declared ones."""
        return [*get_candidates(self.effects), *self.declared]


@dataclass(frozen=True)
class Plan:
    """How many simulations each step may use.

    ``pair_rounds``: coordinate-descent rounds of a pair's joint fit
    (:func:`.pairs.joint_fit`). ``random``: 1 when the library holds an
    effect that draws random numbers (``Candidate.random``). Such an effect
    gets ``random_fit_copies`` / ``random_copies`` instead of ``fit_copies`` /
    ``copies`` in its single fits, held-out scores and refit when its
    signature matches the gap best (the *lead* candidate). As a side candidate
    it keeps the usual copies: Brownian runs are the costliest of the library,
    and the extra copies for a side candidate that matches the gap poorly
    would cost several times the whole analysis. ``tied``: most effects fitted
    beyond ``candidates`` when their signatures tie with the best
    (``DiscrepancySettings.tied``); the costs count them all (``fitted``).
    """

    copies: int
    fit_copies: int
    candidates: int
    fit_evals: int
    probes: int
    refits: int = 2
    pairs: int = 0
    pair_rounds: int = 2
    random: int = 0
    random_fit_copies: int = 2
    random_copies: int = 8
    tied: int = 0

    @property
    def fitted(self) -> int:
        """Most effects fitted singly: ``candidates`` + ``tied``."""
        return self.candidates + self.tied

    def fit_copies_of(self, cand: Candidate, lead: bool) -> int:
        """Copies per fiber per fit evaluation of ``cand`` (``lead``: best signature)."""
        return self.random_fit_copies if cand.random and lead else self.fit_copies

    def copies_of(self, cand: Candidate, lead: bool) -> int:
        """Copies per fiber of ``cand``'s held-out scores (``lead``: best signature)."""
        return self.random_copies if cand.random and lead else self.copies

    @property
    def refit_evals(self) -> int:
        """Brent steps of a pooled refit: two fewer than a half's fit.

        The refit starts from the two halves' values and searches a narrowed
        interval around them: the same number of evaluated values as a half's fit.
        At a half's value the fibers it scores hold their cross-fitted copies; the
        other half's fibers are simulated (a half's value is the score test's zero,
        in general not a point its fit simulated: :mod:`.fit`), so the two
        starting values cost one evaluation on all fibers (:meth:`cost`).
        """
        return max(1, self.fit_evals - 2)

    @property
    def _closing(self) -> int:
        """Evaluations on all fibers a searched refit may add for its interval's ends."""
        return 0 if self.refit_evals < 2 else INTERVAL_EVALS

    def cost(self, n: int) -> dict[str, int]:
        """Most runs per step for n fibers (two folds of n/2 for the fits)."""
        half = (n + 1) // 2
        return {
            "baseline": n * self.copies,
            "probes": self.probes * half,
            # + 1: the side check of a signed effect (fit.fit_effect)
            "fits": 2 * self.fitted * (self.fit_evals + 1) * self.fit_copies * half,
            "heldout": self.fitted * self.copies * n,
            # + 1: the halves' values on the fibers their cross-fitted copies did not cover
            # + the interval's ends (fit.fit_effect, close_interval)
            "refits": self.refits * n * (
                (self.refit_evals + 1 + self._closing) * self.fit_copies + self.copies
            ),
            # per pair: joint fits on both folds, pair_rounds 1D fits each (+1: side
            # check; + the other member alone), cross-fitted copies, final copies
            "pairs": self.pairs
            * (
                2 * self.pair_rounds * (self.fit_evals + 2) * self.fit_copies * half
                + 3 * self.copies * n  # + the partner alone when it had no single fit
                # each member refitted on all fibers (pairs.pair_refits): the other
                # member alone (its value 0), both folds' values, the Brent steps
                + 2 * (1 + 2 + self.refit_evals + self._closing) * self.fit_copies * n
            ),
            # the extra copies of a random lead candidate's fits, held-out scores and refit
            "random": min(self.random, 1)
            * (
                2 * (self.fit_evals + 1) * (self.random_fit_copies - self.fit_copies) * half
                + (self.random_copies - self.copies) * n
                + (self.refit_evals + 1 + self._closing)
                * (self.random_fit_copies - self.fit_copies)
                * n
            ),
        }

    def total(self, n: int) -> int:
        return sum(self.cost(n).values())

    def runs_of(self, n: int, cand: Candidate) -> int:
        """Most runs one candidate takes for n fibers: its probes, both halves' fits,
        held-out copies and pooled refit (pairs not counted).

        What a costly candidate (a flexible model, :data:`MODEL_COST`) adds to the
        time of an analysis is about ``(MODEL_COST - 1) * runs_of``.
        """
        half = (n + 1) // 2
        return (
            len(cand.probes) * half
            + 2 * (self.fit_evals + 1) * self.fit_copies * half
            + self.copies * n
            + n * ((self.refit_evals + 1 + self._closing) * self.fit_copies + self.copies)
        )


def plan_budget(n: int, s: DiscrepancySettings, candidates: list[Candidate]) -> Plan:
    """The most thorough plan within the budget (shrinks fits first, the noise floor last).

    Raises
    ------
    InputError
        If even the smallest plan (2 copies, one candidate, one evaluation) does not fit.
    """
    probes = sum(len(c.probes) for c in candidates)
    n_cand = min(s.candidates, len(candidates))
    plan = Plan(
        s.copies, s.fit_copies, n_cand, s.fit_evals, probes, s.refits,
        # partners come from the whole library (ranked by the gap each first leaves)
        min(s.pairs, len(candidates) * (len(candidates) - 1) // 2),
        random=int(any(c.random for c in candidates)),
        random_fit_copies=s.n_random_fit_copies, random_copies=s.n_random_copies,
        tied=min(s.tied, len(candidates) - n_cand),
    )  # fmt: skip
    if s.budget is None:
        return plan
    shrink = [
        ("tied", 0),
        ("random_copies", s.copies),
        ("random_fit_copies", s.fit_copies),
        ("pairs", 1),
        ("refits", 1),
        ("pairs", 0),
        ("fit_evals", 3),
        ("copies", 6),
        ("candidates", 2),
        ("copies", 4),
        ("fit_evals", 2),
        ("copies", 3),
        ("candidates", 1),
        ("fit_evals", 1),
        ("copies", 2),
    ]
    for attr, v in shrink:
        if plan.total(n) <= s.budget:
            return plan
        if getattr(plan, attr) > v:
            plan = replace(plan, **{attr: v})
            if attr == "copies":  # random effects had already come down to the copies
                plan = replace(plan, random_copies=v)
    if plan.total(n) <= s.budget:
        return plan
    raise InputError(
        f"budget: {s.budget} simulations are too few for {n} fibers; the smallest plan "
        f"needs {plan.total(n)} ({plan.cost(n)})"
    )
