"""Why the pooled refit's value is biased: a dense per-fiber loss profile on the simulator.

Synthesises ``--n`` fibers with one hidden effect, simulates ``--fit-copies``
copies of every fiber on a dense grid of the effect's value (common random
numbers, as the fit does), and stores the per-fiber loss at every grid value
(the loss of :func:`fibersweep.discrepancy.fit.per_fiber_loss`, weights of the
observables with a gap, as the workflow's fits use). Several ``--copy-seeds``
give independent sets of copies on the same data: the spread of the argmin
over them is the copies' Monte Carlo noise of the fit.

From the stored profiles, :func:`summarise` compares the estimators on the
values a Brent search of the workflow would evaluate (a random subset of the
grid) and on the whole grid: the argmin of the mean loss (the value the
workflow reported) and the zero of the mean loss slope
(:func:`fibersweep.discrepancy.estimate.slope_estimate`).

Usage::

    python scripts/studies/discrepancy/diagnose_fit_bias.py --effect pillar_hydro=0.6 --n 60 \
        --grid 0 1.4 15 --copy-seeds 1 2 3 --out results/fitbias_ph
    python scripts/studies/discrepancy/diagnose_fit_bias.py --summarise \
        results/fitbias_ph/profile.npz
"""

from __future__ import annotations

import argparse
import logging
import pickle
import sys
from pathlib import Path

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.copies import CopyMaker, NoiseModel
from fibersweep.discrepancy.dispersion import dispersion_test
from fibersweep.discrepancy.estimate import Fit
from fibersweep.discrepancy.fit import per_fiber_loss
from fibersweep.discrepancy.gap import assess_gap, observable_weights, value_matrices
from fibersweep.discrepancy.schema import validate_measured
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.discrepancy.synth import synthesize

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from common import BOX, DEFAULT_CACHE, study_field  # noqa: E402

log = logging.getLogger("fitbias")


def measure(args) -> Path:
    name, val = args.effect.split("=")
    truth = float(val)
    field = study_field(args.cache)
    table, _ = synthesize(field, FiberSettings(), BOX, args.n, {name: truth}, seed=args.seed,
                          workers=args.workers, progress=False)  # fmt: skip
    data = validate_measured(table, source="diagnose")
    observed = data.table.reset_index(drop=True)
    obs = tuple(data.observed)
    grid = np.linspace(args.grid[0], args.grid[1], int(args.grid[2]))
    grid = np.union1d(grid, [0.0])
    profiles, fits, refits, disp = [], [], [], []
    with Simulator(field, FiberSettings(), workers=args.workers, progress=False) as sim:
        for cs in args.copy_seeds:
            maker = CopyMaker(data.starts, NoiseModel(), cs, sim)
            base = maker.copies(range(8), None)
            values = value_matrices(observed, base, obs)
            w = observable_weights(values)
            gap = assess_gap(values, np.random.default_rng(cs), n_perm=999)
            w_gap = {o: (x if o in gap.flagged else 0.0) for o, x in w.items()}
            log.warning("copy seed %d: gap in %s", cs, gap.flagged)
            rows, dz = [], []
            for v in grid:
                cps = maker.copies(range(args.fit_copies), {name: float(v)} if v else None)
                vals = value_matrices(observed, cps, obs)
                rows.append(per_fiber_loss(vals, w_gap))
                # how widely the observations spread among copies at v (1: as a copy)
                dz.append(dispersion_test(vals, np.random.default_rng(cs), 999).statistic)
            profiles.append(np.stack(rows))
            disp.append(dz)
            log.warning("copy seed %d: dispersion score %s", cs, np.round(dz, 2))
            log.warning("copy seed %d: argmin %.3g", cs, grid[np.argmin(profiles[-1].mean(1))])
            if args.workflow_fits:
                row, refit = workflow_fits(
                    name, maker, observed, base, obs, w_gap, cs, args.fit_copies
                )
                fits.append(row)
                refits.append(refit)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    np.savez(out / "profile.npz", grid=grid, profiles=np.stack(profiles), truth=truth,
             name=name, n=args.n, seed=args.seed, copy_seeds=np.array(args.copy_seeds),
             fits=np.array(fits, dtype=np.float64).reshape(-1, 7),
             dispersion=np.array(disp))  # fmt: skip
    if refits:  # the pooled refits' per-fiber profiles, to compare estimators offline
        with open(out / "refits.pkl", "wb") as fh:
            pickle.dump(refits, fh)
    return out / "profile.npz"


