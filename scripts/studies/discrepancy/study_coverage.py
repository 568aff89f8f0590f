"""Coverage of the discrepancy workflow's 95 % intervals on the simulator.

Per data set: a hidden value (or pair of values) drawn at random from a stated
range (``COVERAGE_RANGES`` of ``scripts/studies/common.py``: 1.5-4x the effect's
detection limit at N = 100, scaled to N; the declared kind: the coordinate range
of ``COVERAGE_DECLARED``), measured-like fibers synthesised with it
(:func:`synth.synthesize`; the declared kind with the candidate's setting applied
to the fiber), and ONLY the workflow's own stages for the true effect(s), with no
candidate screening:

- the noise floor (:func:`stages.noise_floor`: baseline copies, the gap, the
  loss weights of the observables with a gap); a data set without a significant
  gap is recorded and left out of the coverage (the workflow names nothing);
- the signature of the true effect alone (:func:`stages.rank`; it gives a signed
  effect's side and makes a random effect the lead, with its extra fit copies);
- single, random and declared: the halves' fits (:func:`fit.fold_fits`), the
  pooled refit (:func:`fit.pooled_refit`) and its interval
  (:func:`estimate.score_interval`), as :func:`stages.refit` runs them for a
  significant candidate; the refit's per-fiber losses (and dispersion scores) are
  stored, so that ``read_intervals.py`` reads the interval again offline;
- pair: both members' halves, the first member's pooled refit and the gap it
  leaves (the pair's loss weights, :func:`pairs.pair_weights`), the joint fit on
  each fold (:func:`pairs.joint_fit`) and each member's refit with its interval
  (:func:`pairs.pair_refits`), as :func:`pairs.forward_pairs` runs them. The
  first member is fixed (friction; the workflow takes the one that improved the
  held-out fibers most, which needs held-out copies this study does not make).

This measures coverage *conditional on the right name*, which is what an
interval claims: whether the truth lies in the interval of the value the
workflow would quote, given that it names the true effect(s). It does not
measure naming.

One JSON per data set under ``OUT/KIND/seedS.json``; a set whose file exists is
skipped, so the study can be stopped and continued, and more seeds appended::

    python scripts/studies/discrepancy/study_coverage.py --kinds single declared --sets 8 \
        --n 20 --copies 4 --workers 1 --out results/interval_cov/n20
    python scripts/studies/discrepancy/study_coverage.py --tabulate --out results/interval_cov/n20
    python scripts/studies/discrepancy/read_intervals.py results/interval_cov/n20
"""

from __future__ import annotations

import json
import logging
import sys
import time
from pathlib import Path

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.candidates import LIBRARY, get_candidates
from fibersweep.discrepancy.copies import CopyMaker
from fibersweep.discrepancy.declared import apply_values, parse_candidate
from fibersweep.discrepancy.estimate import score_interval
from fibersweep.discrepancy.fit import fold_fits, pooled_refit
from fibersweep.discrepancy.gap import assess_gap, value_matrices
from fibersweep.discrepancy.pairs import SelectionInput, joint_fit, pair_refits, pair_weights
from fibersweep.discrepancy.schema import validate_measured
from fibersweep.discrepancy.settings import DiscrepancySettings, plan_budget
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.discrepancy.stages import Run, noise_floor, rank
from fibersweep.discrepancy.synth import synthesize

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from common import (  # noqa: E402
    BOX,
    COVERAGE_KINDS,
    COVERAGE_SEED0,
    DEFAULT_CACHE,
    STUDY_FLOW,
    coverage_hidden,
    parse_study,
    study_field,
    study_parser,
    wilson,
)
from common import COVERAGE_DECLARED as DECLARED  # noqa: E402
from common import COVERAGE_PAIR as PAIR  # noqa: E402

#: The library kinds and a declared candidate (a rigid contact setting, COVERAGE_DECLARED).
KINDS = (*COVERAGE_KINDS, "declared")
SEED0 = {**COVERAGE_SEED0, "declared": 8301}

