"""The band-pass map: f(L), mode shares and trapped share against stiffness and array geometry.

Usage::

    python3 scripts/studies/flexible/bandpass_map.py run OUT [--geometries G0 G1 G2 G4]
        [--moduli ...]
        [--fractions ...] [--count N] [--rows R] [--spacing B] [--cores C]
        [--refine-runs M] [--contact rough|smooth] [--time-scale K] [--deadline S]
        [--tag TAG]
    python3 scripts/studies/flexible/bandpass_map.py more OUT [--geometries ...] [--moduli ...]
        [--target-se 0.05] [--trap-se 0.1] [--max-count 40] [--refine-tol 6]
        [--refine-count 12]
        [--rounds 3] [--cores C] [--deadline S] [--dry-run]
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
``--tag T`` adds to an existing map (other stiffnesses or lengths of the same
geometries) in folders ``<geometry>+T``, which the summary merges with the map.

``more`` makes an existing map precise, in rounds: every (E, L) whose mean f has a
standard error above ``--target-se`` gets the starts that bring it there (from its
measured spread and trapped share, at most ``--max-count`` runs per point), and every
f = 1/2 bracket wider than ``--refine-tol`` µm whose two lengths meet the target gets
its midpoint (the sort report's refinement on the merged runs). Each round's starts
are new seeded draws, stored beside the map as ``OUT/<geometry>+s<seed>``; ``summary``
merges them with the geometry's map.

``summary`` and ``converge``: :mod:`bandpass_tables`, which also lists the geometries.

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
from typing import Any

import pandas as pd
import yaml
from bandpass_tables import (
    BEAD_RADIUS,
    GEOMETRIES,
    converge,
    load_geometry,
    result_folders,
    summary,
)

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
            "output": str(Path(args.out) / folder_of(geom, args)),
            "cache_dir": args.cache,
        },
    }


def folder_of(geom: str, args: argparse.Namespace) -> str:
    """A geometry's results folder: ``G1``, or ``G1+<tag>`` for more of the same map
    (other stiffnesses or lengths), which the summary merges with it."""
    return f"{geom}+{args.tag}" if args.tag else geom


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


def _start(path: Path, cfg: dict, log_path: Path, env: dict) -> tuple[subprocess.Popen, Any]:
    """Write a sweep's config and start ``fibersweep run`` on it, logging to ``log_path``.

    The sweep gets its own process group, so that :func:`_stop` stops its workers with it.
    """
    path.write_text(yaml.safe_dump(cfg, sort_keys=False))
    log = open(log_path, "a")
    cmd = [sys.executable, "-m", "fibersweep", "run", str(path)]
    return subprocess.Popen(cmd, env=env, stdout=log, stderr=subprocess.STDOUT,
                            start_new_session=True), log  # fmt: skip


def _stop(live: list[tuple[subprocess.Popen, Any]]) -> None:
    """Stop the sweeps still running (their stored runs are kept) and close every log."""
    for p, _ in live:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGTERM)
    for p, log in live:
        p.wait()
        log.close()


def run(args: argparse.Namespace) -> None:
    """Write the configs, run every geometry at once, then summarise."""
    out = Path(args.out)
    (out / "configs").mkdir(parents=True, exist_ok=True)
    share = workers_of(args.geometries, args.fractions, args.cores)
    env = dict(os.environ, **{v: "1" for v in BLAS_ENV})
    procs = {}
    t0 = time.time()
    for geom in args.geometries:
        path = out / "configs" / f"{folder_of(geom, args)}.yaml"
        est = expected_cpu(geom, args.fractions) * len(args.moduli) * args.count
        print(f"fibersweep run {path} (workers {share[geom]}, expected ~{est:.0f} CPU s at "
              "b = a)", flush=True)  # fmt: skip
        procs[geom] = _start(path, config_of(geom, args, share[geom]), out / f"{geom}.log", env)
    while any(p.poll() is None for p, _ in procs.values()):
        if args.deadline and time.time() - t0 > args.deadline:
            print("deadline reached, stopping", flush=True)
            break
        time.sleep(2.0)
    _stop(list(procs.values()))
    for geom, (p, _) in procs.items():
        print(f"{geom}: exit {p.returncode}", flush=True)
    print(f"wall {time.time() - t0:.0f} s", flush=True)
    summary(args.out)


#: Extra-start counts a ``more`` round rounds up to, so that a round needs few configs.
MORE_BUCKETS = (4, 8, 12, 16, 24, 32, 48)


def more_plan(table: pd.DataFrame, runs: pd.DataFrame, args: argparse.Namespace) -> pd.DataFrame:
    """The next starts of one geometry: (E, length, count) rows.

    - **Precision.** A point whose f has a standard error above ``--target-se`` gets the
      starts that bring it there, n_moving (se / target)², and one more in ten, corrected
      for its trapped share, within ``--max-count`` runs in all. A point whose moving
      runs are too few for a standard error (under 2) gets ``--refine-count``. A point
      with trapped runs gets the runs that bring its trapped share's binomial error
      √(p(1 − p)/n) to ``--trap-se`` (0: no runs for the trapped share).
    - **Refinement.** Every bracket of f = 1/2 wider than ``--refine-tol`` [µm] whose two
      lengths are both within the target (the sort report's refinement,
      :func:`fibersweep.sorting.lengths.length_brackets`, on the merged runs) gets
      its midpoint with ``--refine-count`` starts.
    """
    from fibersweep.sorting.lengths import length_brackets

    rows = []
    pick = table[table["E"].isin(args.moduli)] if args.moduli else table
    for _, p in pick.iterrows():
        n, moving, se = int(p["runs"]), int(p["moving"]), float(p["fraction_se"])
        if n >= args.max_count:
            continue
        if moving < 2:
            want = args.refine_count if n < args.refine_count else 0
        elif se > args.target_se:
            need = math.ceil(1.1 * moving * (se / args.target_se) ** 2) - moving
            want = math.ceil(need / max(moving / n, 0.25))
        else:
            want = 0
        trapped = float(p["trapped"]) if "trapped" in p else 0.0
        if trapped > 0.0 and args.trap_se > 0.0:  # its binomial error, from p = 0.1 up
            q = min(max(trapped, 0.1), 0.9)
            want = max(want, math.ceil(q * (1.0 - q) / args.trap_se**2) - n)
        if want > 0:
            bucket = next((b for b in MORE_BUCKETS if b >= want), MORE_BUCKETS[-1])
            count = min(bucket, args.max_count - n)
            rows.append({"E": float(p["E"]), "length": float(p["length"]), "count": count})
    ok = table[table["fraction_se"] <= args.target_se]
    good = {(float(e), float(L)) for e, L in zip(ok["E"], ok["length"], strict=True)}
    points = runs.assign(group=runs["E"])
    for _, b in length_brackets(points, group="group").iterrows():
        e = float(b["group"])
        if args.moduli and e not in args.moduli:
            continue
        wide = float(b["hi"]) - float(b["lo"]) > args.refine_tol
        if wide and (e, float(b["lo"])) in good and (e, float(b["hi"])) in good:
            mid = round(0.5 * (float(b["lo"]) + float(b["hi"])), 1)
            rows.append({"E": e, "length": mid, "count": args.refine_count})
    return pd.DataFrame(rows, columns=["E", "length", "count"])


def _more_configs(out: Path, geom: str, plan: pd.DataFrame, base: dict, last_seed: int) -> list:
    """One config per (E, count) of a plan, in folder ``<geom>+s<seed>``, seeds after
    ``last_seed``."""
    todo = []
    for k, ((e, count), g) in enumerate(plan.groupby(["E", "count"], sort=True)):
        seed = last_seed + k + 1
        cfg = yaml.safe_load(yaml.safe_dump(base))
        cfg["sweep"]["fiber.young_modulus"] = [float(e)]
        cfg["sweep"]["length"] = sorted(float(L) for L in g["length"].unique())
        cfg["sweep"]["random"] = {"count": int(count), "seed": seed}
        cfg["sweep"].pop("refine", None)
        cfg["run"]["workers"] = 1
        cfg["run"]["output"] = str(out / f"{geom}+s{seed}")
        cost = float(count) * sum(COST_80 * (L / 80.0) ** COST_POWER for L in g["length"])
        todo.append((cost, geom, seed, cfg))
    return todo


def more(args: argparse.Namespace) -> None:
    """Rounds of more starts where f is not yet known to the target, and finer lengths
    at the edges, until nothing is left to do, ``--rounds`` are done or the deadline."""
    out = Path(args.out)
    env = dict(os.environ, **{v: "1" for v in BLAS_ENV})
    t0 = time.time()
    for rnd in range(1, args.rounds + 1):
        folders = result_folders(out)
        todo = []
        for geom in args.geometries or sorted(folders):
            if geom not in folders:
                print(f"{geom}: no results under {out}; run the map first", flush=True)
                continue
            table, runs, _ = load_geometry(folders[geom])
            plan = more_plan(table, runs, args)
            base = yaml.safe_load((out / "configs" / f"{geom}.yaml").read_text())
            tags = [f.name.partition("+")[2] for f in folders[geom]]
            used = [int(t[1:]) for t in tags if t[:1] == "s" and t[1:].isdigit()]
            got = _more_configs(out, geom, plan, base, max(used, default=0))
            runs_new = int(plan["count"].sum()) if len(plan) else 0
            print(f"round {rnd} {geom}: {len(plan)} points, {runs_new} runs in {len(got)} "
                  f"configs", flush=True)  # fmt: skip
            todo.extend(got)
            if args.dry_run and len(plan):
                print(plan.to_string(index=False), flush=True)
        if args.dry_run:
            print(f"expected ~{sum(t[0] for t in todo):.0f} CPU s at b = a", flush=True)
            return
        if not todo:
            break
        # the costliest first, so that the cores stay busy to the end
        todo.sort(key=lambda t: -t[0])
        live: list = []
        while todo or live:
            while todo and len(live) < args.cores:
                _, geom, seed, cfg = todo.pop(0)
                path = out / "configs" / f"{geom}+s{seed}.yaml"
                live.append(_start(path, cfg, out / f"{geom}.log", env))
            time.sleep(2.0)
            if args.deadline and time.time() - t0 > args.deadline:
                _stop(live)
                print(f"deadline reached in round {rnd}; stored runs kept", flush=True)
                summary(args.out)
                return
            for p, log in [x for x in live if x[0].poll() is not None]:
                log.close()
                live.remove((p, log))
        print(f"round {rnd} done at {time.time() - t0:.0f} s", flush=True)
    summary(args.out)


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
    r.add_argument("--tag", default="", help="add to an existing map: folders <geometry>+TAG")
    s = sub.add_parser("summary")
    s.add_argument("out")
    m = sub.add_parser("more")
    m.add_argument("out")
    m.add_argument("--geometries", nargs="+", choices=sorted(GEOMETRIES))
    m.add_argument("--moduli", type=float, nargs="+", help="only these E [Pa]")
    m.add_argument("--target-se", type=float, default=0.05, help="standard error of f")
    m.add_argument("--max-count", type=int, default=40, help="most runs per (E, L)")
    m.add_argument("--trap-se", type=float, default=0.1, help="standard error of the "
                   "trapped share (0: off)")  # fmt: skip
    m.add_argument("--refine-tol", type=float, default=6.0, help="edge bracket width [µm]")
    m.add_argument("--refine-count", type=int, default=12, help="starts per new length")
    m.add_argument("--rounds", type=int, default=3)
    m.add_argument("--cores", type=int, default=os.cpu_count() or 1)
    m.add_argument("--deadline", type=float, default=0.0, help="stop the runs after S s")
    m.add_argument("--dry-run", action="store_true", help="print the first round's plan only")
    c = sub.add_parser("converge")
    c.add_argument("outs", nargs="+")
    args = ap.parse_args()
    if args.cmd == "run":
        run(args)
    elif args.cmd == "more":
        more(args)
    elif args.cmd == "summary":
        summary(args.out)
    else:
        converge(args.outs)


if __name__ == "__main__":
    sys.exit(main())
