"""The band-pass map: f(L), mode shares and trapped share against stiffness and array geometry.

Usage::

    python3 scripts/studies/flexible/bandpass_map.py run OUT [--geometries G0 G1 G2 G4]
        [--moduli ...]
        [--fractions ...] [--count N] [--rows R] [--spacing B] [--cores C]
        [--refine-runs M] [--contact rough|smooth] [--time-scale K] [--deadline S]
    python3 scripts/studies/flexible/bandpass_map.py summary OUT
    python3 scripts/studies/flexible/bandpass_map.py converge OUT_A OUT_B [OUT_C ...]

``run`` writes one config per array geometry (``OUT/configs/<geometry>.yaml``: the
ROS2 bead-spring fiber of ``configs/array-flexible.yaml`` swept over
``fiber.young_modulus`` and the lengths ``--fractions`` × period_x, with
``--count`` seeded random starts per length and, with ``--refine-runs``, the sort
report's length refinement, ``sweep.refine``) and runs ``fibersweep run`` on every
geometry at once, ``--cores`` workers shared among them in proportion to their
expected cost (long fibers dominate: CPU ∝ L^2.7), BLAS pinned to one thread
per worker (the kernel's W = M J product is slower threaded: scripts/benchmarks/bench_spacing.py).
With ``--deadline`` [s] the runs still going are stopped then (the stored runs are
kept; a later ``run`` into the same OUT resumes them) and the summary is written from
what is stored. ``--time-scale K`` multiplies ``fiber.classify.trap_time`` (2 s) and
``fiber.step.t_max`` (30 s) by K: a longer observation before a slow fiber counts as
trapped (the trap time also sets the integrator's largest step, trap_time / 20).

``summary`` reads every geometry's results with the sort report's own functions
(:func:`~fibersweep.sweep.sort_report.relabel`, ``migration_table``,
``critical_table``) and writes to OUT:

- ``map.csv`` / ``map.parquet``: per (geometry, E, L) the runs, trapped share, mean f
  with its standard error, the mode shares, and the fiber's bending length
  ℓ_b = (B c / 8πμγ̇)^(1/4) and elasto-viscous number μ̄ = 8πμγ̇L⁴/(B c) = (L/ℓ_b)⁴,
  with B = Eπa⁴/4, c = −ln(ε² e), ε = a/L, γ̇ = U_center / pillar_size (docs/flexible.md);
- ``edges.csv``: every crossing of f = 1/2 with its standard error and bracket, the
  lower edge (first rising crossing) and upper edge (first falling one above it) of
  each band, each in µm and divided by gap, pillar, period_x, period_y and ℓ_b;
- ``fits.csv``: per geometry and edge, the power law L_edge ∝ E^β fitted by weighted
  least squares in log–log (weights from the edges' standard errors) with β's
  standard error; and per E and edge, the spread (coefficient of variation) of the
  edge over the geometries in each unit: the unit that collapses it best is what sets it;
- ``map-f.png``, ``map-trapped.png``, ``map-edges.png``: f(L) and the trapped share
  per geometry (one curve per E, ±1 standard error), the edges against E.

``converge`` compares ``edges.csv`` and the trapped shares of maps that differ only in
``--spacing``: per (geometry, E, edge) the change between two maps against the
combined standard error.

Geometries (triangles, shift 0.1, depth 40 µm; gap = period_y − pillar):

====  ======  ========  ========  ====
name  pillar  period_x  period_y  gap
====  ======  ========  ========  ====
G0    40      80        80        40   the shipped array (configs/array-flexible.yaml)
G1    20      80        80        60   smaller pillar, same periods
G2    40      120       120       80   same pillar, larger periods
G3    80      120       120       40   G0's gap, larger pillar and periods
G4    40      120       80        40   G0 with a longer period_x only
====  ======  ========  ========  ====

Defaults: G0, G1, G2, G4; five moduli 10–100 kPa; nine lengths 0.2–2.05 period_x;
six starts per length; b = a (``--spacing 0.5``, converged against b = a/2 at 10 kPa;
docs/validation/bandpass.md).
"""

