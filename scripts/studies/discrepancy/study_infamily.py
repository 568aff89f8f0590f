"""The in-family check: data made by exactly a family the workflow fits, at 1x-4x its limit.

For each scenario and seed: synthesise ``--n`` fibers on the study field with the
hidden library effect(s) or a declared candidate's setting, run the whole workflow
(the defaults, power analysis and what-to-measure-next off), and classify the
verdict against the truth:

- ``named``: the verdict names exactly the hidden effect(s);
- ``detected, not named``: a gap, and the verdict is ambiguous with the truth among
  its alternatives, or names part of a hidden pair;
- ``unexplained``;
- ``wrong name``: a named effect (or, in an ambiguous verdict, an alternative none
  of whose members is hidden) that is not the truth;
- ``no gap``: not detected.

Beside the verdict it records what decides an in-family "unexplained": the
observables the fits score (those with a gap at baseline), the gap each
refitted candidate leaves at its quoted value (``final``), and the gap that the
*true* model leaves (``--truth-gap``: 8 more copies of every fiber with the
hidden effects at their true values, the same gap test). If the true model
leaves no gap where the fitted one does, the fit, not the model, is at fault.

Scenarios are ``NAME=MULT`` (a library effect at MULT times its N = 100 detection
limit, :data:`LIMITS`), ``A=MULT+B=MULT`` (a pair), or ``decl:KEY=VALUE`` (a
declared candidate's setting at VALUE, analysed with :data:`DECLARED` [KEY]
declared). One JSON per data set in ``--out`` (a study can be stopped and
continued); ``--tabulate`` prints the table.

Usage::

    python scripts/studies/discrepancy/study_infamily.py --n 100 --seeds 9701 9702 \
        --scenarios friction=2 pillar_hydro=2 inlet_speed=2 --workers 1 --out results/infamily
    python scripts/studies/discrepancy/study_infamily.py --tabulate --out results/infamily
"""

from __future__ import annotations

import json
import logging
import sys
import time
from pathlib import Path

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.copies import CopyMaker, NoiseModel
from fibersweep.discrepancy.declared import apply_values, parse_candidate
from fibersweep.discrepancy.gap import GapResult, assess_gap, value_matrices
from fibersweep.discrepancy.schema import validate_measured
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.discrepancy.synth import synthesize
from fibersweep.discrepancy.workflow import DiscrepancySettings, run_discrepancy

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from common import (  # noqa: E402
    BOX,
    REPO,
    STUDY_FLOW,
    parse_study,
    study_field,
    study_parser,
    wilson,
)

log = logging.getLogger("infamily")

#: N = 100 detection limits (80 % detection), medians of the power analysis over four
#: sets of 40 starts (docs/validation/discrepancy.md, *The power analysis*); inlet_speed
#: the mean of its two signs' 0.011 and 0.012.
LIMITS = {"friction": 0.18, "pillar_hydro": 0.18, "inlet_speed": 0.0115, "start_noise": 1.6}

#: The declared candidate each ``decl:KEY=VALUE`` scenario is analysed with.
DECLARED = {
    "fiber.contact.chi": "fiber.contact.chi=1.01..2",
    "fiber.young_modulus": "fiber.young_modulus=1e4..3e7",
}


def quick_box() -> dict[str, tuple[float, float]]:
    """configs/quick.yaml's sweep box, the one ``fibersweep synth configs/quick.yaml`` uses."""
    from fibersweep.api.common import load_config
    from fibersweep.api.compare import sweep_box

    return sweep_box(load_config(REPO / "configs" / "quick.yaml"))


CLASSES = ("named", "detected, not named", "unexplained", "wrong name", "no gap")


def parse_scenario(text: str) -> tuple[dict[str, float], dict[str, object], str]:
    """``friction=2+inlet_speed=-3`` -> hidden library effects; ``decl:KEY=V`` -> a setting.

    Returns
    -------
    effects : dict name -> value
    setting : dict key -> value (the declared setting's true value; empty for library)
    label : str
    """
    if text.startswith("decl:"):
        key, _, val = text[5:].partition("=")
        return {}, {key: float(val)}, text
    effects = {}
    for part in text.split("+"):
        name, _, mult = part.partition("=")
        effects[name] = round(float(mult) * LIMITS[name], 6)
    return effects, {}, text


