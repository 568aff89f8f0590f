#!/usr/bin/env python3
"""Sweep throughput, measured in one run so the numbers compare (the machine is shared).

Reports, for the same tasks on the same cached flow field:
  * local pool, 1 worker and 2 workers: runs/s in steady state and the 1 -> 2 speed-up;
  * Dask LocalCluster, 2 workers, once per --chunk-size (runs per Dask task; default 1 and
    auto): runs/s and its overhead per run against the local pool;
  * start-up cost (spawn + open the field + Numba warm-up) of each executor;
  * an estimate of configs/paper.yaml (flow field excluded) from the measured per-run
    times of a random sample of the paper's own sweep points (--paper-sample 0: skipped).

Steady throughput is runs / (end of the last run - start of the first), from the workers'
own timestamps: start-up is left out, gaps between runs and an idle tail at the end count.
(Timestamps taken as results reach the client would favour chunks, whose runs arrive in
bursts.)

With ``--against TREE`` (a checkout of another version, e.g. the commit before a
refactor), it instead times this tree and TREE alternately, ``--rounds`` times
each after one untimed warm-up (Numba caches), in one run so the machine's load
hits both alike, and prints the ratios of the medians (this / other):
  * a whole sweep, ``fibersweep run CONFIG`` from an empty folder, the command's wall
    time (interpreter and pool start-up included; the flow field is cached);
  * the discrepancy check of each tree's own scripts/tools/snapshot_discrepancy.py
    (``scripts/snapshot_discrepancy.py`` in a tree of the former layout; ``--disc-n``
    fibers), timed by its own report (the workflow alone, synthesis excluded).

Usage:  python scripts/benchmarks/bench_sweep.py [--config configs/quick.yaml] [--paper-sample 60]
                                      [--chunk-size 1 --chunk-size auto]
        python scripts/benchmarks/bench_sweep.py --against /tmp/before [--rounds 3] [--disc-n 30]
                                      [--cache DIR] [--only sweep|discrepancy]
"""

from __future__ import annotations

import argparse
import logging
import os
import random
import re
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

from fibersweep.config import load_config
from fibersweep.sweep.executors import make_executor
from fibersweep.sweep.fields import flow_field_for
from fibersweep.sweep.plan import make_tasks
from fibersweep.sweep.worker import WorkerSpec, init_worker, run_task

#: Arguments of a run of seconds (scripts/benchmarks/run.py --smoke): the script runs
#: end to end, its numbers mean nothing.
SMOKE = ["--repeat", "1", "--paper-sample", "0", "--skip-dask"]

log = logging.getLogger("bench_sweep")


def parse_chunk_size(text: str) -> int | None:
    """'auto' -> None (the executor chooses), else a positive number of runs per Dask task."""
    if text == "auto":
        return None
    size = int(text)
    if size < 1:
        raise argparse.ArgumentTypeError(f"chunk size must be >= 1 or 'auto', got {text}")
    return size


