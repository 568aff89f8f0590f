"""The band-pass map's tables and figures, read from its results folders.

``summary`` reads every geometry's results with the sort report's own functions
(:func:`~fibersweep.sorting.report.relabel`, ``migration_table``,
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
- ``pairs.csv``: per pair of geometries that differ in one array parameter (G0/G4 and
  G1/G5: period_x; G1/G6: period_y, i.e. the gap), E and edge, the ratio of their edges
  with its standard error, and how far (in se) it lies from what the gap, the pillar,
  period_x, period_y or the bending length at the edge would give;
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
G5    20      120       80        60   G1 with a longer period_x only
G6    20      80        100       80   G1 with a longer period_y (a wider gap) only
====  ======  ========  ========  ====
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

GEOMETRIES = {
    "G0": {"pillar_size": 40.0, "period_x": 80.0, "period_y": 80.0},
    "G1": {"pillar_size": 20.0, "period_x": 80.0, "period_y": 80.0},
    "G2": {"pillar_size": 40.0, "period_x": 120.0, "period_y": 120.0},
    "G3": {"pillar_size": 80.0, "period_x": 120.0, "period_y": 120.0},
    "G4": {"pillar_size": 40.0, "period_x": 120.0, "period_y": 80.0},
    "G5": {"pillar_size": 20.0, "period_x": 120.0, "period_y": 80.0},
    "G6": {"pillar_size": 20.0, "period_x": 80.0, "period_y": 100.0},
}
BEAD_RADIUS = 2.0  # [µm]


def bending_length(e: float, length: float, mu: float, shear: float) -> float:
    """ℓ_b [µm] = (B c / 8πμγ̇)^(1/4), B = Eπa⁴/4 [pN µm²], c = −ln(ε² e), ε = a/L."""
    b = e * math.pi * BEAD_RADIUS**4 / 4.0
    c = -math.log((BEAD_RADIUS / length) ** 2 * math.e)
    return (b * c / (8.0 * math.pi * mu * shear)) ** 0.25


def load_geometry(folders: list[Path]) -> tuple[pd.DataFrame, pd.DataFrame, dict]:
    """(migration table with geometry columns, runs, config) of one geometry's results.

    ``folders``: the geometry's map folder and its ``more`` folders (``<geometry>+s<seed>``),
    whose runs are merged per (E, L): each folder's starts are independent seeded draws.
    A ``more`` folder with no runs stored yet (just started, or stopped before its
    first) is left out.
    """
    from fibersweep.analysis.modes import ModeSettings
    from fibersweep.results import load_array_results
    from fibersweep.sorting import report as sr
    from fibersweep.sweep.store import read_runs

    parts, meta0, cfg0 = [], None, None
    for folder in folders:
        if folder is not folders[0] and read_runs(folder).empty:
            print(f"{folder.name}: no runs stored yet; left out", flush=True)
            continue
        runs, meta, cfg = load_array_results(folder)
        trap = cfg["fiber"]["classify"]["trap_speed"]
        runs = sr.relabel(runs, meta, ModeSettings(), trap)
        runs["E"] = [float(meta[s]["values"]["fiber.young_modulus"]) for s in runs["setting"]]
        runs["folder"] = folder.name
        parts.append(runs.drop(columns=[c for c in runs if c.startswith("traj_")]))
        meta0, cfg0 = meta0 or meta, cfg0 or cfg
    runs = pd.concat(parts, ignore_index=True)
    moduli = sorted(runs["E"].unique())
    runs["setting"] = [moduli.index(e) for e in runs["E"]]
    runs["setting_label"] = [f"fiber.young_modulus={e:g}" for e in runs["E"]]
    table = sr.migration_table(runs)
    table["E"] = [moduli[int(s)] for s in table["setting"]]
    arr = meta0[0]["array"]
    mu = float(meta0[0]["flow"]["fluid"]["viscosity"])
    u = float(meta0[0]["u_center"])
    shear = u / arr["pillar_size"]
    table["geometry"] = geometry_of(folders[0])
    for k in ("pillar_size", "period_x", "period_y"):
        table[k] = float(arr[k])
    table["gap"] = table["period_y"] - table["pillar_size"]
    table["shear_rate"] = shear
    table["bending_length"] = [
        bending_length(e, L, mu, shear) for e, L in zip(table["E"], table["length"], strict=True)
    ]
    table["mu_bar"] = (table["length"] / table["bending_length"]) ** 4
    table["spacing"] = float(cfg0["fiber"].get("bead_spacing", 1.0))
    return table, runs, cfg0


def geometry_of(folder: Path) -> str:
    """The geometry a results folder belongs to: ``G1`` for ``G1`` and ``G1+s3``."""
    return folder.name.split("+")[0]


def result_folders(out: Path) -> dict[str, list[Path]]:
    """Every geometry's results folders under a map folder (sweeps with a manifest)."""
    found: dict[str, list[Path]] = {}
    for p in sorted(out.iterdir()):
        if p.is_dir() and (p / "manifest.json").exists():
            found.setdefault(geometry_of(p), []).append(p)
    return found