def _gap_dict(g: GapResult | None) -> dict | None:
    if g is None:
        return None
    return {
        "flagged": g.flagged,
        "significant": g.significant,
        "biased": g.biased,
        "p_holm": {n: round(x.p_holm, 4) for n, x in g.gaps.items()},
        "bias_p_holm": {n: [round(q, 4) for q in x.bias_p_holm] for n, x in g.gaps.items()},
        "bias_z": {n: [round(q, 2) for q in x.bias_z] for n, x in g.gaps.items()},
    }


def classify(kind: str, named: list[dict[str, float]], truth: set[str]) -> str:
    """One of :data:`CLASSES` (``named``: the verdict's alternatives)."""
    if kind == "no significant gap":
        return "no gap"
    if kind == "unexplained":
        return "unexplained"
    sets = [set(a) for a in named]
    if kind == "named":
        if sets[0] == truth:
            return "named"
        return "detected, not named" if sets[0] < truth else "wrong name"
    # ambiguous: a wrong name when an alternative shares nothing with the truth
    if any(not (s & truth) for s in sets):
        return "wrong name"
    return "detected, not named"


def truth_gap(data, field, fiber, effects, seed, workers, n_perm, declared=None, flow=None,
              cache=None) -> GapResult:  # fmt: skip
    """The gap test against 8 copies made with the hidden model itself (other draws)."""
    with Simulator(field, fiber, workers=workers, progress=False, tracks=False,
                   candidates=declared or [], flow=flow, cache_dir=cache) as sim:  # fmt: skip
        maker = CopyMaker(data.starts, NoiseModel(), seed + 104729, sim)
        cps = maker.copies(range(8), effects)
    values = value_matrices(data.table.reset_index(drop=True), cps, tuple(data.observed))
    return assess_gap(values, np.random.default_rng([seed, 97]), n_perm=n_perm)


def run_one(text: str, seed: int, args, field) -> dict:
    effects, setting, label = parse_scenario(text)
    fiber = FiberSettings()
    declared: tuple = ()
    truth_fiber = fiber
    truth_eff = dict(effects)
    if setting:
        ((key, val),) = setting.items()
        cand = parse_candidate(DECLARED[key], fiber, STUDY_FLOW)
        declared = (cand,)
        u = _candidate_value(cand, val)
        truth_fiber, _ = apply_values({cand.name: cand}, {cand.name: u}, fiber, STUDY_FLOW)
        truth_eff = {cand.name: u}
    t0 = time.perf_counter()
    box = quick_box() if args.box == "quick" else BOX
    table, _ = synthesize(field, truth_fiber, box, args.n, effects, seed=seed,
                          workers=args.workers, progress=False)  # fmt: skip
    data = validate_measured(table, source=label)
    s = DiscrepancySettings(seed=seed, workers=args.workers, declared=declared,
                            power_fibers=0, next_copies=0)  # fmt: skip
    res = run_discrepancy(data, field, fiber, s, progress=False, flow=STUDY_FLOW,
                          cache_dir=args.cache)  # fmt: skip
    v = res.verdict
    truth = set(truth_eff)
    row = {
        "scenario": label + (" (quick box)" if args.box == "quick" else ""),
        "seed": seed,
        "n": len(table),
        "truth": truth_eff,
        "verdict": v.kind,
        "effects": v.effects,
        "alternatives": [dict(a) for a in v.alternatives],
        "text": v.text,
        "class": classify(v.kind, [dict(a) for a in v.alternatives], truth),
        "baseline": _gap_dict(res.gap),
        "heldout": [
            {
                "name": h.name,
                "value": h.value,
                "significant": h.significant,
                "p_holm": h.p_holm,
                "improvement": list(h.improvement),
                "explains": h.explains,
                "final": _gap_dict(h.final),
                "residual": _gap_dict(h.residual),
            }
            for h in res.heldout
        ],  # fmt: skip
        "sets": [
            {
                "name": st.name,
                "values": st.values,
                "fold_values": st.fold_values,
                "p_holm": st.p_holm,
                "intervals": st.intervals,
                "final": _gap_dict(st.final),
                "residual": _gap_dict(st.residual),
            }
            for st in res.sets
        ],  # fmt: skip
        "intervals": res.extra.get("intervals", {}),
        "fold_values": res.extra.get("fold_values", {}),
        "simulations": res.simulations,
        "seconds": round(time.perf_counter() - t0, 1),
    }
    if args.truth_gap and res.gap.any:
        g = truth_gap(data, field, fiber, truth_eff, seed, args.workers, s.n_perm,
                      declared=list(declared), flow=STUDY_FLOW, cache=args.cache)  # fmt: skip
        row["truth_gap"] = _gap_dict(g)
    return row