def workflow_fits(
    name, maker, observed, base, obs, w_gap, seed, k_fit=2
) -> tuple[list[float], Fit]:
    """The workflow's fits on these copies: each half by Brent (5 evaluations), then the
    pooled refit around the halves' values (3 more, the halves' values known).

    Returns [half 0, half 1, refit argmin, refit slope estimate, interval lo, hi, seed]
    and the refit.
    """
    from fibersweep.discrepancy.candidates import LIBRARY
    from fibersweep.discrepancy.estimate import score_interval, slope_estimate
    from fibersweep.discrepancy.fit import fit_effect

    cand = LIBRARY[name]
    n = len(observed)
    perm = np.random.default_rng([seed, 11]).permutation(n)
    folds = [np.sort(perm[: n // 2]), np.sort(perm[n // 2 :])]
    halves = []
    for train in folds[::-1]:
        obs_tr = observed.iloc[train].reset_index(drop=True)
        sub = [b.iloc[train].reset_index(drop=True) for b in base[:k_fit]]
        f = fit_effect(cand, maker, obs_tr, sub, train, obs, w_gap, 5, side=1.0)
        halves.append(f.value)
    pad = 0.25 * (cand.hi - cand.lo)
    bounds = (max(cand.lo, min(halves) - pad), min(cand.hi, max(halves) + pad))
    f = fit_effect(cand, maker, observed, base[:k_fit], np.arange(n), obs, w_gap, 3,
                   bounds=bounds, stage="refit", known=halves)  # fmt: skip
    lo, hi, *_ = score_interval(f)
    row = [*halves, f.value, slope_estimate(f), lo, hi, float(seed)]
    log.warning("copy seed %d: halves %.3g %.3g, refit %.3g, estimate %.3g [%.3g, %.3g]",
                seed, *row[:6])  # fmt: skip
    return row, f


def summarise(path: str, n_sub: int = 6, n_rep: int = 400) -> str:
    from fibersweep.discrepancy.estimate import score_interval, slope_estimate

    d = np.load(path)
    grid, P, truth = d["grid"], d["profiles"], float(d["truth"])
    rng = np.random.default_rng(0)
    lines = [f"{d['name']} = {truth:g}, N = {int(d['n'])}, {len(P)} sets of copies, "
             f"grid {grid[0]:g}..{grid[-1]:g} ({len(grid)} values)"]  # fmt: skip
    for s, L in enumerate(P):
        full = Fit(str(d["name"]), float(grid[np.argmin(L.mean(1))]), 0.0, 0.0, (),
                   tuple(zip(grid, L, strict=True)))  # fmt: skip
        lo, hi, *_ = score_interval(full)
        mean = L.mean(1) - L.mean(1).min()
        lines.append(f"copies {s}: whole grid argmin {full.value:.3g}, slope zero "
                     f"{slope_estimate(full):.3g}, interval [{lo:.3g}, {hi:.3g}]; mean loss - min: "
                     + " ".join(f"{m:.4f}" for m in mean))  # fmt: skip
        am, sz = [], []
        for _ in range(n_rep):
            pick = np.sort(rng.choice(len(grid), size=min(n_sub, len(grid)), replace=False))
            f = Fit(str(d["name"]), float(grid[pick][np.argmin(L[pick].mean(1))]), 0.0, 0.0, (),
                    tuple(zip(grid[pick], L[pick], strict=True)))  # fmt: skip
            est = slope_estimate(f)
            am.append(f.value)
            sz.append(est)
        lines.append(
            f"  {n_sub} random grid values: argmin mean {np.mean(am):.3g} sd "
            f"{np.std(am):.3g}; slope zero mean {np.mean(sz):.3g} sd {np.std(sz):.3g}"
        )
    if "dispersion" in d.files and d["dispersion"].size:
        for s, dz in enumerate(d["dispersion"]):
            lines.append(f"copies {s}: dispersion score of the observations at each grid value: "
                         + " ".join(f"{x:.2f}" for x in dz))  # fmt: skip
    if "fits" in d.files and len(d["fits"]):
        F = d["fits"]
        lines.append("workflow fits (halves, refit argmin, refit estimate, interval):")
        lines += [f"  copies {int(r[6])}: {r[0]:.3g} {r[1]:.3g} -> {r[2]:.3g} / {r[3]:.3g} "
                  f"[{r[4]:.3g}, {r[5]:.3g}]" for r in F]  # fmt: skip
        lines.append(f"  mean: refit argmin {F[:, 2].mean():.3g}, estimate {F[:, 3].mean():.3g},"
                     f" interval covers {int(((F[:, 4] <= truth) & (truth <= F[:, 5])).sum())}"
                     f" of {len(F)}")  # fmt: skip
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--effect", default="pillar_hydro=0.6")
    ap.add_argument("--n", type=int, default=60)
    ap.add_argument("--seed", type=int, default=41)
    ap.add_argument("--grid", type=float, nargs=3, default=[0.0, 1.4, 15])
    ap.add_argument("--copy-seeds", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--fit-copies", type=int, default=2)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cache", default=DEFAULT_CACHE)
    ap.add_argument("--out", default="results/fitbias")
    ap.add_argument(
        "--workflow-fits",
        action="store_true",
        help="also run the workflow's half fits and pooled refit per copy seed",
    )
    ap.add_argument("--summarise", default=None)
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)
    path = args.summarise or measure(args)
    print(summarise(str(path)))


if __name__ == "__main__":
    main()
