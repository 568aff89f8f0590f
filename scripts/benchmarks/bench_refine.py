#!/usr/bin/env python3
"""Adaptive refinement against the uniform grid that resolves the same, measured in one run.

At L = 0.8 l_obs over θ0 in [-10, 10] deg (one column per --dtheta) and y0/h_obs in [0, 1],
every class boundary is located along y0 to --tol (a bracket of two neighbouring runs of
different classes at most --tol apart), on the coarse dx = 4 µm field with the real
simulator:

  * refined: a grid of step --coarse in y0, then `sweep.refine` (axes [y0], tolerance --tol);
  * uniform: the grid of step --tol in y0 on the same θ0 columns, which brackets every
    boundary it sees to --tol: the uniform grid that resolves the same.

Reported: the runs of each and their ratio (and of the CPU seconds the runs took); then,
taking the uniform grid as the reference, every boundary segment it finds (neighbouring
points of different classes) is looked for
among the refinement's brackets at the same θ0: a segment is found when a refined bracket
of the same two classes overlaps it (their intervals meet within --tol); the missed ones
are listed. Refined brackets the uniform grid has no counterpart for are counted too (a
band thinner than its step). Writes the refined phase figure with its boundaries (missed
segments marked) to --figure.

Usage:  nice -n 5 python scripts/benchmarks/bench_refine.py [--cache .fibersweep-cache] [--out DIR]
            [--dtheta 2] [--coarse 0.05] [--tol 0.005] [--delta-jump 0.1] [--workers 2]
            [--figure docs/figures/refine.png]
"""

from __future__ import annotations

import argparse
import logging
import time
from pathlib import Path

import numpy as np
import pandas as pd

from fibersweep.analysis.boundaries import brackets
from fibersweep.config import parse_config
from fibersweep.sweep.manifest import read_manifest
from fibersweep.sweep.runner import run_sweep
from fibersweep.sweep.store import read_runs

#: Arguments of a run of seconds (scripts/benchmarks/run.py --smoke): the script runs
#: end to end, its numbers mean nothing.
SMOKE = ["--dtheta", "20", "--coarse", "0.25", "--tol", "0.05", "--out", "{tmp}",
         "--cache", "{cache}"]  # fmt: skip

log = logging.getLogger("bench_refine")

LENGTH = 0.8
THETA_RANGE = (-10.0, 10.0)


def make_config(args: argparse.Namespace, out: Path, refine: bool):
    """The sweep: refined from a coarse grid, or the uniform grid at the tolerance."""
    step = args.coarse if refine else args.tol
    sweep = {
        "theta0": {"start": THETA_RANGE[0], "stop": THETA_RANGE[1], "step": args.dtheta},
        "y0": {"start": 0.0, "stop": 1.0, "step": step},
        "length": LENGTH,
    }
    if refine:
        sweep["refine"] = {
            "axes": ["y0"],
            "tolerance": {"y0": args.tol},
            "max_runs": args.max_runs,
            "rounds": 20,
            **({"delta_jump": args.delta_jump} if args.delta_jump else {}),
        }
    data = {
        "flow": {"dx": 4.0},
        "fiber": {"model": "rigid"},
        "sweep": sweep,
        "run": {"workers": args.workers, "output": str(out), "cache_dir": args.cache},
    }
    return parse_config(data, source="bench_refine")


def segments(runs: pd.DataFrame, delta_jump: float | None = None) -> pd.DataFrame:
    """Class brackets along y0 at each θ0 column (sorted)."""
    b = brackets(runs, ["y0"], delta_jump=delta_jump)
    b = b[b["kind"] == "class"]
    return b.sort_values(["theta0", "lo"]).reset_index(drop=True)


def match(
    reference: pd.DataFrame, found: pd.DataFrame, tol: float, same_classes: bool = True
) -> np.ndarray:
    """For each reference segment: is there a found one (of the same classes) within ``tol``?"""
    ok = np.zeros(len(reference), dtype=bool)
    for k, r in enumerate(reference.itertuples()):
        f = found[np.isclose(found["theta0"], r.theta0, atol=1e-9)]
        if same_classes:
            pair = {r.class_lo, r.class_hi}
            same = [{a, b} == pair for a, b in zip(f["class_lo"], f["class_hi"], strict=True)]
            f = f[same]
        ok[k] = bool(((f["lo"] <= r.hi + tol) & (f["hi"] >= r.lo - tol)).any())
    return ok


def timed_sweep(cfg) -> tuple[pd.DataFrame, float, dict]:
    t0 = time.perf_counter()
    summary = run_sweep(cfg)
    wall = time.perf_counter() - t0
    return read_runs(Path(cfg.run.output)), wall, summary.refinement or {}