from __future__ import annotations

import argparse
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

GEOMETRIES = {
    "G0": {"pillar_size": 40.0, "period_x": 80.0, "period_y": 80.0},
    "G1": {"pillar_size": 20.0, "period_x": 80.0, "period_y": 80.0},
    "G2": {"pillar_size": 40.0, "period_x": 120.0, "period_y": 120.0},
    "G3": {"pillar_size": 80.0, "period_x": 120.0, "period_y": 120.0},
    "G4": {"pillar_size": 40.0, "period_x": 120.0, "period_y": 80.0},
}
#: Default stiffnesses [Pa]: five, log-spaced over 10–100 kPa.
MODULI = [1.0e4, 1.78e4, 3.16e4, 5.62e4, 1.0e5]
#: Default lengths as fractions of period_x: from below the gap to beyond twice the period.
FRACTIONS = [0.2, 0.35, 0.5, 0.65, 0.8, 1.0, 1.25, 1.6, 2.05]
#: Default geometries: four that separate gap, pillar, period_x and period_y (G0 against
#: G4: period_x alone; against G1: pillar and gap at fixed periods; against G2: periods
#: and gap at a fixed pillar).
DEFAULT_GEOMETRIES = ["G0", "G1", "G2", "G4"]
#: CPU seconds of one 20-row run at b = a, L = 80 µm, and the power of L it grows with
#: (measured on the shipped array, 10–100 kPa: 1.5 s at 80 µm, 16 s at 176 µm, 58 s at
#: 264 µm), to share the workers among geometries by their expected cost.
COST_80, COST_POWER = 1.5, 2.7
BEAD_RADIUS = 2.0  # [µm]
BLAS_ENV = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def config_of(geom: str, args: argparse.Namespace, workers: int) -> dict:
    """The sweep config of one geometry (see the module docstring)."""
    g = GEOMETRIES[geom]
    px = g["period_x"]
    lengths = sorted({round(f * px, 1) for f in args.fractions})
    fiber = {
        "model": "bead-spring",
        "integrator": "ros2",
        "bead_radius": BEAD_RADIUS,
        "array_rows": args.rows,
        "record": {"samples": 200, "all_beads": False},
        "contact": {"pillar": args.contact},
        "classify": {"trap_time": 2.0 * args.time_scale},
        "step": {"t_max": 30.0 * args.time_scale},
    }
    if args.spacing != 1.0:
        fiber["bead_spacing"] = args.spacing
    sweep = {
        "fiber.young_modulus": [float(e) for e in args.moduli],
        "length": lengths,
        "theta0": [-10.0, 10.0],
        "y0": [0.0, 1.0],
        "random": {"count": args.count, "seed": args.seed},
    }
    if args.refine_runs > 0:
        sweep["refine"] = {
            "axes": ["length"],
            "tolerance": {"length": args.refine_tol},
            "max_runs": args.refine_runs,
        }
    return {
        "flow": {
            "dx": 2.0,
            "array": {"pillar_shape": "triangle", "shift": 0.1, "depth": 40.0, **g},
        },
        "fiber": fiber,
        "sweep": sweep,
        "run": {
            "workers": workers,
            "output": str(Path(args.out) / geom),
            "cache_dir": args.cache,
        },
    }


def expected_cpu(geom: str, fractions: list[float]) -> float:
    """Expected CPU seconds of one start at every length of a geometry (b = a)."""
    px = GEOMETRIES[geom]["period_x"]
    return sum(COST_80 * (f * px / 80.0) ** COST_POWER for f in fractions)


def workers_of(geoms: list[str], fractions: list[float], cores: int) -> dict[str, int]:
    """Workers per geometry, at least one each, the rest in proportion to expected cost."""
    cost = {g: expected_cpu(g, fractions) for g in geoms}
    total = sum(cost.values())
    share = {g: max(1, int(cores * cost[g] / total)) for g in geoms}
    while sum(share.values()) < cores:  # hand out what rounding left to the costliest
        g = max(geoms, key=lambda g: cost[g] / share[g])
        share[g] += 1
    return share