def edges_table(table: pd.DataFrame) -> pd.DataFrame:
    """Every f = 1/2 crossing of each (geometry, E), and which are a band's edges."""
    from fibersweep.sorting import report as sr

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


def _power_law(g: pd.DataFrame) -> dict | None:
    """L_edge ∝ E^β by weighted least squares in log–log; None under three points."""
    g = g[np.isfinite(g["se"]) & (g["se"] > 0)]
    if len(g) < 3:
        return None
    x = np.log(g["E"].to_numpy(float))
    y = np.log(g["critical"].to_numpy(float))
    w = 1.0 / (g["se"] / g["critical"]).to_numpy(float) ** 2
    a = np.column_stack([np.ones_like(x), x])
    cov = np.linalg.inv(a.T @ (a * w[:, None]))
    coef = cov @ (a.T @ (w * y))
    chi2 = float(np.sum(w * (y - a @ coef) ** 2))
    dof = len(x) - 2
    scale = max(1.0, chi2 / dof)  # inflate when the scatter exceeds the errors
    se = math.sqrt(cov[1, 1] * scale)
    # β against the bending length's 1/4 and against no dependence on E
    return {"points": len(g), "E_min": g["E"].min(), "E_max": g["E"].max(), "beta": coef[1],
            "beta_se": se, "chi2_dof": chi2 / dof, "z_quarter": (coef[1] - 0.25) / se,
            "z_zero": coef[1] / se}  # fmt: skip


def fits_table(edges: pd.DataFrame) -> pd.DataFrame:
    """Power laws in E per geometry and edge; spread over geometries per E and edge.

    ``power_law``: every lower (upper) edge of the geometry; ``power_law_band``: only
    those at stiffnesses where the geometry has a band (both edges), so that a
    high-pass filter's cut-off is not fitted with a band's edge.
    """
    rows = []
    e = edges[edges["edge"] != "other"]
    both = e.groupby(["geometry", "E"])["edge"].transform(lambda v: v.nunique() == 2)
    for kind, sub in (("power_law", e), ("power_law_band", e[both])):
        for (geom, edge), g in sub.groupby(["geometry", "edge"]):
            fit = _power_law(g)
            if fit is not None:
                rows.append({"kind": kind, "geometry": geom, "edge": edge, **fit})
    units = ["critical", "per_gap", "per_pillar", "per_period_x", "per_period_y",
             "per_bending_length"]  # fmt: skip
    for (modulus, edge), g in e.groupby(["E", "edge"]):
        if g["geometry"].nunique() < 3:
            continue
        r = {"kind": "collapse", "E": modulus, "edge": edge, "points": len(g)}
        for u in units:
            v = g[u].to_numpy(float)
            r[f"cv_{u}"] = float(np.std(v, ddof=1) / np.mean(v))
        rows.append(r)
    return pd.DataFrame(rows)