def measure(name: str, workers: int, tasks, spec, chunk_size: int | None = None) -> dict:
    """Run ``tasks``; steady throughput from the workers' own run start and end times."""
    kw = {"chunk_size": chunk_size} if name == "dask" else {}
    ex = make_executor(name, workers, **kw)
    t0 = time.time()
    starts, ends, run_s, cpu_s = [], [], [], []
    for oc in ex.run(run_task, tasks, init_worker, (spec, ex.parent_handles_ctrl_c)):
        row = oc.value["row"] if oc.value else {}
        if oc.error or row.get("status") != "ok":
            log.warning("%s: %s", oc.key, oc.error or row.get("reason"))
        if not row:
            continue
        run_s.append(float(row["wall_time"]))
        cpu_s.append(float(row.get("cpu_time") or 0.0))
        ends.append(float(row["finished_at"]))
        starts.append(ends[-1] - run_s[-1])
    total = time.time() - t0
    label = f"{name} x{workers}"
    if name == "dask":
        label += f" c{chunk_size or 'auto'}"
    return {
        "name": label,
        "workers": workers,
        "n": len(ends),
        "tasks": getattr(ex, "chunks_submitted", len(ends)),
        "total_s": total,
        "startup_s": min(starts) - t0,
        "steady_rps": len(ends) / (max(ends) - min(starts)),
        "mean_run_s": statistics.fmean(run_s),
        "mean_cpu_s": statistics.fmean(cpu_s),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="configs/quick.yaml")
    ap.add_argument("--paper", default="configs/paper.yaml")
    ap.add_argument("--repeat", type=int, default=2, help="copies of the sweep's tasks")
    ap.add_argument("--paper-sample", type=int, default=60)
    ap.add_argument("--skip-dask", action="store_true")
    ap.add_argument(
        "--chunk-size",
        type=parse_chunk_size,
        action="append",
        help="runs per Dask task, or 'auto' (repeat to compare; default: 1 and auto)",
    )
    ap.add_argument("--against", type=Path, help="another checkout: before/after ratios")
    ap.add_argument("--rounds", type=int, default=3, help="timed runs per tree (--against)")
    ap.add_argument("--disc-n", type=int, default=30, help="fibers of the discrepancy check")
    ap.add_argument("--cache", default=".fibersweep-cache", help="flow cache (--against)")
    ap.add_argument("--only", choices=("sweep", "discrepancy"), help="time one of the two")
    args = ap.parse_args()
    if args.against is not None:
        compare_trees(args)
        return
    chunk_sizes = args.chunk_size or [1, None]
    logging.basicConfig(level=logging.WARNING)

    cfg = load_config(args.config)
    field, info = flow_field_for(cfg)
    spec = WorkerSpec(
        flow_json=cfg.flow.model_dump_json(),
        field_path=str(Path(info.path).resolve()),
        flow_key=info.key,
        fiber_json=cfg.fiber.model_dump_json(),
    )
    base = make_tasks(cfg, info.key)
    # Copies with distinct keys (Dask keys must be unique); same physics.
    tasks = [replace(t, key=f"{t.key}-{k}") for k in range(args.repeat) for t in base]
    print(f"{args.config}: {len(tasks)} runs per executor, field dx = {cfg.flow.dx} µm")

    load_before = os.getloadavg()[0]
    results = [measure("local", 1, tasks, spec), measure("local", 2, tasks, spec)]
    if not args.skip_dask:
        results += [measure("dask", 2, tasks, spec, c) for c in chunk_sizes]
    print(f"load average before: {load_before:.2f} (2 cores; > 2 means a shared machine)")
    print(
        f"{'executor':<16}{'runs':>6}{'tasks':>7}{'total s':>10}{'start-up s':>12}{'runs/s':>9}"
        f"{'wall/run':>10}{'cpu/run':>9}{'cpu use':>9}"
    )
    for r in results:
        # cpu use: fraction of each worker's time spent computing runs (1.0 = a free core each)
        use = r["steady_rps"] * r["mean_cpu_s"] / r["workers"]
        print(
            f"{r['name']:<16}{r['n']:>6}{r['tasks']:>7}{r['total_s']:>10.2f}"
            f"{r['startup_s']:>12.2f}{r['steady_rps']:>9.2f}{r['mean_run_s']:>10.3f}"
            f"{r['mean_cpu_s']:>9.3f}{use:>9.2f}"
        )
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    l1, l2 = results[0], results[1]
    print(
        f"scaling 1 -> 2 workers (steady runs/s ratio): {l2['steady_rps'] / l1['steady_rps']:.2f}"
    )
    per_run_local = 1.0 / l2["steady_rps"]
    for d in results[2:]:
        per_run_dask = 1.0 / d["steady_rps"]
        print(
            f"Dask overhead per run vs local pool (2 workers, steady state), {d['name']}: "
            f"{100 * (per_run_dask - per_run_local) / per_run_local:+.1f} % "
            f"({1e3 * (per_run_dask - per_run_local):+.1f} ms per run, {d['tasks']} Dask tasks)"
        )
    if args.paper_sample > 0:
        paper_estimate(args.paper, cfg, spec, info, args.paper_sample)


