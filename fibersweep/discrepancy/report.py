"""Write the discrepancy report: Markdown, figures, JSON summary and the updated config(s).

The report formats and writes what the workflow computed (a
:class:`~.result.DiscrepancyResult`: every test and count it shows, the
dispersion tests and the power analysis's fibers included); it computes none.

Files written into the output directory (each atomically):

- ``summary.json``: verdict, gaps, ranking, fits (per half), held-out before/after,
  sets of effects tried, power analysis, what to measure next, the follow-up
  fibers' test; for scripts;
- ``report.md``: the same for people, in two layers: a first page in words
  (:mod:`.report_first_page`), then the statistical detail with a glossary and
  the figures (:mod:`.report_text`, :mod:`.report_followup`) and the advice
  (:mod:`.advice`); every stage skipped for the budget is said;
- figures (:mod:`.report_figures`): ``phase_before_after.png``,
  ``residual_map.png``, ``gap_before_after.png``, ``next_measure.png``;
- ``updated_config.yaml`` (named effect or set) or ``updated_config.<set>.yaml``
  (each alternative of an ambiguous verdict): the input config with every
  effect of the set added to ``fiber.effects``.

One scale for the gap everywhere: the *excess score* of an observable (how
much worse the measurement scores than a model copy) divided by the spread of
the copies' own scores, "copy-spread units" (0: as good as the model's own
copies; 1: one spread worse per fiber).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from fibersweep.atomic import atomic_write
from fibersweep.config.loading import apply_overrides
from fibersweep.discrepancy.advice import advice_lines, cannot_exclude
from fibersweep.discrepancy.candidates import Candidate
from fibersweep.discrepancy.detection import limit_in_unit
from fibersweep.discrepancy.gap import GAP_UNIT, GapResult
from fibersweep.discrepancy.observables import OBSERVABLES, geometry_of, scored
from fibersweep.discrepancy.report_figures import figures
from fibersweep.discrepancy.report_text import markdown
from fibersweep.discrepancy.result import DiscrepancyResult

__all__ = ["GAP_UNIT", "summary", "write_report"]

#: Stages whose failed runs are failures of the analysis itself (the baseline model);
#: runs under a probed or fitted effect that fail are outcomes of that effect.
ANALYSIS_STAGES = ("baseline",)


def _clean(x: Any) -> Any:
    """JSON-safe: NaN/inf -> None, numpy scalars -> Python."""
    if isinstance(x, dict):
        return {str(k): _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def _gap_dict(g: GapResult | None, weights: dict[str, float]) -> dict[str, Any]:
    if g is None:
        return {}
    biased = set(g.biased)
    out = {}
    for name, o in g.gaps.items():
        w = weights.get(name, 0.0)
        out[name] = {
            "statistic": o.test.statistic,
            "noise_floor": o.test.null_mean,
            "noise_sd": o.test.null_sd,
            "z": o.test.z,
            "p": o.test.p_value,
            "p_holm": o.p_holm,
            "significant": o.significant,
            "excess": {"mean": o.excess[0], "lo95": o.excess[1], "hi95": o.excess[2]},
            # the same in copy-spread units (the one scale of tables and figures)
            "gap": {"mean": o.excess[0] * w, "lo95": o.excess[1] * w, "hi95": o.excess[2] * w},
            "n": o.test.n,
            "bias_z": list(o.bias_z),
            "bias_p": list(o.bias_p),
            "bias_p_holm": list(o.bias_p_holm),
            "signed_p_holm": min(o.bias_p_holm) if o.bias_p_holm else None,
            "systematic": name in biased,
        }
    return out


def _removed(before: dict[str, Any], after: dict[str, Any]) -> dict[str, float | None]:
    """Share of each observable's gap an effect removed (1 - after/before), None if no gap."""
    out: dict[str, float | None] = {}
    for name, b in before.items():
        a = after.get(name)
        bm = b["gap"]["mean"]
        am = a["gap"]["mean"] if a else None
        ok = am is not None and bm is not None and bm > 0
        out[name] = (1.0 - am / bm) if ok else None
    return out