#: What one length scale predicts for the ratio of two arrays' edges: each maps
#: (geometry, one edge's row of edges.csv) to the scale [µm].
SCALES = {
    "gap": lambda g, r: g["period_y"] - g["pillar_size"],
    "pillar": lambda g, r: g["pillar_size"],
    "period_x": lambda g, r: g["period_x"],
    "period_y": lambda g, r: g["period_y"],
    # ℓ_b at the edge: the fiber's own scale, which the array changes only through γ̇
    "bending_length": lambda g, r: r["critical"] / r["per_bending_length"],
}


def pairs_table(edges: pd.DataFrame) -> pd.DataFrame:
    """Edges of two geometries that differ in one array parameter, as ratios.

    For geometries A and B whose pillar_size, period_x and period_y differ in exactly
    one, and an edge (lower or upper) both have at the same E: ratio = L_B / L_A with
    its standard error (propagated from both edges' se), and per candidate scale in
    :data:`SCALES` the ratio it predicts (scale_B / scale_A) and z = (ratio −
    prediction) / se. The scale whose |z| is small and the others' large is what sets
    the edge; a pair with every |z| small cannot tell. The same label (lower, upper)
    need not be the same feature in two arrays: read the pair with the curves.
    """
    keys = ("pillar_size", "period_x", "period_y")
    rows = []
    e = edges[edges["edge"] != "other"]
    geoms = sorted(e["geometry"].unique())
    for i, a in enumerate(geoms):
        for b in geoms[i + 1 :]:
            ga, gb = GEOMETRIES[a], GEOMETRIES[b]
            changed = [k for k in keys if ga[k] != gb[k]]
            if len(changed) != 1:
                continue
            m = e[e["geometry"] == a].merge(e[e["geometry"] == b], on=["E", "edge"],
                                            suffixes=("_a", "_b"))  # fmt: skip
            for _, r in m.iterrows():
                ratio = r["critical_b"] / r["critical_a"]
                se = ratio * math.hypot(r["se_a"] / r["critical_a"], r["se_b"] / r["critical_b"])
                row = {"a": a, "b": b, "changed": changed[0], "E": r["E"], "edge": r["edge"],
                       "edge_a": r["critical_a"], "edge_b": r["critical_b"], "ratio": ratio,
                       "ratio_se": se}  # fmt: skip
                ra = {"critical": r["critical_a"], "per_bending_length": r["per_bending_length_a"]}
                rb = {"critical": r["critical_b"], "per_bending_length": r["per_bending_length_b"]}
                for name, scale in SCALES.items():
                    pred = scale(gb, rb) / scale(ga, ra)
                    row[f"pred_{name}"] = pred
                    row[f"z_{name}"] = (ratio - pred) / se if se > 0 else math.nan
                rows.append(row)
    return pd.DataFrame(rows)