def run(args: argparse.Namespace) -> None:
    """Write the configs, run every geometry at once, then summarise."""
    out = Path(args.out)
    (out / "configs").mkdir(parents=True, exist_ok=True)
    share = workers_of(args.geometries, args.fractions, args.cores)
    env = dict(os.environ, **{v: "1" for v in BLAS_ENV})
    procs = {}
    t0 = time.time()
    for geom in args.geometries:
        path = out / "configs" / f"{geom}.yaml"
        cfg = config_of(geom, args, share[geom])
        path.write_text(yaml.safe_dump(cfg, sort_keys=False))
        log = open(out / f"{geom}.log", "a")
        cmd = [sys.executable, "-m", "fibersweep", "run", str(path)]
        est = expected_cpu(geom, args.fractions) * len(args.moduli) * args.count
        print(" ".join(cmd), f"(workers {share[geom]}, expected ~{est:.0f} CPU s at b = a)",
              flush=True)  # fmt: skip
        # own process group, so that the deadline stops the sweep's workers with it
        proc = subprocess.Popen(cmd, env=env, stdout=log, stderr=subprocess.STDOUT,
                                start_new_session=True)  # fmt: skip
        procs[geom] = (proc, log)
    while any(p.poll() is None for p, _ in procs.values()):
        if args.deadline and time.time() - t0 > args.deadline:
            for geom, (p, _) in procs.items():
                if p.poll() is None:
                    print(f"{geom}: deadline reached, stopping", flush=True)
                    os.killpg(p.pid, signal.SIGTERM)
            for p, _ in procs.values():
                p.wait()
            break
        time.sleep(2.0)
    for geom, (p, log) in procs.items():
        log.close()
        print(f"{geom}: exit {p.returncode}", flush=True)
    print(f"wall {time.time() - t0:.0f} s", flush=True)
    summary(args.out)


def bending_length(e: float, length: float, mu: float, shear: float) -> float:
    """ℓ_b [µm] = (B c / 8πμγ̇)^(1/4), B = Eπa⁴/4 [pN µm²], c = −ln(ε² e), ε = a/L."""
    b = e * math.pi * BEAD_RADIUS**4 / 4.0
    c = -math.log((BEAD_RADIUS / length) ** 2 * math.e)
    return (b * c / (8.0 * math.pi * mu * shear)) ** 0.25


def _load(folder: Path) -> tuple[pd.DataFrame, pd.DataFrame, dict]:
    """(migration table with geometry columns, runs, config) of one geometry's results."""
    from fibersweep.analysis.modes import ModeSettings
    from fibersweep.sweep import sort_report as sr

    runs, meta, cfg = sr.load_array_results(folder)
    runs = sr.relabel(runs, meta, ModeSettings(), cfg["fiber"]["classify"]["trap_speed"])
    table = sr.migration_table(runs)
    table["E"] = [float(meta[s]["values"]["fiber.young_modulus"]) for s in table["setting"]]
    arr = meta[0]["array"]
    mu = float(meta[0]["flow"]["fluid"]["viscosity"])
    u = float(meta[0]["u_center"])
    shear = u / arr["pillar_size"]
    table["geometry"] = folder.name
    for k in ("pillar_size", "period_x", "period_y"):
        table[k] = float(arr[k])
    table["gap"] = table["period_y"] - table["pillar_size"]
    table["shear_rate"] = shear
    table["bending_length"] = [
        bending_length(e, L, mu, shear) for e, L in zip(table["E"], table["length"], strict=True)
    ]
    table["mu_bar"] = (table["length"] / table["bending_length"]) ** 4
    table["spacing"] = float(cfg["fiber"].get("bead_spacing", 1.0))
    return table, runs, cfg