def _power_dict(res: DiscrepancyResult) -> dict[str, Any] | None:
    """The power analysis the workflow ran, with the fibers it says would do
    (:class:`.followup.PowerFibers`); None when it did not run."""
    pw = res.extra.get("power")
    if pw is None:
        return None
    fibers = res.extra["power_fibers"]
    effects = []
    declared = {c.name: c for c in res.settings.declared}
    cis = fibers.realistic_ci or (None,) * len(pw.effects)
    for e, (real, need), need_ci in zip(pw.effects, fibers.realistic, cis, strict=True):
        unit = limit_in_unit(declared[e.name], e) if e.name in declared else {}
        effects.append(
            {
                "effect": e.name,
                "direction": "+" if e.probe > 0 else "-",
                "probe": e.probe,
                "gamma": e.gamma,
                "read_at": e.read_at,
                "limit": e.limit,
                "limit_ci": list(e.limit_ci) if e.limit_ci is not None else None,
                "dispersion_limit": e.dispersion_limit,
                "realistic": real,
                "fibers_for_realistic": need,
                "fibers_for_realistic_ci": need_ci,
                **unit,
            }
        )
    lead = None
    if (h := fibers.leading) is not None:
        lead = {
            "effect": h.name,
            "value": h.value,
            **_in_unit(declared.get(h.name), h.value, None),
            "fibers_to_detect": h.fibers_to_detect,
            "fibers_to_detect_ci": h.fibers_to_detect_ci,
            "fibers_to_name": h.fibers_to_name,
        }
    return {
        "n": pw.n,
        "n_simulated": pw.n_sim,
        "alpha": pw.alpha,
        "power": pw.power,
        "effects": effects,
        "lookalikes": [{"a": a, "b": b, "cosine": c} for a, b, c in pw.lookalikes],
        "leading": lead,
        "simulations": pw.simulations,
    }


def _spread_dict(h: Any) -> dict[str, Any] | None:
    """A random effect's held-out spread test (:func:`dispersion.spread_test`), or None."""
    t = h.spread
    if t is None:
        return None
    return {
        "base_mean": t.base_mean,
        "effect_mean": t.effect_mean,
        "reduction": dict(zip(("mean", "lo95", "hi95"), t.reduction, strict=True)),
        "p_over": t.p_over,
        "p_reduce": t.p_reduce,
        "p": t.p,
        "p_holm": h.spread_p_holm,
        "heldout_dispersion_p": t.calm.p_value,
        "shift_p": t.p_shift,
        "significant": h.spread_significant,
        "final_dispersion_p": None if h.final_dispersion is None else h.final_dispersion.p_value,
    }


def _dispersion_dict(res: DiscrepancyResult) -> dict[str, Any]:
    """The dispersion tests the workflow ran (:func:`.stages.dispersion`): of the data
    against the baseline copies, and against each random effect's final copies.

    Outside the Holm family of the gap: it names nothing and does not change the
    verdict; it says whether the outcomes are spread more widely than the model's.
    """
    return {
        name: {"mean_score": t.statistic, "z": t.z, "p": t.p_value, "n": t.n}
        for name, t in res.dispersion.items()
    }


def _next_dict(res: DiscrepancyResult) -> dict[str, Any] | None:
    nx = res.extra.get("next")
    if nx is None:
        return None
    return {
        "reason": res.extra.get("next_reason", ""),
        "hypotheses": list(nx.labels),
        "best": [b.__dict__ for b in nx.best],
        "fibers_needed": nx.fibers_to_settle,
        "fibers_needed_at_measured_starts": nx.fibers_to_separate_measured,
        "window": None if nx.window is None else [float(w) for w in nx.window],
        "simulations": nx.simulations,
    }


def _settle_dict(res: DiscrepancyResult) -> dict[str, Any] | None:
    st = res.extra.get("settle")
    if st is None:
        return None
    t = st.test
    first = res.extra.get("verdict_first")
    return {
        "reason": st.reason,
        "hypotheses": list(st.labels),
        "fibers": st.n,
        "observables": list(st.observables),
        "statistic": t.statistic,
        "expected": list(t.expected),
        "sd": list(t.spread),
        "p_values": list(t.p_values),
        "outcome": t.outcome,
        "settled": st.settled,
        "gap_left_by_winner": list(st.adequacy.flagged) if st.adequacy is not None else None,
        "failed_copies": t.failed,
        "fibers_needed": t.fibers_to_settle,
        "per_fiber": [float(x) for x in t.per_fiber],
        "simulations": st.simulations,
        "text": st.text(),
        "verdict_first": {"kind": first.kind, "text": first.text} if first else None,
    }


