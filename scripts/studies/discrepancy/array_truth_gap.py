"""The gap test of the array discrepancy workflow at the TRUE model (a row shift hidden).

Synthesises ``N`` fibers through ``ROWS`` rows of ``configs/array.yaml`` at dx = 2 µm
with ``flow.array.shift = 0.125`` (as ``tests/validation/test_discrepancy_array_hidden.py``
does), then runs the workflow's gap test (:func:`.gap.assess_gap` on copies made by
:class:`.copies.CopyMaker`, as :func:`.stages.refit` makes its final copies) with the
copies at the true setting. If the true model itself leaves a significant gap, the
copies are not made the way the data were.

Per seed it prints the gap per observable (score z, p; signed-residual z, p, Holm p),
the copies that failed and why, and the fraction residual split by where the fiber
starts (near a pillar's reach or not) and by length.

    nice -n 10 python3 scripts/studies/discrepancy/array_truth_gap.py --seeds 5701 5702 5703
    nice -n 10 python3 scripts/studies/discrepancy/array_truth_gap.py --seeds 5701 --copies 8
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from fibersweep.api.compare import declared_candidates, sweep_box
from fibersweep.config import load_config
from fibersweep.discrepancy.array_schema import array_measured_data
from fibersweep.discrepancy.array_synth import clear_starts, synthesize_array
from fibersweep.discrepancy.copies import CopyMaker, array_noise
from fibersweep.discrepancy.gap import assess_gap, value_matrices
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.flow.cache import get_flow_field

REPO = Path(__file__).resolve().parents[3]
N, ROWS = 60, 6
BASE = ["flow.dx=2", f"fiber.array_rows={ROWS}", "run.workers=2"]
TRUTH = ["flow.array.shift=0.125"]


def one(seed: int, copies: int, cache: Path, workers: int, copy_seed: int | None,
        via: bool) -> None:  # fmt: skip
    made = load_config(REPO / "configs" / "array.yaml", [*BASE, *TRUTH])
    field, _ = get_flow_field(made.flow, cache)
    table, truth = synthesize_array(field, made.fiber, sweep_box(made), N, {}, seed=seed,
                                    workers=workers, progress=False)  # fmt: skip
    data = array_measured_data(table)
    noise = array_noise(made.fiber)
    true = np.column_stack([truth["true_starts"][k] for k in ("theta0", "y0", "length")])
    cseed = seed if copy_seed is None else copy_seed
    if via:  # as the workflow's final copies: the design's simulator, the candidate switched on
        cfg = load_config(REPO / "configs" / "array.yaml", BASE)
        design, _ = get_flow_field(cfg.flow, cache)
        decl = declared_candidates(cfg, TRUTH)
        with Simulator(design, cfg.fiber, workers=workers, progress=False, candidates=decl,
                       flow=cfg.flow, cache_dir=cache) as sim:  # fmt: skip
            cps_via = CopyMaker(data.starts, noise, cseed, sim).copies(
                range(copies), {decl[0].name: 1.0}, desc="via candidate"
            )
    with Simulator(field, made.fiber, workers=workers, progress=False) as sim:
        maker = CopyMaker(data.starts, noise, cseed, sim)
        cps = maker.copies(range(copies), None, desc="truth copies")
        # the same fibers re-run at their true starts with fresh run seeds: no start noise
        at_true = sim.run(true, {}, np.arange(len(true)) + 1000, desc="at-true")
    if via:
        for k, (a, b) in enumerate(zip(cps, cps_via, strict=True)):
            fa, fb = a["fraction"].to_numpy(float), b["fraction"].to_numpy(float)
            diff = ~((fa == fb) | (np.isnan(fa) & np.isnan(fb)))
            print(
                f"  copy {k}: direct vs via-candidate fraction differ in {diff.sum()} fibers; "
                f"status differ in {(a['status'] != b['status']).sum()}"
            )
            for i in np.flatnonzero(diff)[:10]:
                print(f"    fiber {i}: direct {fa[i]:.4f} {a['mode'][i]} | via {fb[i]:.4f} "
                      f"{b['mode'][i]} {b['reason'][i][:60]}")  # fmt: skip
        cps = cps_via
    vals = value_matrices(data.table, cps, data.observed)
    gap = assess_gap(vals, np.random.default_rng([seed, 11]), n_perm=1999)
    print(f"\n== seed {seed}: {len(table)} fibers written, {len(truth['failed'])} synth failed; "
          f"{copies} copies; flagged: {gap.flagged or 'none'}")  # fmt: skip
    for name, g in gap.gaps.items():
        bz = ", ".join(f"{z:+.2f}" for z in g.bias_z)
        bp = ", ".join(f"{p:.4f}" for p in g.bias_p)
        bh = ", ".join(f"{p:.4f}" for p in g.bias_p_holm)
        print(f"  {name:8s} score z {g.test.z:+.2f} p {g.test.p_value:.4f} (Holm {g.p_holm:.4f}) "
              f"| bias z [{bz}] p [{bp}] Holm [{bh}] n {g.test.n}")  # fmt: skip
    # failures of the copies
    fails = [(k, c) for k, c in enumerate(cps) if (c["status"] != "ok").any()]
    nf = sum(int((c["status"] != "ok").sum()) for c in cps)
    print(f"  copies failed: {nf} of {copies * len(table)}")
    for k, c in fails:
        for i in np.flatnonzero((c["status"] != "ok").to_numpy()):
            print(f"    copy {k} fiber {i}: {c['reason'][i][:110]}")
    # where the residual lives: fraction observed - mean of copies
    V = vals["fraction"]
    cm = np.nanmean(V[:, 1:], axis=1)
    r = V[:, 0] - cm
    y0, L = table["y0"].to_numpy(), table["length"].to_numpy()
    # near a pillar's reach: a start 2 σ (y0) away from the measured one touches
    near = np.zeros(len(table), dtype=bool)
    for dy in (-0.02, -0.01, 0.01, 0.02):
        s = data.starts.copy()
        s[:, 1] = np.mod(s[:, 1] + dy, 1.0)
        near |= ~clear_starts(field, made.fiber, s)
    f_true = at_true["fraction"].to_numpy(dtype=float)
    for lab, m in (("all", np.ones(len(r), bool)), ("near", near), ("far", ~near),
                   ("y0<0.23 & L<37", (y0 < 0.23) & (L < 37)),
                   ("rest", ~((y0 < 0.23) & (L < 37)))):  # fmt: skip
        ok = m & np.isfinite(r)
        if ok.any():
            print(f"  fraction residual {lab:16s} n {ok.sum():3d} mean {np.mean(r[ok]):+.4f} "
                  f"sd {np.std(r[ok]):.4f}")  # fmt: skip
    big = np.argsort(-np.abs(np.nan_to_num(r)))[:8]
    print("  largest |obs - copies| fraction:   i   y0_meas  y0_true   th    L     obs   "
          "at_true copies")  # fmt: skip
    for i in big:
        cv = " ".join(f"{v:.3f}" for v in V[i, 1:])
        print(f"    {i:3d} {y0[i]:.4f} {true[i, 1]:.4f} {true[i, 0]:+5.1f} {true[i, 2]:5.1f} "
              f"{V[i, 0]:.3f} {f_true[i]:.3f}  [{cv}] near={near[i]}")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[5701])
    ap.add_argument("--copies", type=int, default=3)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--copy-seed", type=int, default=None)
    ap.add_argument(
        "--via-candidate",
        action="store_true",
        help="score the copies made as the workflow's final ones (design + candidate)",
    )
    ap.add_argument("--cache", type=Path, default=REPO / ".fibersweep-cache" / "tests")
    a = ap.parse_args()
    for seed in a.seeds:
        one(seed, a.copies, a.cache, a.workers, a.copy_seed, a.via_candidate)


if __name__ == "__main__":
    main()