def paper_estimate(paper_path: str, cfg, spec, info, n_sample: int) -> None:
    """configs/paper.yaml: time a random sample of its own points with 2 workers."""
    paper = load_config(paper_path)
    tasks = make_tasks(paper, info.key)
    rng = random.Random(0)
    sample = rng.sample(tasks, min(n_sample, len(tasks)))
    pspec = replace(spec, fiber_json=paper.fiber.model_dump_json())
    p = measure("local", 2, sample, pspec)
    est = len(tasks) / p["steady_rps"]
    ideal = len(tasks) * p["mean_cpu_s"] / 2.0
    print(
        f"{paper_path}: {len(tasks)} runs; sample of {p['n']} at dx = {cfg.flow.dx} µm: "
        f"{p['mean_run_s']:.3f} s wall, {p['mean_cpu_s']:.3f} s CPU per run, "
        f"{p['steady_rps']:.2f} runs/s on 2 workers -> estimate {est / 60:.1f} min here, "
        f"{ideal / 60:.1f} min on 2 free cores (+ {p['startup_s']:.0f} s start-up), field excluded"
    )
    if paper.flow.dx != cfg.flow.dx:
        print(
            f"  (measured on the dx = {cfg.flow.dx} µm field; paper.yaml uses dx = "
            f"{paper.flow.dx} µm: the per-step cost of a rigid fiber does not depend on dx)"
        )


def _timed(tree: Path, argv: list[str], pattern: str | None) -> float:
    """Run ``argv`` with ``tree`` first on the path; the seconds its own report prints
    (``pattern``'s group), or the command's wall time when ``pattern`` is None."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    t0 = time.perf_counter()
    out = subprocess.run(argv, cwd=tree, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    m = re.search(pattern, out.stdout + out.stderr) if pattern else None
    if out.returncode != 0 or (pattern and m is None):
        raise SystemExit(f"{tree}: {' '.join(argv)} failed:\n{out.stdout}\n{out.stderr}")
    return float(m.group(1)) if m else wall


def compare_trees(args: argparse.Namespace) -> None:
    """Sweep and discrepancy times of this tree against ``args.against``, interleaved."""
    here = Path(__file__).resolve().parents[2]  # the repository
    trees = {"this": here, "other": args.against.resolve()}
    cache = str(Path(args.cache).resolve())

    def snap(tree: Path) -> str:
        """The tree's own snapshot script (its API follows the tree's package)."""
        script = tree / "scripts" / "tools" / "snapshot_discrepancy.py"
        return str(script if script.exists() else tree / "scripts" / "snapshot_discrepancy.py")

    times: dict[tuple[str, str], list[float]] = {}
    with tempfile.TemporaryDirectory() as tmp:

        def sweep(tree: Path, k: str) -> float:
            out = Path(tmp) / f"sweep-{k}"
            argv = [sys.executable, "-m", "fibersweep", "run", str(Path(args.config).resolve()),
                    "-o", str(out), "--no-resume", f"run.cache_dir={cache}"]  # fmt: skip
            return _timed(tree, argv, None)

        def disc(tree: Path, k: str) -> float:
            argv = [sys.executable, snap(tree), str(Path(tmp) / f"disc-{k}"),
                    "--n", str(args.disc_n), "--cache", cache]  # fmt: skip
            return _timed(tree, argv, r"discrepancy ([\d.]+) s")

        for rnd in range(args.rounds + 1):  # round 0: warm-up (Numba caches), not counted
            for name, tree in trees.items():
                for what, fn in (("sweep", sweep), ("discrepancy", disc)):
                    if args.only and what != args.only:
                        continue
                    t = fn(tree, f"{name}-{rnd}")
                    print(f"round {rnd} {name:>5} {what:<12} {t:7.2f} s", flush=True)
                    if rnd:
                        times.setdefault((what, name), []).append(t)
    print(f"this: {trees['this']}, other: {trees['other']}; {args.rounds} timed rounds")
    for what in [w for w in ("sweep", "discrepancy") if (w, "this") in times]:
        a = statistics.median(times[(what, "this")])
        b = statistics.median(times[(what, "other")])
        spread = max(times[(what, "other")]) / min(times[(what, "other")])
        print(f"{what:<12} median this {a:7.2f} s, other {b:7.2f} s: ratio this/other "
              f"{a / b:.3f} (other's own max/min over rounds: {spread:.3f})")  # fmt: skip


if __name__ == "__main__":
    main()