def _in_unit(cand: Candidate | None, value: float, interval: Any) -> dict[str, Any]:
    """A declared candidate's value and interval in its setting's unit ({} for an effect)."""
    if cand is None:
        return {}
    out: dict[str, Any] = {"setting": cand.show(value)}
    if interval is not None and not cand.categorical:
        lo, hi = cand.interval(interval[0], interval[1])
        out["interval95_setting"] = [lo, hi]
    return out


def _declared_dict(c: Candidate) -> dict[str, Any]:
    """What a declared candidate is: its setting, scale, range (in its unit) and switch."""
    lo, hi = c.interval(c.lo, c.hi)
    return {
        "name": c.name, "key": c.key, "scale": c.scale, "unit": c.unit,
        "range": [lo, hi], "switch": dict(c.switch), "note": c.note,
    }  # fmt: skip


#: The stages that may be skipped, by their summary key, as the report names them.
SKIPPABLE = {
    "pairs_skipped": "two effects together",
    "power_skipped": "power analysis",
    "next_skipped": "what to measure next",
    "settle_skipped": "follow-up test",
}


def _skipped(res: DiscrepancyResult) -> dict[str, str]:
    """Each stage that did not run, as the report names it, with why (budget or other)."""
    return {name: res.extra[k] for k, name in SKIPPABLE.items() if res.extra.get(k)}


def _costs(res: DiscrepancyResult) -> dict[str, int] | None:
    """The follow-ups' runs planned before the analysis (:func:`.followup.followup_costs`)."""
    c = res.extra.get("followup_costs")
    return None if c is None else {"power": c.power, "power_more": c.power_more,
                                   "next": c.next}  # fmt: skip


def summary(res: DiscrepancyResult) -> dict[str, Any]:
    """JSON-ready summary of a workflow result."""
    v = res.verdict
    w = res.weights
    before = _gap_dict(res.heldout_before, w)
    ho = []
    fold = res.extra.get("fold_values", {})
    intervals = res.extra.get("intervals", {})
    declared = {c.name: c for c in res.settings.declared}
    for h in res.heldout:
        after = _gap_dict(h.residual, w)
        ho.append(
            {
                "effect": h.name,
                "value": h.value,
                **_in_unit(declared.get(h.name), h.value, intervals.get(h.name)),
                "halves": fold.get(h.name),
                "interval95": list(intervals[h.name][:2]) if h.name in intervals else None,
                # True where the test did not reject up to the refit's search bound
                "interval95_open": list(intervals[h.name][2:]) if h.name in intervals else None,
                "improvement": dict(zip(("mean", "lo95", "hi95"), h.improvement, strict=True)),
                "p": h.p_value,
                "p_holm": h.p_holm,
                "significant": h.significant,
                "explains": h.explains,
                "gap_after": after,
                "gap_final": _gap_dict(h.final, w),
                "gap_removed": _removed(before, after),
                "spread": _spread_dict(h),
            }
        )
    sets = []
    for st in res.sets:
        after = _gap_dict(st.residual, w)
        sets.append(
            {
                "set": st.name,
                "values": st.values,
                "halves": {k: list(v) for k, v in st.fold_values.items()},
                # each member's refit on all fibers (the other at its pair value)
                "interval95": {k: list(v[:2]) for k, v in st.intervals.items()} or None,
                "interval95_open": {k: list(v[2:]) for k, v in st.intervals.items()} or None,
                "gains": {
                    k: dict(zip(("mean", "lo95", "hi95"), g, strict=True))
                    for k, g in st.gains.items()
                },
                "p": st.p_values,
                "p_holm": st.p_holm,
                "improvement": dict(zip(("mean", "lo95", "hi95"), st.improvement, strict=True)),
                "significant": st.significant(res.settings.alpha),
                "explains": st.explains(res.settings.alpha),
                "gap_after": after,
                "gap_removed": _removed(before, after),
                "gap_final": _gap_dict(st.final, w),
            }
        )
    by_stage = dict(res.failed_by_stage)
    analysis_failed = sum(by_stage.get(k, 0) for k in ANALYSIS_STAGES)
    X = res.observed
    varying = [c for c in ("theta0", "y0", "length") if float(np.ptp(X[c])) > 1e-9]
    out = {
        "verdict": {
            "kind": v.kind,
            "effects": v.effects,
            "alternatives": list(v.alternatives),
            "observable": v.observable,
            "region": v.region,
            "text": v.text,
        },
        "n_fibers": len(res.observed),
        "n_heldout": len(res.heldout_rows),
        "observables": list(res.observables),
        "observables_absent": [
            o for o in scored(geometry=geometry_of(res.observables)) if o not in res.observables
        ],
        # the unit of each observable's values and residuals ('' for a class)
        "observable_units": {o: OBSERVABLES[o].unit for o in res.observables if o in OBSERVABLES},
        "start_axes_varying": varying,
        "alpha": res.settings.alpha,
        "gap_unit": GAP_UNIT,
        "gap": _gap_dict(res.gap, w),
        "descriptive": res.descriptive,
        "region": {
            "where": res.region.describe(),
            "n": res.region.n,
            "mean_excess": res.region.mean_excess,
            "share": res.region.share,
        },
        "region_by_observable": {k: r.describe() for k, r in res.region_by_observable.items()},
        "signatures": [
            {"effect": s.name, "probe": s.probe, "cosine": s.cosine, "strength": s.strength}
            for s in res.signatures
        ],
        "fits": [
            {
                "effect": f.name,
                "value": f.value,
                "loss": f.loss,
                "loss_baseline": f.loss0,
                "evaluations": [list(e) for e in f.evaluations],
            }
            for f in res.fits
        ],
        "declared": [_declared_dict(c) for c in res.settings.declared],
        "heldout_gap_before": before,
        "heldout": ho,
        "sets": sets,
        "power": _power_dict(res),
        "dispersion": _dispersion_dict(res),
        "power_skipped": res.extra.get("power_skipped"),
        "next": _next_dict(res),
        "next_skipped": res.extra.get("next_skipped"),
        "settle": _settle_dict(res),
        "settle_skipped": res.extra.get("settle_skipped"),
        "pairs_skipped": res.extra.get("pairs_skipped"),
        "power_unread": res.extra.get("power_unread", []),
        "stages_skipped": _skipped(res),
        "followup_costs": _costs(res),
        "simulations": res.simulations,
        "simulations_planned": res.plan.cost(len(res.observed)),
        "simulations_by_stage": res.extra.get("runs_by_stage", {}),
        "failed_runs": analysis_failed,
        "failed_runs_by_stage": by_stage,
        "seconds": res.seconds,
        "settings": {
            "copies": res.plan.copies,
            "fit_copies": res.plan.fit_copies,
            "candidates": res.plan.candidates,
            "tied": res.plan.tied,
            "fit_evals": res.plan.fit_evals,
            "pairs": res.plan.pairs,
            "seed": res.settings.seed,
            "budget": res.settings.budget,
            "noise": res.settings.noise.as_dict(),
        },
    }
    clean = _clean(out)
    out["cannot_exclude"] = cannot_exclude(clean)
    out["advice"] = advice_lines(clean)
    return _clean(out)


