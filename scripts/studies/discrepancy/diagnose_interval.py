"""Why the refit's 95 % interval missed: the score test's T at the truth, read three ways.

For the single-kind data sets of ``scripts/studies/discrepancy/study_coverage.py`` (same seeds, same
stages: noise floor, the true effect's signature, the halves' fits, the pooled
refit's search and bracket, *without* the interval step of
:func:`fibersweep.discrepancy.fit.fit_effect`), the per-fiber losses at the
refit's evaluated values are kept, and two more evaluations are made at the
truth ± 15 % of the effect's limit (common random numbers). T at the truth is
then read

- ``midpoint``: T between neighbouring evaluated values, interpolated between
  their midpoints (the interval's read-out before 2026-11-27; still the
  estimate's, ``fit._slope_t``);
- ``per-fiber``: each fiber's slope interpolated between its midpoint slopes,
  then T (``estimate._fiber_t``, the interval's read-out now);
- ``at truth``: from the two evaluations at the truth (the test itself, with
  no interpolation).

Under the test's own assumptions T at the truth has rms 1 over data sets; an rms
above that from a read-out, but not from the evaluations at the truth, is the
read-out's error. One JSON per data set, so the study can be stopped and resumed::

    python scripts/studies/discrepancy/diagnose_interval.py --effect inlet_speed --sets 16 --out \
        results/diag_interval
    python scripts/studies/discrepancy/diagnose_interval.py --tabulate --out results/diag_interval
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path

import numpy as np
from scipy.stats import t as student_t

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.candidates import get_candidates
from fibersweep.discrepancy.copies import CopyMaker
from fibersweep.discrepancy.estimate import Fit, _fiber_t, _slope_t
from fibersweep.discrepancy.estimate import merged_profile as _merged
from fibersweep.discrepancy.fit import fit_effect, fold_fits, per_fiber_loss, refit_bounds
from fibersweep.discrepancy.gap import value_matrices
from fibersweep.discrepancy.schema import validate_measured
from fibersweep.discrepancy.settings import DiscrepancySettings, plan_budget
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.discrepancy.stages import Run, noise_floor, rank
from fibersweep.discrepancy.synth import synthesize

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from common import BOX, DEFAULT_CACHE, study_field  # noqa: E402
from common import COVERAGE_SEED0 as SEED0  # noqa: E402
from common import COVERAGE_SINGLES as SINGLES  # noqa: E402
from common import coverage_hidden as hidden  # noqa: E402
from common import coverage_limit as limit  # noqa: E402

log = logging.getLogger("diagnose_interval")


def t_at_truth(profile: list, truth: float) -> dict[str, float]:
    """T at ``truth`` from a refit's profile, by the midpoint and per-fiber read-outs."""
    fit = Fit("x", truth, 0.0, 0.0, (), tuple((float(v), np.asarray(L)) for v, L in profile))
    x, L = _merged(fit)
    mid, _, T = _slope_t(x, L)
    return {
        "midpoint": float(np.interp(truth, mid, np.clip(T, -1e6, 1e6))),
        "per-fiber": float(_fiber_t(x, L, np.array([truth]))[0]),
    }