def _candidate_value(cand, setting_value: float) -> float:
    """The candidate's fitted coordinate of a setting value (inverse of ``cand.setting``)."""
    from scipy.optimize import brentq

    lo = cand.lo + 1e-9 * (cand.hi - cand.lo)  # the rigid scale is infinite at 0
    return float(brentq(lambda u: cand.setting(u) - setting_value, lo, cand.hi))


def tabulate(out: Path) -> str:
    rows = [json.loads(p.read_text()) for p in sorted(out.glob("*.json"))]
    by: dict[str, list[dict]] = {}
    for r in rows:
        by.setdefault(r["scenario"], []).append(r)
    head = "| scenario (× N = 100 limit) | data sets | " + " | ".join(CLASSES)
    lines = [head + " | true model leaves a gap | runs |", "|" + "---|" * (len(CLASSES) + 4)]
    tot = dict.fromkeys(CLASSES, 0)
    for name, rs in by.items():
        c = {k: sum(r["class"] == k for r in rs) for k in CLASSES}
        for k in CLASSES:
            tot[k] += c[k]
        tg = [r for r in rs if "truth_gap" in r]
        tgs = f"{sum(bool(r['truth_gap']['flagged']) for r in tg)} of {len(tg)}" if tg else "–"
        runs = [r["simulations"] for r in rs]
        lines.append(f"| {name} | {len(rs)} | " + " | ".join(str(c[k]) for k in CLASSES)
                     + f" | {tgs} | {min(runs)}–{max(runs)} |")  # fmt: skip
    n = len(rows)
    if n:
        lo, hi = wilson(tot["unexplained"], n)
        lines.append(
            f"\nall: {n} data sets; unexplained {tot['unexplained']} "
            f"(Wilson 95 % [{lo:.2f}, {hi:.2f}]); wrong names {tot['wrong name']}"
        )
    for r in rows:
        if r["class"] != "named":
            lines.append(f"- {r['scenario']} seed {r['seed']}: {r['class']}: {r['text']}")
    return "\n".join(lines)


def main() -> None:
    ap = study_parser(__doc__, "results/infamily")
    ap.add_argument("--scenarios", nargs="+", default=["friction=2"])
    ap.add_argument("--seeds", type=int, nargs="+", default=[9701])
    ap.add_argument("--n", type=int, default=100)
    ap.add_argument(
        "--box",
        choices=("study", "quick"),
        default="study",
        help="start box: the studies' or configs/quick.yaml's (one length)",
    )
    ap.add_argument(
        "--truth-gap",
        action="store_true",
        help="also test the gap against copies of the true model",
    )
    if (args := parse_study(ap, tabulate)) is None:
        return
    out = args.out
    out.mkdir(parents=True, exist_ok=True)
    field = study_field(args.cache)
    for seed in args.seeds:
        for text in args.scenarios:
            tag = text.replace(":", "_").replace("+", "_")
            tag += "_quick" if args.box == "quick" else ""
            path = out / f"{tag}_{seed}.json"
            if path.exists():
                continue
            row = run_one(text, seed, args, field)
            path.write_text(json.dumps(row, indent=1, default=float))
            log.warning("%s seed %d: %s (%s) %.0f s", text, seed, row["class"], row["text"],
                        row["seconds"])  # fmt: skip


if __name__ == "__main__":
    main()