def write_report(
    res: DiscrepancyResult, out_dir: str | Path, config_data: dict[str, Any] | None = None
) -> dict[str, Any]:
    """Write every report file into ``out_dir``; returns the JSON summary.

    Parameters
    ----------
    config_data : dict, optional
        The input config as a plain mapping (``Config.model_dump(mode='json')``);
        the updated config(s) are this with ``fiber.effects`` set.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    s = summary(res)
    v = res.verdict
    made = figures(res, out)
    configs = []
    declared = {c.name: c for c in res.settings.declared}
    if config_data is not None and v.kind in ("named", "ambiguous"):
        for alt in v.alternatives or ({k: val} for k, val in v.effects.items()):
            data = json.loads(json.dumps(config_data))
            fiber = data.setdefault("fiber", {})
            effects = {k: float(val) for k, val in alt.items() if k not in declared}
            if effects:
                fiber["effects"] = {**(fiber.get("effects") or {}), **effects}
            over = {}
            for k, val in alt.items():
                if k in declared:
                    over.update(declared[k].overrides(val))
            if over:  # a declared candidate: its setting, as a KEY=VALUE override would
                data = apply_overrides(data, {}, [f"{k}={json.dumps(x)}" for k, x in over.items()])
            tag = "+".join(alt).replace("/", "_")
            fname = "updated_config.yaml" if v.kind == "named" else f"updated_config.{tag}.yaml"
            atomic_write(out / fname, yaml.safe_dump(data, sort_keys=False))
            configs.append(fname)
    s["updated_configs"] = configs
    s["figures"] = made
    atomic_write(out / "summary.json", json.dumps(s, indent=2))
    atomic_write(out / "report.md", markdown(s, made, configs))
    return s
