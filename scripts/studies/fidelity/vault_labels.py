"""The pole-vault a person sees: a labelled set of runs and every rule's agreement with it.

The set (``tests/data/vault_labels/``) is a set of starts from the contact band of
the default field (dx = 4 µm, sub-grid pillar, the settings of configs/quick.yaml),
each labelled by eye from its chronophotograph (Below / Above / Pole-vaulting /
Trapping) with a one-line reason. Steps:

``select RESULTS``
    Pick the starts from a sweep of the contact band, without looking at any
    rule's class: runs that touched the pillar, most of them runs whose head
    and tail swapped (where the pole-vaulting rules differ), some trapped runs
    (kernel stop) and some that touched without swapping, stratified over
    length, sign of θ0 and the side they passed. Writes the CSV with empty labels.
``simulate``
    Runs every start of the CSV on the config's field and stores the trajectory
    thinned as a sweep stores it (``fiber.record.samples``) in ``trajectories.npz``.
``pictures``
    Draws the stored trajectories as contact sheets of chronophotographs that
    show no class (the pictures the labels were made from).
``compare``
    Classifies every stored trajectory with every rule of the registry and prints
    each rule's agreement with the labels and its confusion table (rows: label,
    columns: rule), and the agreement of the corner rule over its two parameters.

Usage::

    python scripts/studies/fidelity/vault_labels.py select results/band-dx4 > starts.csv   # one-off
    python scripts/studies/fidelity/vault_labels.py simulate [--config configs/quick.yaml]
    python scripts/studies/fidelity/vault_labels.py pictures
    python scripts/studies/fidelity/vault_labels.py pictures --set holdout --out \
        docs/figures/vault-labels/holdout \
        --zoom --grid 2x3 --dpi 110 --snapshots 18
    python scripts/studies/fidelity/vault_labels.py compare
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from fibersweep.analysis.labelled import (
    confusion,
    load_trajectories,
    rule_labels,
    save_trajectories,
)
from fibersweep.analysis.trajectory import CLASSES, Trajectory

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from common import REPO  # noqa: E402

DATA = REPO / "tests" / "data" / "vault_labels"
LABELS = DATA / "labels.csv"
TRAJ = DATA / "trajectories.npz"
SHEETS = REPO / "docs" / "figures" / "vault-labels"


# --------------------------------------------------------------------------- storage


def field_and_settings(config: Path):
    """(FlowField, FiberSettings) of a config, the field from the cache (solved if absent)."""
    import os

    from fibersweep.config.loading import load_config
    from fibersweep.flow.cache import get_flow_field

    cfg = load_config(config)
    cache = os.environ.get("FIBERSWEEP_TEST_CACHE", cfg.run.cache_dir)
    field, _ = get_flow_field(cfg.flow, cache)
    return field, cfg.fiber


# --------------------------------------------------------------------------- select


def select(
    results: Path,
    n_swapped: int,
    n_trapped: int,
    n_other: int,
    seed: int,
    first_id: int = 1,
    name: str = "design",
) -> pd.DataFrame:
    """Starts to label from a sweep of the contact band; no rule's class is used.

    Swapped: |θ_f − θ0| > 90° (head and tail exchanged, whatever the rule says);
    trapped: the kernel stopped the run as trapped (the same for every rule).
    """
    from fibersweep.sweep.store import read_runs

    runs = read_runs(results)
    runs = runs[(runs["status"] == "ok") & runs["contact"].astype(bool)].copy()
    rng = np.random.default_rng(seed)
    trapped = runs["class"] == "Trapping"  # the trap rule, common to every pole-vault rule
    swapped = ~trapped & ((runs["theta_f"] - runs["theta0"]).abs() > 90.0)
    other = ~trapped & ~swapped & runs["y0"].between(0.15, 0.45)
    geo_mid = None
    picks = []
    for mask, n in ((swapped, n_swapped), (trapped, n_trapped), (other, n_other)):
        pool = runs[mask].copy()
        if geo_mid is None:
            geo_mid = float(np.median(runs["y_f"]))
        pool["stratum"] = list(
            zip(pool["length"], np.sign(pool["theta0"]), pool["y_f"] > geo_mid, strict=True)
        )
        pool = pool.iloc[rng.permutation(len(pool))]
        # round robin over strata: every length, sign of θ0 and side gets its share
        pool["rank"] = pool.groupby("stratum").cumcount()
        picks.append(pool.sort_values("rank", kind="stable").head(n))
    sel = pd.concat(picks).sort_values(["length", "theta0", "y0"]).reset_index(drop=True)
    sel = sel[["theta0", "y0", "length"]].round({"theta0": 3, "y0": 4, "length": 4})
    sel.insert(0, "set", name)
    sel.insert(0, "id", np.arange(first_id, first_id + len(sel)))
    return sel.assign(label="", reason="")


# --------------------------------------------------------------------------- simulate


def simulate_all(starts: pd.DataFrame, config: Path) -> tuple[list[int], list[Trajectory]]:
    """Run every start; the stored (thinned) trajectory of each."""
    from fibersweep.fiber.result import FiberStart
    from fibersweep.fiber.run import simulate

    field, fiber = field_and_settings(config)
    rec = fiber.record.model_copy(update={"trajectories": True})
    fiber = fiber.model_copy(update={"record": rec})
    ids, trajs = [], []
    for row in starts.itertuples():
        res = simulate(field, fiber, FiberStart(theta0=row.theta0, y0=row.y0, length=row.length))
        if res.trajectory is None:
            raise RuntimeError(f"start {row.id} recorded no trajectory ({res.status})")
        ids.append(int(row.id))
        trajs.append(res.trajectory)
    return ids, trajs


# --------------------------------------------------------------------------- pictures


def _panel(
    ax, tr: Trajectory, geometry, title: str, snapshots: int = 22, zoom: bool = False
) -> None:
    """Chronophotograph of one stored trajectory without any class on it.

    Fiber (head to tail segment) at ``snapshots`` regular times, coloured by time;
    filled dot: the head (the end that leads at the start); open dot: the tail;
    dashed: the centre of mass.
    """
    from matplotlib.collections import LineCollection
    from matplotlib.colors import Normalize
    from matplotlib.patches import Polygon

    xb, yb = geometry.base_center
    h = geometry.pillar_height
    length = float(np.hypot(*(tr.head[0] - tr.tail[0])))
    x_lo, _, x_hi, _ = geometry.shape.bounds
    xs = np.column_stack([tr.head[:, 0], tr.tail[:, 0]])
    margin = 0.6 * length + 15.0  # the interaction, little of the approach and departure
    near = (xs.max(axis=1) > x_lo - margin) & (xs.min(axis=1) < x_hi + margin)
    idx = np.flatnonzero(near) if near.sum() >= 2 else np.arange(len(tr.t))
    moving = tr.com_speed > 0.01 * float(np.max(tr.com_speed))
    if not moving[idx[-1]] and moving[idx].any():  # trapped: stop shortly after it stops
        last = idx[np.flatnonzero(moving[idx])[-1]]
        idx = idx[tr.t[idx] <= tr.t[last] + 0.1 * (tr.t[last] - tr.t[idx[0]])]
    t0, t1 = tr.t[idx[0]], tr.t[idx[-1]]
    picks = np.unique(np.searchsorted(tr.t, np.linspace(t0, t1, snapshots)).clip(0, len(tr.t) - 1))
    outline = (geometry.shape.outline() - [xb, yb]) / h
    ax.add_patch(Polygon(outline, closed=True, fc="0.85", ec="0.3", lw=0.8))
    segs = [(np.vstack([tr.tail[k], tr.head[k]]) - [xb, yb]) / h for k in picks]
    norm = Normalize(t0, t1)
    lc = LineCollection(segs, cmap="viridis", norm=norm, lw=1.6, capstyle="round")
    lc.set_array(tr.t[picks])
    ax.add_collection(lc)
    ax.scatter((tr.head[picks, 0] - xb) / h, (tr.head[picks, 1] - yb) / h, c=tr.t[picks],
               cmap="viridis", norm=norm, s=14, ec="k", lw=0.3, zorder=3)  # fmt: skip
    ax.scatter((tr.tail[picks, 0] - xb) / h, (tr.tail[picks, 1] - yb) / h, s=5, fc="w",
               ec="0.35", lw=0.4, zorder=3)  # fmt: skip
    sel = slice(idx[0], idx[-1] + 1)
    ax.plot((tr.x[sel] - xb) / h, (tr.y[sel] - yb) / h, "--", color="0.3", lw=0.6)
    pts = np.vstack([*segs, outline])
    if zoom:  # the pillar and one fiber length around it
        near = np.abs(pts[:, 0]) < 0.6 + length / h
        pts = pts[near] if near.sum() > 2 else pts
    ax.set_xlim(pts[:, 0].min() - 0.1, pts[:, 0].max() + 0.1)
    ax.set_ylim(min(pts[:, 1].min(), 0.0) - 0.1, pts[:, 1].max() + 0.1)
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=8)
    ax.tick_params(labelsize=6)


def contact_sheets(
    starts: pd.DataFrame,
    trajs: dict[int, Trajectory],
    geometry,
    out: Path,
    grid: tuple[int, int] = (3, 3),
    snapshots: int = 22,
    dpi: int = 90,
    zoom: bool = False,
) -> list[Path]:
    """Contact sheets of chronophotographs (``grid`` rows x columns), no class drawn."""
    from fibersweep.plots.style import paper_style, save_figure, subplots

    out.mkdir(parents=True, exist_ok=True)
    paths = []
    rows = list(starts.itertuples())
    per = grid[0] * grid[1]
    for s in range(0, len(rows), per):
        chunk = rows[s : s + per]
        with paper_style():
            size = (4.0 * grid[1], 2.8 * grid[0])
            fig, axes = subplots(*grid, figsize=size, layout="constrained", squeeze=False)
            for ax, row in zip(axes.ravel(), chunk, strict=False):
                title = f"#{row.id}: θ0 = {row.theta0:g}°, y0/h = {row.y0:g}, L/l = {row.length:g}"
                _panel(ax, trajs[int(row.id)], geometry, title, snapshots, zoom)
            for ax in axes.ravel()[len(chunk) :]:
                ax.set_axis_off()
            path = out / f"sheet-{s // per + 1:02d}.png"
            paths.append(save_figure(fig, path, dpi=dpi))
    return paths


# --------------------------------------------------------------------------- compare


def compare(starts: pd.DataFrame, config: Path) -> None:
    """Print each rule's agreement with the labels and its confusion table."""
    from fibersweep.analysis.classify import RULES

    field, fiber = field_and_settings(config)
    geometry, u = field.geometry, float(field.fluid.u_center)
    th = fiber.classify
    trajs = load_trajectories(TRAJ)
    done = starts[starts["label"].isin(CLASSES)]
    print(f"{len(done)} labelled runs ({(done['label'].value_counts()).to_dict()})")
    got = rule_labels(done, trajs, geometry, u, th, RULES)
    print("agreement per set (the default was chosen on 'design', confirmed on 'holdout'):")
    for name in RULES:
        cells = [
            f"{s} {int((got[name][m] == done['label'][m]).sum())}/{int(m.sum())}"
            for s in done["set"].unique()
            for m in [done["set"] == s]
        ]
        print(f"  {name:12s} " + ", ".join(cells))
    for name in RULES:
        agree = int((got[name] == done["label"]).sum())
        print(f"\n{name}: {agree} of {len(done)} agree ({agree / len(done):.1%})")
        print(confusion(done["label"], got[name]).to_string())
    if "corner" in RULES:
        print("\ncorner rule: agreement over corner_fraction (rows) x corner_turn (columns)")
        fracs, turns = (0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5), (60.0, 75.0, 90.0, 120.0)
        print("        " + " ".join(f"{t:6g}" for t in turns))
        for f in fracs:
            cells = []
            for t in turns:
                s = th.model_copy(update={"corner_fraction": f, "corner_turn": t})
                lab = rule_labels(done, trajs, geometry, u, s, ["corner"])["corner"]
                cells.append(int((lab == done["label"]).sum()))
            print(f"{f:6g}  " + " ".join(f"{c:6d}" for c in cells))
    wrong = done.assign(**{f"by {n}": got[n] for n in RULES})
    rule = th.rule
    miss = wrong[wrong[f"by {rule}"] != wrong["label"]]
    print(f"\nruns where the default rule ({rule}) disagrees with the label: {len(miss)}")
    with pd.option_context("display.width", 250, "display.max_colwidth", 90):
        print(miss.drop(columns=["reason"]).to_string(index=False))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("select", help="starts to label from a sweep folder (CSV to stdout)")
    s.add_argument("results", type=Path)
    s.add_argument("--swapped", type=int, default=72)
    s.add_argument("--trapped", type=int, default=12)
    s.add_argument("--other", type=int, default=16)
    s.add_argument("--seed", type=int, default=28)
    s.add_argument("--first-id", type=int, default=1)
    s.add_argument("--set", default="design", help="name of the set (design, holdout)")
    for name in ("simulate", "pictures", "compare"):
        p = sub.add_parser(name)
        p.add_argument("--config", type=Path, default=REPO / "configs" / "quick.yaml")
        p.add_argument("--labels", type=Path, default=LABELS)
        if name == "pictures":
            p.add_argument("--out", type=Path, default=SHEETS, help="folder of the sheets")
            p.add_argument("--ids", default="", help="only these label ids (comma-separated)")
            p.add_argument("--set", default="", help="only the runs of this set (design, holdout)")
            p.add_argument("--grid", default="3x3", help="panels per sheet, ROWSxCOLUMNS")
            p.add_argument("--snapshots", type=int, default=22, help="fibers drawn per run")
            p.add_argument("--dpi", type=int, default=90)
            p.add_argument("--zoom", action="store_true", help="crop to the pillar")
    args = ap.parse_args()
    if args.cmd == "select":
        sel = select(
            args.results, args.swapped, args.trapped, args.other, args.seed, args.first_id, args.set
        )
        sel.to_csv(sys.stdout, index=False)
        return
    starts = pd.read_csv(args.labels, keep_default_na=False)
    if args.cmd == "simulate":
        ids, trajs = simulate_all(starts, args.config)
        DATA.mkdir(parents=True, exist_ok=True)
        save_trajectories(TRAJ, ids, trajs)
        print(f"stored {len(ids)} trajectories in {TRAJ.relative_to(REPO)}")
    elif args.cmd == "pictures":
        field, _ = field_and_settings(args.config)
        if args.ids:
            starts = starts[starts["id"].isin([int(i) for i in args.ids.split(",")])]
        if args.set:
            starts = starts[starts["set"] == args.set]
        grid = tuple(int(v) for v in args.grid.split("x"))
        sheets = contact_sheets(
            starts,
            load_trajectories(TRAJ),
            field.geometry,
            args.out,
            grid,
            args.snapshots,
            args.dpi,
            args.zoom,
        )
        for p in sheets:
            print(f"wrote {p}")
    else:
        compare(starts, args.config)


if __name__ == "__main__":
    main()
