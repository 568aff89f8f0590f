#!/usr/bin/env python3
"""Record every simulated outcome of one discrepancy check, to compare two versions bit for bit.

Synthesises N measured fibers (default 60) with hidden ``pillar_scale`` and
``friction`` on the coarse field (dx = 4 µm), with tracks (so the track
observables and the pillar_scale track rescaling are exercised), then runs the
workflow on a reduced plan. Every batch the workflow's ``Simulator`` returns is
kept, in order, with its stage label; with the synthesised tables and the
verdict they go to OUT (Parquet + JSON). ``scripts/tools/compare_runs.py --snapshot A
B`` then compares two such folders exactly.

To compare two versions whose module layout differs, run each tree's own copy of
this script (``scripts/benchmarks/bench_discrepancy_ab.py`` does so, and times them).

Usage:  python scripts/tools/snapshot_discrepancy.py OUT [--n 60] [--seed 3] [--workers 2]
                                                  [--cache DIR]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import pandas as pd

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy import simulate as sim_mod
from fibersweep.discrepancy.measured import validate_trajectories, with_tracks
from fibersweep.discrepancy.schema import validate_measured
from fibersweep.discrepancy.synth import STUDY_BOX as BOX
from fibersweep.discrepancy.synth import synthesize_with_tracks
from fibersweep.discrepancy.workflow import DiscrepancySettings, run_discrepancy

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
from common import study_field  # noqa: E402  (scripts/studies/common.py)

HIDDEN = {"pillar_scale": 0.1, "friction": 0.5}
PLAN = dict(
    copies=3, fit_copies=2, candidates=2, fit_evals=4, refits=1, n_perm=999,
    power_fibers=0, next_copies=0, pairs=1,
    effects=("pillar_scale", "friction", "inlet_speed"),
)  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--n", type=int, default=60)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cache", type=Path, default=Path(".fibersweep-cache"))
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    field = study_field(args.cache)
    fiber = FiberSettings()
    t0 = time.perf_counter()
    table, tracks, _ = synthesize_with_tracks(
        field, fiber, BOX, args.n, HIDDEN, seed=args.seed, workers=args.workers,
        progress=False, fps=100.0,
    )  # fmt: skip
    t_synth = time.perf_counter() - t0
    data = validate_measured(table)
    data = with_tracks(data, validate_trajectories(tracks, data.table, "tracks"), field.geometry)

    batches: list[pd.DataFrame] = []
    original = sim_mod.Simulator.run

    def recording(self, starts, effects, seeds, desc="runs", fps=None):  # noqa: ANN001
        df = original(self, starts, effects, seeds, desc=desc, fps=fps)
        rec = df.drop(columns=[c for c in ("track",) if c in df]).copy()
        rec.insert(0, "batch", len(batches))
        rec.insert(1, "desc", desc)
        rec.insert(2, "effects", json.dumps(dict(sorted((effects or {}).items()))))
        batches.append(rec)
        return df

    sim_mod.Simulator.run = recording
    settings = DiscrepancySettings(seed=args.seed, workers=args.workers, **PLAN)
    t1 = time.perf_counter()
    res = run_discrepancy(data, field, fiber, settings, progress=False)
    t_disc = time.perf_counter() - t1
    sim_mod.Simulator.run = original

    table.to_parquet(args.out / "measured.parquet")
    tracks.to_parquet(args.out / "tracks.parquet")
    pd.concat(batches, ignore_index=True).to_parquet(args.out / "batches.parquet")
    verdict = {
        "kind": res.verdict.kind,
        "effects": {k: float(v) for k, v in res.verdict.effects.items()},
        "text": res.verdict.text,
        "simulations": int(res.simulations),
    }
    (args.out / "verdict.json").write_text(json.dumps(verdict, indent=1, sort_keys=True))
    (args.out / "timing.json").write_text(
        json.dumps({"synth_s": t_synth, "discrepancy_s": t_disc, "batches": len(batches)})
    )
    kind, named = verdict["kind"], verdict["effects"]
    print(f"{len(batches)} batches, {res.simulations} runs; synth {t_synth:.1f} s, "
          f"discrepancy {t_disc:.1f} s; verdict {kind} {named}")  # fmt: skip


if __name__ == "__main__":
    main()