log = logging.getLogger("coverage")


def hidden(kind: str, index: int, seed: int, n: int) -> dict[str, float]:
    """The hidden value(s) of data set ``index``: :func:`common.coverage_hidden`, or for
    the declared kind the candidate's coordinate drawn uniformly in its stated range."""
    if kind != "declared":
        return coverage_hidden(kind, index, seed, n)
    lo, hi = DECLARED["coordinate"]
    u = float(np.random.default_rng([seed, 31]).uniform(lo, hi))
    return {DECLARED["key"]: round(u, 5)}


def _interval_row(name, truth, value, halves, iv, cand=None) -> dict:
    """``covered``: the truth in [lo, hi] as reported. ``covered_open``: an end the
    refit's range cut ('≤' / '≥' in the report) taken as the effect's range end."""
    lo, hi, open_lo, open_hi = iv
    c = cand or LIBRARY[name]
    lo_o, hi_o = (c.lo if open_lo else lo), (c.hi if open_hi else hi)
    return {"effect": name, "truth": truth, "value": value, "halves": halves,
            "interval95": [lo, hi], "open": [open_lo, open_hi],
            "covered": bool(lo <= truth <= hi),
            "covered_open": bool(lo_o <= truth <= hi_o)}  # fmt: skip


def run_set(
    kind: str,
    index: int,
    seed: int,
    field,
    n: int,
    copies: int,
    workers: int,
    cache: str = DEFAULT_CACHE,
) -> dict:
    """One data set: synthesise, then the workflow's fit-and-interval stages only."""
    effects = hidden(kind, index, seed, n)
    t0 = time.perf_counter()
    declared: tuple = ()
    truth_fiber, lib = FiberSettings(), dict(effects)
    if kind == "declared":
        cand = parse_candidate(DECLARED["spec"], FiberSettings(), STUDY_FLOW)
        declared, lib = (cand,), {}
        truth_fiber, _ = apply_values({cand.name: cand}, effects, FiberSettings(), STUDY_FLOW)
    table, _ = synthesize(field, truth_fiber, BOX, n, lib, seed=seed, workers=workers,
                          progress=False)  # fmt: skip
    data = validate_measured(table, source=f"{kind}{seed}")
    s = DiscrepancySettings(seed=seed, workers=workers, copies=copies, effects=tuple(lib),
                            declared=declared)  # fmt: skip
    cands = list(declared) or get_candidates(s.effects)
    plan = plan_budget(n, s, cands)
    observed = data.table.reset_index(drop=True)
    rng = np.random.default_rng([s.seed, 11])  # the workflow's folds (run_discrepancy)
    perm = rng.permutation(n)
    folds = [np.sort(perm[: n // 2]), np.sort(perm[n // 2 :])]
    row: dict = {"kind": kind, "index": index, "seed": seed, "n": n, "copies": copies,
                 "truth": effects, "rows": []}  # fmt: skip
    with Simulator(field, FiberSettings(), workers=workers, progress=False,
                   candidates=list(declared), flow=STUDY_FLOW, cache_dir=cache) as sim:  # fmt: skip
        maker = CopyMaker(data.starts, s.noise, s.seed, sim)
        run = Run(s, plan, cands, observed, tuple(data.observed), folds, rng, maker)
        st = noise_floor(run)
        row["gap"] = list(st.gap.flagged)
        if st.gap.any:
            st = rank(st)
            side = {sg.name: float(np.sign(sg.probe)) for sg in st.signatures}
            halves = {}
            for c in cands:
                base = st.base[: plan.fit_copies_of(c, c.name == st.lead)]
                fits = fold_fits(c, maker, observed, base, folds, run.observables, st.w_gap,
                                 plan.fit_evals, side=side[c.name])  # fmt: skip
                halves[c.name] = [f.value for f in fits]
            if kind == "pair":
                row["rows"] = _pair(run, st, cands, halves, effects)
            else:
                (c,) = cands
                base = st.base[: plan.fit_copies_of(c, c.name == st.lead)]
                fit = pooled_refit(c, maker, observed, base, halves[c.name], run.observables,
                                   st.w_gap, plan.refit_evals)  # fmt: skip
                row["rows"] = [_interval_row(c.name, effects[c.name], fit.value,
                                             halves[c.name], score_interval(fit), c)]  # fmt: skip
                # the refit's per-fiber losses (and a random effect's dispersion scores):
                # other read-outs of its interval offline (scripts/.../read_intervals.py)
                row["profile"] = [[v, loss.tolist()] for v, loss in fit.profile]
                row["dispersion"] = [[v, d.tolist()] for v, d in fit.dispersion]
                row["range"] = [c.lo, c.hi]
        row["runs"] = sim.used
    row["seconds"] = time.perf_counter() - t0
    return row


def _pair(run: Run, st, cands, halves: dict, effects: dict) -> list[dict]:
    """The forward step's fits for the true pair (first member: PAIR[0])."""
    plan, s, maker, observed = run.plan, run.settings, run.maker, run.observed
    first, second = (next(c for c in cands if c.name == m) for m in PAIR)
    base = st.base[: plan.fit_copies]
    fit1 = pooled_refit(first, maker, observed, base, halves[first.name], run.observables,
                        st.w_gap, plan.refit_evals)  # fmt: skip
    cps = maker.copies(range(plan.copies), {first.name: fit1.value}, desc="final")
    left = assess_gap(value_matrices(observed, cps, run.observables), run.rng, alpha=s.alpha,
                      n_perm=s.n_perm)  # fmt: skip
    inp = SelectionInput(
        observed=observed, folds=run.folds, fold_values=halves, base_values=st.values,
        single_values={}, weights=pair_weights(st.weights, st.gap, left, s.alpha),
        observables=run.observables, copies=plan.copies, fit_copies=plan.fit_copies,
        fit_evals=plan.fit_evals, alpha=s.alpha, n_perm=s.n_perm, rounds=plan.pair_rounds,
        refit_evals=plan.refit_evals,
    )  # fmt: skip
    per_fold = [
        joint_fit(
            first,
            second,
            {first.name: halves[first.name][f], second.name: halves[second.name][f]},
            run.folds[1 - f],
            inp,
            maker,
        )  # fmt: skip
        for f in range(2)
    ]
    fold = {m: [pf[m] for pf in per_fold] for m in PAIR}
    values, ivs = pair_refits((second, first), fold, inp, maker)  # pairs._checked
    return [_interval_row(m, effects[m], values[m], fold[m], ivs[m]) for m in PAIR]


def _fitted(out: Path, kind: str) -> int:
    """Data sets of ``kind`` under ``out`` that had a gap and were fitted."""
    return sum(bool(json.loads(p.read_text())["rows"]) for p in out.glob(f"{kind}/seed*.json"))


def tabulate(out: Path) -> str:
    """Per kind (and per effect): k/n covered, Wilson 95 %, mean bias, RMSE."""
    rows = [json.loads(p.read_text()) for p in sorted(out.glob("*/seed*.json"))]
    lines = ["| kind | effect | data sets (no gap) | covered k/n | coverage [Wilson 95 %] "
             "| open ends to the range | mean bias | RMSE | mean width | open ends "
             "| value at an end | mean time [s] |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for kind in KINDS:
        sets = [r for r in rows if r["kind"] == kind]
        if not sets:
            continue
        fitted = [x for r in sets for x in r["rows"]]
        groups = [("all", fitted)] + [
            (e, [x for x in fitted if x["effect"] == e])
            for e in dict.fromkeys(x["effect"] for x in fitted)
        ]
        for label, xs in groups:
            if not xs or (label != "all" and len(groups) == 2):
                continue
            k = sum(x["covered"] for x in xs)
            lo, hi = wilson(k, len(xs))
            if label == "all" and len({x["effect"] for x in xs}) > 1:
                bias = rmse = width = "(per effect)"
            else:
                err = np.array([x["value"] - x["truth"] for x in xs])
                wid = np.array([x["interval95"][1] - x["interval95"][0] for x in xs])
                bias, rmse, width = (f"{err.mean():+.3g}", f"{np.sqrt((err**2).mean()):.3g}",
                                     f"{wid.mean():.3g}")  # fmt: skip
            opened = sum(any(x["open"]) for x in xs)
            # the value on an end: the accepted stretch lay beside it (widened to hold it)
            edge = sum(x["value"] in x["interval95"] for x in xs)
            secs = np.mean([r["seconds"] for r in sets])
            ko = sum(x.get("covered_open", x["covered"]) for x in xs)
            lo_o, hi_o = wilson(ko, len(xs))
            if label != "all":  # the data sets of this effect only
                sets_e = [r for r in sets if label in r["truth"]]
                nogap = sum(not r["rows"] for r in sets_e)
                n_sets = len(sets_e)
            else:
                nogap, n_sets = sum(not r["rows"] for r in sets), len(sets)
            lines.append(f"| {kind} | {label} | {n_sets} ({nogap}) | {k}/{len(xs)} | "
                         f"{k / len(xs):.2f} [{lo:.2f}, {hi:.2f}] | {ko}/{len(xs)} "
                         f"[{lo_o:.2f}, {hi_o:.2f}] | {bias} | {rmse} | {width} | "
                         f"{opened} | {edge} | {secs:.0f} |")  # fmt: skip
        if kind == "pair":
            both = [r for r in sets if r["rows"]]
            kb = sum(all(x["covered"] for x in r["rows"]) for r in both)
            if both:
                lo, hi = wilson(kb, len(both))
                lines.append(f"| pair | both members | {len(sets)} | {kb}/{len(both)} | "
                             f"{kb / len(both):.2f} [{lo:.2f}, {hi:.2f}]" + " |" * 8)  # fmt: skip
    return "\n".join(lines)


def main() -> None:
    ap = study_parser(__doc__, "results/coverage")
    ap.add_argument("--kinds", nargs="+", choices=KINDS, default=list(KINDS))
    ap.add_argument("--sets", type=int, default=20,
                    help="data sets per kind with a significant gap (fitted)")  # fmt: skip
    ap.add_argument("--max-sets", type=int, default=60, help="most data sets drawn per kind")
    ap.add_argument("--first", type=int, default=0, help="index of the first data set")
    ap.add_argument("--seed-offset", type=int, default=0,
                    help="added to each kind's first seed (new data sets)")  # fmt: skip
    ap.add_argument("--n", type=int, default=60, help="fibers per data set")
    ap.add_argument("--copies", type=int, default=8, help="baseline copies per fiber")
    if (args := parse_study(ap, tabulate)) is None:
        return
    out = args.out
    field = study_field(args.cache)
    # index-major: a study cut short has every kind at its first indices. A data set
    # without a significant gap is recorded (the workflow would name nothing) and costs
    # only its noise floor; indices go on until --sets data sets of each kind were
    # fitted (at most --max-sets drawn per kind).
    for i in range(args.first, args.first + args.max_sets):
        todo = [k for k in args.kinds if _fitted(out, k) < args.sets]
        if not todo:
            break
        for kind in todo:
            seed = SEED0[kind] + args.seed_offset + i
            path = out / kind / f"seed{seed}.json"
            if path.exists():
                continue
            row = run_set(kind, i, seed, field, args.n, args.copies, args.workers, args.cache)
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps(row, indent=1, default=float))
            log.warning("%s %d (seed %d): %s %s in %.0f s", kind, i, seed, row["truth"],
                        [(x["value"], x["interval95"], x["covered"]) for x in row["rows"]],
                        row["seconds"])  # fmt: skip
    print(tabulate(out))


if __name__ == "__main__":
    main()