def figure(runs: pd.DataFrame, missed: pd.DataFrame, separatrix, path: Path) -> None:
    """The refined runs and their boundaries: whole range, and zoomed on the boundaries."""
    from matplotlib.lines import Line2D

    from fibersweep.fiber.result import CLASSES
    from fibersweep.plots.phase import BOUNDARY_STYLE, draw_boundaries
    from fibersweep.plots.style import CLASS_STYLE, paper_style, save_figure, subplots

    ok = runs[runs["status"] == "ok"]
    grid = (ok["round"] == 0).to_numpy()
    near = ok.loc[~grid, "y0"]
    zoom = (float(near.min()) - 0.03, float(near.max()) + 0.03) if len(near) else (0, 1)
    with paper_style():
        fig, axes = subplots(1, 2, figsize=(7.0, 3.3), squeeze=False)
        for ax, ylim in zip(axes[0], (None, zoom), strict=True):
            for c in CLASSES:
                q = ok[ok["class"] == c]
                if len(q):
                    size = np.where(q["round"].to_numpy() > 0, 6.0, 14.0 if ylim is None else 30.0)
                    ax.scatter(
                        q["theta0"], q["y0"], s=size, lw=0.3, edgecolor="k", **CLASS_STYLE[c]
                    )
            draw_boundaries(ax, ok)
            if separatrix is not None:
                ax.axhline(separatrix, color="0.2", lw=1.0, ls="--", zorder=1)
            if len(missed):
                ax.scatter(missed["theta0"], missed["y0"], marker="x", s=45, color="red", zorder=6)
            if ylim is not None:
                ax.set_ylim(*ylim)
                ax.set_title("zoom on the boundaries", fontsize=8)
            else:
                ax.set_title(f"L = {LENGTH} l_obs: {len(runs)} runs", fontsize=8)
            ax.set_xlabel(r"$\theta_0$ [deg]")
        axes[0, 0].set_ylabel(r"$y_0/h_{obs}$")
        hs = [
            Line2D([], [], ls="", markersize=5, label=c, **CLASS_STYLE[c])
            for c in CLASSES
            if (ok["class"] == c).any()
        ]
        hs.append(Line2D([], [], label="located boundary", **BOUNDARY_STYLE))
        if separatrix is not None:
            hs.append(Line2D([], [], color="0.2", ls="--", lw=1.0, label="separatrix"))
        if len(missed):
            hs.append(Line2D([], [], ls="", marker="x", color="red", label="missed"))
        fig.legend(handles=hs, loc="outside upper center", ncol=len(hs), frameon=False)
        save_figure(fig, path, format="png")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cache", default=".fibersweep-cache", help="flow-field cache directory")
    ap.add_argument("--out", type=Path, default=Path("results/bench_refine"))
    ap.add_argument("--dtheta", type=float, default=2.0, help="θ0 column step [deg]")
    ap.add_argument("--coarse", type=float, default=0.05, help="starting y0 step [h_obs]")
    ap.add_argument("--tol", type=float, default=0.005, help="y0 tolerance [h_obs]")
    ap.add_argument("--delta-jump", type=float, default=None, help="also bisect δ jumps")
    ap.add_argument("--max-runs", type=int, default=20_000, help="refinement budget")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--figure", type=Path, default=None)
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)

    refined, t_ref, info = timed_sweep(make_config(args, args.out / "refined", True))
    uniform, t_uni, _ = timed_sweep(make_config(args, args.out / "uniform", False))
    n_ref, n_uni = len(refined), len(uniform)
    ref_b, uni_b = segments(refined, args.delta_jump), segments(uniform)
    width = ref_b["hi"] - ref_b["lo"]
    found = match(uni_b, ref_b, args.tol)
    placed = match(uni_b, ref_b, args.tol, same_classes=False)
    extra = ~match(ref_b, uni_b, args.tol, same_classes=False)
    n_cols = refined["theta0"].nunique()
    print(f"L = {LENGTH} l_obs, θ0 in {THETA_RANGE} step {args.dtheta} ({n_cols} columns), "
          f"y0/h in [0, 1]; tolerance {args.tol} h_obs; coarse step {args.coarse}"
          + (f"; delta_jump {args.delta_jump}" if args.delta_jump else ""))  # fmt: skip
    print(f"refined: {n_ref} runs ({int((refined['round'] == 0).sum())} grid + "
          f"{int((refined['round'] > 0).sum())} in {info.get('rounds')} rounds), "
          f"{len(ref_b)} class brackets, widest {width.max():.4g} h_obs "
          f"({int((width <= args.tol + 1e-12).sum())} within tolerance); stopped: "
          f"{info.get('stopped')}; {t_ref:.0f} s")  # fmt: skip
    print(f"uniform: {n_uni} runs, {len(uni_b)} class brackets; {t_uni:.0f} s")
    print(f"ratio uniform / refined runs: {n_uni / n_ref:.2f}x")
    cpu_ref, cpu_uni = float(refined["cpu_time"].sum()), float(uniform["cpu_time"].sum())
    print(f"CPU time of the runs: refined {cpu_ref:.1f} s, uniform {cpu_uni:.1f} s, ratio "
          f"{cpu_uni / cpu_ref:.2f}x (runs near a boundary take longer)")  # fmt: skip
    print(f"uniform-grid boundary segments: {len(uni_b)}; located by the refinement with the "
          f"same classes {int(found.sum())}, at the same place with other classes "
          f"{int((placed & ~found).sum())}, missed {int((~placed).sum())}")  # fmt: skip
    for r in uni_b[~found].itertuples():
        what = "other classes" if placed[r.Index] else "missed"
        print(f"  {what}: θ0 = {r.theta0:g}, y0 in [{r.lo:.3f}, {r.hi:.3f}], "
              f"{r.class_lo} | {r.class_hi}")  # fmt: skip
    print(f"refined brackets with no uniform-grid counterpart: {int(extra.sum())}")
    for r in ref_b[extra].itertuples():
        print(f"  extra: θ0 = {r.theta0:g}, y0 in [{r.lo:.4f}, {r.hi:.4f}], "
              f"{r.class_lo} | {r.class_hi}")  # fmt: skip
    failed = int((refined["status"] != "ok").sum()) + int((uniform["status"] != "ok").sum())
    print(f"failed runs: {failed}")
    if args.figure is not None:
        missed = uni_b[~placed].assign(y0=lambda d: 0.5 * (d["lo"] + d["hi"]))
        sep = (read_manifest(args.out / "refined") or {}).get("separatrix")
        figure(refined, missed, sep, args.figure)
        print(f"wrote {args.figure}")


if __name__ == "__main__":
    main()
