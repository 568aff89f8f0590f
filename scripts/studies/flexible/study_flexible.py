"""Single pillar: δ, class fractions and deformation against E, rigid limit to bending fibers.

Usage: python scripts/studies/flexible/study_flexible.py [--dx 4] [--cache .fibersweep-cache] \
    [--out DIR]
       [--lengths 0.6 1.2] [--moduli 26e6 2e6 0.5e6 0.1e6 0.03e6]
       [--thetas -10 0 10] [--y0s 10]

For each length L/l_obs and Young's modulus E, runs the bead-spring-ros2 model
from the starts θ0 x y0/h (a reduced grid of the paper's sweep: θ0 ∈ [-10°, 10°],
``--y0s`` values of y0/h evenly inside (0, 1)), and the rigid model as E = ∞.
Writes DIR/study.csv (one row per run), prints the table per (L, E): mean δ,
mean |δ| over passing runs, class fractions, medians of the deformation
observables, and draws DIR/stiffness_study.png (mean |δ| and class fractions
against E) and DIR/chrono_bending.png (chronophotograph of the softest, longest
fiber from θ0 = 0, y0/h = 0.45).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pandas as pd

from fibersweep.config.fiber import FiberSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.fiber.result import CLASSES, FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.flow.cache import get_flow_field
from fibersweep.plots.chrono import chronophotograph
from fibersweep.plots.style import paper_style, save_figure, subplots

RIGID = float("inf")


def _runs(field, lengths, moduli, thetas, y0s) -> pd.DataFrame:
    rows = []
    for L in lengths:
        for E in [RIGID, *moduli]:
            st = (
                FiberSettings()
                if E == RIGID
                else FiberSettings(model="bead-spring-ros2", young_modulus=E)
            )
            t0 = time.perf_counter()
            for th in thetas:
                for y0 in y0s:
                    r = simulate(field, st, FiberStart(th, y0, L))
                    rows.append({"E": E, **r.row()})
            print(f"L/l = {L}, E = {E:g} Pa: {time.perf_counter() - t0:.1f} s", flush=True)
    return pd.DataFrame(rows)


def _table(df: pd.DataFrame) -> pd.DataFrame:
    out = []
    for (L, E), g in df.groupby(["length", "E"], sort=True):
        ok = g[g.status == "ok"]
        passing = ok[ok["class"] != "Trapping"]
        row = {
            "L/l_obs": L,
            "E [MPa]": E / 1e6,
            "runs": len(g),
            "failed": int((g.status != "ok").sum()),
            "mean delta": passing.delta.mean(),
            "mean |delta|": passing.delta.abs().mean(),
        }
        for c in CLASSES:
            row[c] = float((ok["class"] == c).mean()) if len(ok) else np.nan
        row["median max kappa [1/um]"] = ok.max_curvature.median()
        row["min end-to-end"] = ok.min_end_to_end.min()
        row["max wrap [deg]"] = ok.max_wrap.max()
        row["max tension [pN]"] = ok.max_tension.max()
        out.append(row)
    return pd.DataFrame(out)


def _figure(table: pd.DataFrame, path: Path) -> None:
    with paper_style():
        fig, axes = subplots(1, 2, figsize=(7.0, 2.8), layout="constrained")
        ax, bx = axes
        for L, g in table.groupby("L/l_obs"):
            e = g["E [MPa]"].to_numpy()
            soft = np.isfinite(e)
            line = ax.plot(e[soft], g["mean |delta|"].to_numpy()[soft], "o-", label=f"L/l = {L}")
            ax.axhline(
                g["mean |delta|"].to_numpy()[~soft][0], color=line[0].get_color(), ls=":", lw=1
            )
            for c, mk in zip(CLASSES, "s^vD", strict=False):
                bx.plot(e[soft], g[c].to_numpy()[soft], marker=mk, ls="-" if L == 1.2 else "--",
                        label=f"{c}, L/l = {L}")  # fmt: skip
        ax.set_xscale("log")
        ax.set_xlabel("E [MPa]")
        ax.set_ylabel(r"mean $|\delta|$ (passing runs)")
        ax.set_title("dotted: rigid model", fontsize="small")
        ax.legend(fontsize="x-small")
        bx.set_xscale("log")
        bx.set_xlabel("E [MPa]")
        bx.set_ylabel("class fraction")
        bx.legend(fontsize="xx-small", ncol=2, loc="center left", bbox_to_anchor=(0.0, 0.7))
        save_figure(fig, path)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, default=4.0)
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--out", default="results/flexible")
    ap.add_argument("--lengths", type=float, nargs="+", default=[0.6, 1.2])
    ap.add_argument("--moduli", type=float, nargs="+", default=[26e6, 2e6, 0.5e6, 0.1e6, 0.03e6])
    ap.add_argument("--thetas", type=float, nargs="+", default=[-10.0, 0.0, 10.0])
    ap.add_argument("--y0s", type=int, default=10, help="y0/h values, evenly inside (0, 1)")
    ap.add_argument("--replot", action="store_true", help="table and figure from DIR/study.csv")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.replot:
        df = pd.read_csv(out / "study.csv", keep_default_na=False, na_values=["", "nan"])
    else:
        field, _ = get_flow_field(FlowSettings(dx=args.dx), args.cache)
        y0s = (np.arange(args.y0s) + 0.5) / args.y0s
        df = _runs(field, args.lengths, args.moduli, args.thetas, y0s)
        df.to_csv(out / "study.csv", index=False)
    table = _table(df)
    with pd.option_context("display.width", 200, "display.max_columns", 30):
        print(table.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    _figure(table, out / "stiffness_study.png")
    if args.replot:
        return
    soft = FiberSettings(
        model="bead-spring-ros2",
        young_modulus=min(args.moduli),
        record={"trajectories": True, "all_beads": True, "samples": 400},
    )
    r = simulate(field, soft, FiberStart(0.0, 0.45, max(args.lengths)))
    chronophotograph(r, field.geometry, out / "chrono_bending.png", snapshots=16)
    print(f"chronophotograph: {r.cls}, delta {r.delta:+.3f}, max wrap {r.max_wrap:.0f} deg, "
          f"min end-to-end {r.min_end_to_end:.3f}")  # fmt: skip
    print(f"wrote {out}/study.csv, stiffness_study.png, chrono_bending.png")


if __name__ == "__main__":
    main()