def _edges(table: pd.DataFrame) -> pd.DataFrame:
    """Every f = 1/2 crossing of each (geometry, E), and which are a band's edges."""
    from fibersweep.sweep import sort_report as sr

    rows = []
    for (geom, e), g in table.groupby(["geometry", "E"], sort=True):
        crit = sr.critical_table(g.assign(setting=0)).sort_values("critical")
        lower = crit[crit["rising"]]
        lo = float(lower["critical"].iloc[0]) if len(lower) else math.nan
        upper = crit[~crit["rising"] & (crit["critical"] > (lo if math.isfinite(lo) else -1))]
        up = float(upper["critical"].iloc[0]) if len(upper) else math.nan
        first = g.iloc[0]
        for _, c in crit.iterrows():
            edge = "lower" if c["critical"] == lo else "upper" if c["critical"] == up else "other"
            lb = bending_length(e, c["critical"], 0.34, float(first["shear_rate"]))
            rows.append(
                {
                    "geometry": geom,
                    "E": e,
                    "edge": edge,
                    "critical": c["critical"],
                    "se": c["se"],
                    "lo": c["lo"],
                    "hi": c["hi"],
                    "rising": c["rising"],
                    "per_gap": c["critical"] / first["gap"],
                    "per_pillar": c["critical"] / first["pillar_size"],
                    "per_period_x": c["critical"] / first["period_x"],
                    "per_period_y": c["critical"] / first["period_y"],
                    "per_bending_length": c["critical"] / lb,
                }
            )
    return pd.DataFrame(rows)


def _fits(edges: pd.DataFrame) -> pd.DataFrame:
    """Power laws in E per geometry and edge; spread over geometries per E and edge."""
    rows = []
    for (geom, edge), g in edges[edges["edge"] != "other"].groupby(["geometry", "edge"]):
        g = g[np.isfinite(g["se"]) & (g["se"] > 0)]
        if len(g) < 3:
            continue
        x = np.log(g["E"].to_numpy(float))
        y = np.log(g["critical"].to_numpy(float))
        sy = (g["se"] / g["critical"]).to_numpy(float)
        w = 1.0 / sy**2
        a = np.column_stack([np.ones_like(x), x])
        cov = np.linalg.inv(a.T @ (a * w[:, None]))
        coef = cov @ (a.T @ (w * y))
        chi2 = float(np.sum(w * (y - a @ coef) ** 2))
        dof = len(x) - 2
        scale = max(1.0, chi2 / dof) if dof > 0 else 1.0  # inflate when scatter exceeds errors
        rows.append({"kind": "power_law", "geometry": geom, "edge": edge, "points": len(g),
                     "beta": coef[1], "beta_se": math.sqrt(cov[1, 1] * scale),
                     "chi2_dof": chi2 / dof if dof > 0 else math.nan})  # fmt: skip
    units = ["critical", "per_gap", "per_pillar", "per_period_x", "per_period_y",
             "per_bending_length"]  # fmt: skip
    for (e, edge), g in edges[edges["edge"] != "other"].groupby(["E", "edge"]):
        if g["geometry"].nunique() < 3:
            continue
        r = {"kind": "collapse", "E": e, "edge": edge, "points": len(g)}
        for u in units:
            v = g[u].to_numpy(float)
            r[f"cv_{u}"] = float(np.std(v, ddof=1) / np.mean(v))
        rows.append(r)
    return pd.DataFrame(rows)


