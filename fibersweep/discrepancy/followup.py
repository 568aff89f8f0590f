"""After the verdict: the power analysis and what to measure next, when they apply.

- verdict "no significant gap" or "unexplained": :func:`power.analyse_power` on
  the measured starts (which effects could be present below which magnitudes,
  how many fibers would name the leading candidate);
- verdict ambiguous, two significant candidates left unexplained, or a fit
  whose halves disagree by more than a factor 2: :func:`nextmeasure.discriminate`
  between the two hypotheses.

Both run within what the budget leaves; otherwise the report says why not.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from fibersweep.discrepancy.copies import CopyMaker
from fibersweep.discrepancy.decide import HeldOut, Verdict
from fibersweep.discrepancy.library import Candidate
from fibersweep.discrepancy.simulate import Simulator

__all__ = ["next_hypotheses", "followup", "POWER_BOOT"]

#: Bootstrap resamples of the simulated starts behind each detection limit's interval
#: (no new runs; about a minute of scoring with all seven effects on 40 starts).
POWER_BOOT = 30


def _weak(values: list[float]) -> bool:
    """The two folds' fits disagree by more than a factor 2 (or in sign)."""
    a, b = values
    if a == b:
        return False
    if a * b <= 0:
        return True
    return max(abs(a), abs(b)) > 2 * min(abs(a), abs(b))


def next_hypotheses(
    verdict: Verdict, heldout: list[HeldOut], fold_values: dict[str, list[float]]
) -> tuple[dict[str, float], dict[str, float], str] | None:
    """The two hypotheses what-to-measure-next should separate, and why (None: nothing).

    Ambiguous: its first two alternatives. Unexplained with two significant
    candidates: those two. Otherwise a weakly identified fit (the named or the
    best candidate's two fold values differ by more than a factor 2): the
    effect at each fold value. Otherwise, unexplained: the model as it is
    against the candidate that helped most out of sample (at its value, or the
    mean of its nonzero fold values), so the report says at which starts, and
    with how many fibers, that candidate would be confirmed or ruled out.
    """
    if verdict.kind == "ambiguous" and len(verdict.alternatives) >= 2:
        a, b = verdict.alternatives[:2]
        return dict(a), dict(b), "the verdict is ambiguous"
    sig = sorted((h for h in heldout if h.significant), key=lambda h: -h.improvement[0])
    if verdict.kind == "unexplained" and len(sig) >= 2:
        return (
            {sig[0].name: sig[0].value},
            {sig[1].name: sig[1].value},
            ("two candidates each improve the fit significantly"),
        )
    name = next(iter(verdict.effects), None) if verdict.kind == "named" else None
    if name is None and heldout:
        name = max(heldout, key=lambda h: h.improvement[0]).name
    if name is not None and name in fold_values and _weak(fold_values[name]):
        v0, v1 = fold_values[name]
        return {name: v0}, {name: v1}, f"the two halves fit {name} = {v0:.3g} and {v1:.3g}"
    if verdict.kind == "unexplained" and heldout:
        # the doubt of an unexplained gap: is the candidate that helped most there or
        # not? The starts where its prediction departs most from the model as it is
        # test it fastest (issue 30: which starts, how many more fibers)
        best = max(heldout, key=lambda h: h.improvement[0])
        v = best.value if best.value != 0.0 else _mean_nonzero(fold_values.get(best.name, []))
        if v != 0.0:
            return (
                {},
                {best.name: v},
                (
                    f"the gap is unexplained; {best.name} = {v:.3g} helped most out of sample "
                    f"(p Holm {best.p_holm:.2g}): these starts test it against the model as it is"
                ),
            )
    return None


def _mean_nonzero(values: list[float]) -> float:
    """Mean of the nonzero fold values (0 when there are none)."""
    nz = [v for v in values if v != 0.0]
    return float(np.mean(nz)) if nz else 0.0


def followup(
    verdict: Verdict,
    heldout: list[HeldOut],
    fold_values: dict[str, list[float]],
    candidates: Sequence[Candidate],
    maker: CopyMaker,
    sim: Simulator,
    plan: Any,
    s: Any,
    obs: tuple[str, ...],
    rng: np.random.Generator,
) -> dict[str, Any]:
    """Power analysis and what-to-measure-next, when they apply and the budget allows.

    Parameters
    ----------
    plan : workflow.Plan
        Its ``copies`` (the ensemble the power analysis scales to).
    s : workflow.DiscrepancySettings
        ``power_fibers``, ``next_copies``, ``noise``, ``seed``, ``alpha``.

    Returns
    -------
    dict
        ``power`` (PowerResult), ``next`` (Discrimination) and ``next_reason``,
        or ``power_skipped`` / ``next_skipped`` with the reason.
    """
    from fibersweep.discrepancy.nextmeasure import discriminate, start_grid
    from fibersweep.discrepancy.power import analyse_power

    out: dict[str, Any] = {}
    if s.power_fibers and verdict.kind in ("no significant gap", "unexplained"):
        n_sim = min(s.power_fibers, maker.n)
        cost = 3 * n_sim * 2 * sum(len(c.probes) for c in candidates)
        if cost <= sim.remaining:
            out["power"] = analyse_power(
                maker, candidates, maker.n, obs, rng, n_sim=n_sim,
                workflow_copies=plan.copies, alpha=s.alpha, n_boot=POWER_BOOT,
            )  # fmt: skip
        else:
            out["power_skipped"] = f"the budget leaves {sim.remaining} runs, it needs {cost}"
    hyp = next_hypotheses(verdict, heldout, fold_values) if s.next_copies else None
    if hyp is not None:
        a, b, why = hyp
        grid = start_grid(maker.starts)
        cost = 2 * s.next_copies * (len(grid) + maker.n)
        if cost <= sim.remaining:
            out["next"] = discriminate(
                sim, s.noise, (a, b), maker.starts, obs, seed=s.seed,
                copies=s.next_copies, grid=grid, alpha=s.alpha,
            )  # fmt: skip
            out["next_reason"] = why
        else:
            out["next_skipped"] = f"the budget leaves {sim.remaining} runs, it needs {cost}"
    return out