def run_set(name: str, index: int, n: int, copies: int, field) -> dict:
    seed = SEED0["single"] + index
    effects = hidden("single", index, seed, n)
    t0 = time.perf_counter()
    table, _ = synthesize(field, FiberSettings(), BOX, n, effects, seed=seed, workers=1,
                          progress=False)  # fmt: skip
    data = validate_measured(table, source=f"single{seed}")
    s = DiscrepancySettings(seed=seed, workers=1, copies=copies, effects=tuple(effects))
    cands = get_candidates(s.effects)
    plan = plan_budget(n, s, cands)
    observed = data.table.reset_index(drop=True)
    rng = np.random.default_rng([s.seed, 11])  # the workflow's folds
    perm = rng.permutation(n)
    folds = [np.sort(perm[: n // 2]), np.sort(perm[n // 2 :])]
    row: dict = {"seed": seed, "effect": name, "truth": effects[name], "n": n, "gap": False}
    with Simulator(field, FiberSettings(), workers=1, progress=False) as sim:
        maker = CopyMaker(data.starts, s.noise, s.seed, sim)
        run = Run(s, plan, cands, observed, tuple(data.observed), folds, rng, maker)
        st = noise_floor(run)
        if st.gap.any:
            st = rank(st)
            (c,) = cands
            side = float(np.sign(st.signatures[0].probe))
            base = st.base[: plan.fit_copies_of(c, c.name == st.lead)]
            halves = [f.value for f in fold_fits(c, maker, observed, base, folds, run.observables,
                                                 st.w_gap, plan.fit_evals, side=side)]  # fmt: skip
            fit = fit_effect(c, maker, observed, base, np.arange(n), run.observables, st.w_gap,
                             plan.refit_evals, bounds=refit_bounds(c, halves), stage="refit",
                             known=halves, estimate=True, bracket_root=True,
                             close_interval=False)  # fmt: skip
            truth, h = effects[name], 0.15 * limit(name, n)
            at = []
            for v in (truth - h, truth + h):
                cps = maker.copies(range(len(base)), {name: v}, desc="diagnose")
                at.append(per_fiber_loss(value_matrices(observed, cps, run.observables), st.w_gap))
            g = (at[1] - at[0]) / (2 * h)
            T = t_at_truth(list(fit.profile), truth)
            T["at truth"] = float(g.mean() / (g.std(ddof=1) / np.sqrt(len(g))))
            row.update(gap=True, value=fit.value, evaluated=[p[0] for p in fit.profile], T=T)
    row["seconds"] = time.perf_counter() - t0
    return row


def tabulate(out: Path) -> str:
    rows = [json.loads(p.read_text()) for p in sorted(out.glob("seed*.json"))]
    lines = [
        "| effect | data sets with a gap | read-out | rms of T at the truth | rejects the truth |",
        "|---|---|---|---|---|",
    ]
    for name in sorted({r["effect"] for r in rows}):
        rs = [r for r in rows if r["effect"] == name and r["gap"]]
        crit = student_t.ppf(0.975, rs[0]["n"] - 1) if rs else np.inf
        for how in ("midpoint", "per-fiber", "at truth"):
            T = np.array([r["T"][how] for r in rs])
            lines.append(f"| {name} | {len(rs)} | {how} | {np.sqrt(np.mean(T**2)):.2f} | "
                         f"{int((np.abs(T) > crit).sum())} of {len(T)} |")  # fmt: skip
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--effect", choices=SINGLES, default="inlet_speed")
    ap.add_argument("--sets", type=int, default=16, help="data sets with a gap")
    ap.add_argument("--n", type=int, default=20)
    ap.add_argument("--copies", type=int, default=4)
    ap.add_argument("--cache", default=DEFAULT_CACHE)
    ap.add_argument("--out", default="results/diag_interval")
    ap.add_argument("--tabulate", action="store_true")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)
    out = Path(args.out)
    if not args.tabulate:
        field = study_field(args.cache)
        out.mkdir(parents=True, exist_ok=True)
        first = SINGLES.index(args.effect)  # the study's rotation over the singles
        done = 0
        for index in range(first, 3 * 80, len(SINGLES)):
            path = out / f"seed{SEED0['single'] + index}.json"
            row = json.loads(path.read_text()) if path.exists() else None
            if row is None:
                row = run_set(args.effect, index, args.n, args.copies, field)
                path.write_text(json.dumps(row, indent=1))
                log.warning("%s seed %d: %s", args.effect, row["seed"], row.get("T"))
            done += bool(row["gap"])
            if done >= args.sets:
                break
    print(tabulate(out))


if __name__ == "__main__":
    main()