def _figures(table: pd.DataFrame, edges: pd.DataFrame, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    geoms = sorted(table["geometry"].unique())
    for col, err, name, ylab in (
        ("fraction_mean", "fraction_se", "map-f.png", "mean f (moving runs)"),
        ("trapped", None, "map-trapped.png", "trapped share"),
    ):
        fig, axes = plt.subplots(1, len(geoms), figsize=(4 * len(geoms), 3.4), squeeze=False)
        for ax, geom in zip(axes[0], geoms, strict=True):
            g = table[table["geometry"] == geom]
            for e, ge in g.groupby("E"):
                ge = ge.sort_values("length")
                ax.errorbar(ge["length"], ge[col], yerr=None if err is None else ge[err],
                            marker="o", ms=3, capsize=2, label=f"{e / 1e3:.3g} kPa")  # fmt: skip
            first = g.iloc[0]
            for x, ls in ((first["gap"], ":"), (first["period_x"], "--")):
                ax.axvline(x, color="0.5", ls=ls, lw=0.8)
            ax.set_title(f"{geom}: pillar {first['pillar_size']:g}, "
                         f"λ {first['period_x']:g}×{first['period_y']:g}, gap {first['gap']:g}",
                         fontsize=8)  # fmt: skip
            ax.set_xlabel("L [µm] (dotted: gap, dashed: period_x)")
            ax.set_ylabel(ylab)
            ax.set_ylim(-0.05, 1.05)
        axes[0][0].legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(out / name, dpi=120)
        plt.close(fig)
    if len(edges):
        fig, ax = plt.subplots(figsize=(5, 3.6))
        for (geom, edge), g in edges[edges["edge"] != "other"].groupby(["geometry", "edge"]):
            ax.errorbar(g["E"], g["critical"], yerr=g["se"], marker="o" if edge == "lower"
                        else "s", ms=4, capsize=2, label=f"{geom} {edge}")  # fmt: skip
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("E [Pa]")
        ax.set_ylabel("band edge [µm]")
        ax.legend(fontsize=6)
        fig.tight_layout()
        fig.savefig(out / "map-edges.png", dpi=120)
        plt.close(fig)


def summary(out_dir: str) -> None:
    """Write map.csv/.parquet, edges.csv, fits.csv and the figures of a map folder."""
    out = Path(out_dir)
    tables, costs = [], []
    for folder in sorted(p for p in out.iterdir() if p.is_dir() and (p / "manifest.json").exists()):
        table, runs, _ = _load(folder)
        tables.append(table)
        if "cpu_time" in runs:
            costs.append((folder.name, len(runs), float(runs["cpu_time"].sum()),
                          float(runs["cpu_time"].max())))  # fmt: skip
    if not tables:
        print(f"{out}: no results yet")
        return
    table = pd.concat(tables, ignore_index=True)
    cols = ["geometry", "pillar_size", "period_x", "period_y", "gap", "E", "length", "runs",
            "moving", "trapped", "fraction_mean", "fraction_se", "fraction_std", "angle_mean",
            "zigzag", "displacement", "wrap-and-jump", "mixed", "bending_length", "mu_bar",
            "shear_rate", "spacing"]  # fmt: skip
    table = table[[c for c in cols if c in table]]
    table.to_csv(out / "map.csv", index=False)
    table.to_parquet(out / "map.parquet", index=False)
    edges = _edges(table)
    edges.to_csv(out / "edges.csv", index=False)
    fits = _fits(edges) if len(edges) else pd.DataFrame()
    fits.to_csv(out / "fits.csv", index=False)
    _figures(table, edges, out)
    with pd.option_context("display.width", 200, "display.max_rows", 500,
                           "display.float_format", "{:.3g}".format):  # fmt: skip
        print(table[["geometry", "E", "length", "runs", "trapped", "fraction_mean",
                     "fraction_se", "mu_bar"]].to_string(index=False))  # fmt: skip
        if len(edges):
            print(edges[["geometry", "E", "edge", "critical", "se", "lo", "hi", "per_gap",
                         "per_period_x", "per_bending_length"]].to_string(index=False))  # fmt: skip
        if len(fits):
            print(fits.to_string(index=False))
    se = table["fraction_se"]
    print(f"points {len(table)}; f standard error: median {se.median():.3f}, largest "
          f"{se.max():.3f}; points with se > 0.05: {int((se > 0.05).sum())}")  # fmt: skip
    for geom, n, cpu, worst in costs:
        print(f"{geom}: {n} runs, CPU {cpu:.0f} s ({cpu / max(n, 1):.2f} s/run, largest "
              f"{worst:.1f} s)")  # fmt: skip
    if costs:
        print(f"total CPU {sum(c[2] for c in costs):.0f} s over {sum(c[1] for c in costs)} runs")


def converge(dirs: list[str]) -> None:
    """Edges and trapped shares of maps that differ in bead spacing, side by side."""
    maps = []
    for d in dirs:
        if not (Path(d) / "map.csv").exists():
            print(f"{d}: no summary (no runs stored); left out")
            continue
        e = (
            pd.read_csv(Path(d) / "edges.csv")
            if (Path(d) / "edges.csv").stat().st_size > 1
            else pd.DataFrame(columns=["geometry", "E", "edge", "critical", "se"])
        )
        t = pd.read_csv(Path(d) / "map.csv")
        sp = float(t["spacing"].iloc[0])
        maps.append((sp, e[e["edge"] != "other"], t))
    maps.sort(key=lambda m: -m[0])
    key = ["geometry", "E", "edge"]
    for (s1, e1, t1), (s2, e2, t2) in zip(maps, maps[1:], strict=False):
        m = e1.merge(e2, on=key, suffixes=("_1", "_2"))
        m["change"] = m["critical_2"] - m["critical_1"]
        m["se_comb"] = np.hypot(m["se_1"], m["se_2"])
        m["converged"] = m["change"].abs() < m["se_comb"]
        print(f"b/2a {s1:g} -> {s2:g}: band edges [µm]")
        print(m[key + ["critical_1", "critical_2", "change", "se_comb", "converged"]]
              .to_string(index=False))  # fmt: skip
        tk = ["geometry", "E", "length"]
        tt = t1.merge(t2, on=tk, suffixes=("_1", "_2"))
        n = np.minimum(tt["runs_1"], tt["runs_2"])
        p = 0.5 * (tt["trapped_1"] + tt["trapped_2"])
        tt["se_trap"] = np.sqrt(np.maximum(p * (1 - p), 0.25 / n) * 2 / n)
        tt["d_trapped"] = tt["trapped_2"] - tt["trapped_1"]
        tt["d_f"] = tt["fraction_mean_2"] - tt["fraction_mean_1"]
        tt["se_f"] = np.hypot(tt["fraction_se_1"], tt["fraction_se_2"])
        print(tt[tk + ["trapped_1", "trapped_2", "d_trapped", "se_trap", "fraction_mean_1",
                       "fraction_mean_2", "d_f", "se_f"]].to_string(index=False))  # fmt: skip
        n_t = int((tt["d_trapped"].abs() < 2 * tt["se_trap"]).sum())
        n_f = int((tt["d_f"].abs() < 2 * tt["se_f"]).sum())
        print(f"trapped share: |change| < 2 se at {n_t} of {len(tt)} points; "
              f"f: |change| < 2 se at {n_f} of {int(tt['se_f'].notna().sum())}")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("out")
    r.add_argument("--geometries", nargs="+", default=DEFAULT_GEOMETRIES,
                   choices=sorted(GEOMETRIES))  # fmt: skip
    r.add_argument("--moduli", type=float, nargs="+", default=MODULI)
    r.add_argument("--fractions", type=float, nargs="+", default=FRACTIONS)
    r.add_argument("--count", type=int, default=6, help="random starts per length")
    r.add_argument("--seed", type=int, default=0)
    r.add_argument("--rows", type=int, default=20)
    r.add_argument("--spacing", type=float, default=0.5, help="fiber.bead_spacing (b/2a)")
    r.add_argument("--contact", choices=["rough", "smooth"], default="rough")
    r.add_argument("--time-scale", type=float, default=1.0)
    r.add_argument("--refine-runs", type=int, default=0, help="sweep.refine max_runs (0: off)")
    r.add_argument("--refine-tol", type=float, default=4.0, help="refined bracket width [µm]")
    r.add_argument("--cores", type=int, default=os.cpu_count() or 1)
    r.add_argument("--cache", default=".fibersweep-cache")
    r.add_argument("--deadline", type=float, default=0.0, help="stop the runs after S s")
    s = sub.add_parser("summary")
    s.add_argument("out")
    c = sub.add_parser("converge")
    c.add_argument("outs", nargs="+")
    args = ap.parse_args()
    if args.cmd == "run":
        run(args)
    elif args.cmd == "summary":
        summary(args.out)
    else:
        converge(args.outs)


if __name__ == "__main__":
    sys.exit(main())