def figures(table: pd.DataFrame, edges: pd.DataFrame, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    geoms = sorted(table["geometry"].unique())
    moduli = sorted(table["E"].unique())
    # one colour per stiffness in every panel, softest dark
    colour = {e: plt.cm.viridis(i / max(1, len(moduli) - 1)) for i, e in enumerate(moduli)}
    for col, err, name, ylab in (
        ("fraction_mean", "fraction_se", "map-f.png", "mean f (moving runs)"),
        ("trapped", None, "map-trapped.png", "trapped share"),
    ):
        ncol = min(4, len(geoms))
        nrow = math.ceil(len(geoms) / ncol)
        fig, axes = plt.subplots(nrow, ncol, figsize=(4 * ncol + 1, 3.4 * nrow), squeeze=False,
                                 layout="constrained")  # fmt: skip
        for ax in axes.flat[len(geoms) :]:
            ax.set_visible(False)
        for ax, geom in zip(axes.flat, geoms, strict=False):
            g = table[table["geometry"] == geom]
            for e, ge in g.groupby("E"):
                ge = ge.sort_values("length")
                ax.errorbar(ge["length"], ge[col], yerr=None if err is None else ge[err],
                            marker="o", ms=3, capsize=2, color=colour[e],
                            label=f"{e / 1e3:.3g} kPa")  # fmt: skip
            first = g.iloc[0]
            for x, ls in ((first["gap"], ":"), (first["period_x"], "--")):
                ax.axvline(x, color="0.5", ls=ls, lw=0.8)
            ax.set_title(f"{geom}: pillar {first['pillar_size']:g}, "
                         f"λ {first['period_x']:g}×{first['period_y']:g}, gap {first['gap']:g}",
                         fontsize=8)  # fmt: skip
            ax.set_xlabel("L [µm] (dotted: gap, dashed: period_x)")
            ax.set_ylabel(ylab)
            ax.set_ylim(-0.05, 1.05)
        handles = [plt.Line2D([], [], color=colour[e], marker="o", ms=3) for e in moduli]
        fig.legend(handles, [f"{e / 1e3:.3g} kPa" for e in moduli], fontsize=7,
                   loc="outside right center")  # fmt: skip
        fig.savefig(out / name, dpi=100)  # under the docs' 300 KB per figure
        plt.close(fig)
    if len(edges):
        e = edges[edges["edge"] != "other"]
        fig, ax = plt.subplots(figsize=(6.4, 4.0), layout="constrained")
        for k, geom in enumerate(sorted(e["geometry"].unique())):
            for edge, style in (("lower", "o-"), ("upper", "s--")):
                g = e[(e["geometry"] == geom) & (e["edge"] == edge)].sort_values("E")
                if len(g):
                    ax.errorbar(g["E"], g["critical"], yerr=g["se"], fmt=style, ms=4,
                                capsize=2, color=f"C{k}", label=f"{geom} {edge}")  # fmt: skip
        # what an edge set by the bending length would do: L ∝ E^(1/4)
        e_lo, e_hi = float(e["E"].min()), float(e["E"].max())
        if e_hi > e_lo:
            mid = float(np.median(e["critical"]))
            x = np.array([e_lo, e_hi])
            ax.plot(x, mid * (x / math.sqrt(e_lo * e_hi)) ** 0.25, ":", color="0.4",
                    label="∝ E^(1/4) (bending length)")  # fmt: skip
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("E [Pa]")
        ax.set_ylabel("edge: f = 1/2 crossing [µm]")
        fig.legend(fontsize=6, loc="outside right center")
        fig.savefig(out / "map-edges.png", dpi=120)
        plt.close(fig)


def summary(out_dir: str) -> None:
    """Write map.csv/.parquet, edges.csv, fits.csv and the figures of a map folder."""
    out = Path(out_dir)
    tables, costs = [], []
    for geom, folders in result_folders(out).items():
        table, runs, _ = load_geometry(folders)
        tables.append(table)
        if "cpu_time" in runs:
            costs.append((geom, len(runs), float(runs["cpu_time"].sum()),
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
    edges = edges_table(table)
    edges.to_csv(out / "edges.csv", index=False)
    fits = fits_table(edges) if len(edges) else pd.DataFrame()
    fits.to_csv(out / "fits.csv", index=False)
    pairs = pairs_table(edges) if len(edges) else pd.DataFrame()
    pairs.to_csv(out / "pairs.csv", index=False)
    figures(table, edges, out)
    with pd.option_context("display.width", 200, "display.max_rows", 500,
                           "display.float_format", "{:.3g}".format):  # fmt: skip
        print(table[["geometry", "E", "length", "runs", "trapped", "fraction_mean",
                     "fraction_se", "mu_bar"]].to_string(index=False))  # fmt: skip
        if len(edges):
            print(edges[["geometry", "E", "edge", "critical", "se", "lo", "hi", "per_gap",
                         "per_period_x", "per_bending_length"]].to_string(index=False))  # fmt: skip
        if len(fits):
            print(fits.to_string(index=False))
        if len(pairs):
            cols = ["a", "b", "changed", "E", "edge", "edge_a", "edge_b", "ratio", "ratio_se"]
            print(pairs[cols + [f"z_{k}" for k in SCALES]].to_string(index=False))
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
