"""Signature strength of track observables against the summary ones (docs/trajectories.md).

For N fibers with starts uniform in the quick config's sweep box, simulate
``--copies`` jittered baseline copies and ``--effect-copies`` jittered copies
with each effect on, observe them as a measurement would (summary observables:
their noise laws; tracks: resampled at ``--fps`` with per-frame noise
1 µm / 1.5°, then derived by
:func:`fibersweep.analysis.observables.track_values`), and print per observable
and effect the shift z-score: the mean over fibers of (effect copy - mean of the
baseline copies) over its standard error (times on a log scale). It also prints
the spread of (noisy-track value - exact value), the measurement error the noise
laws of the track observables must describe.

Usage::

    nice -n 5 python scripts/studies/discrepancy/track_signatures.py --n 40 --copies 4 \
        --effects friction=0.25 pillar_hydro=1 inlet_speed=0.05
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
import pandas as pd

from fibersweep.analysis.observables import track_values
from fibersweep.config import axis_values, load_config
from fibersweep.discrepancy.copies import NoiseModel
from fibersweep.discrepancy.observables import log_scale, noise_draws
from fibersweep.discrepancy.simulate import outcome_row
from fibersweep.discrepancy.synth import parse_effects
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.flow.cache import get_flow_field

SUMMARY = ("delta", "theta_c", "y_c", "t_pass", "dwell")
TIMES = ("t_pass", "dwell", "t_transit")


def observe_track(traj, fps: float, sd_xy: float, sd_th: float, rng) -> tuple[np.ndarray, ...]:
    """The track as a camera sees it: samples at ``fps`` [1/s] with per-frame noise."""
    tf = np.arange(traj.t[0], traj.t[-1], 1.0 / fps)
    x = np.interp(tf, traj.t, traj.x) + sd_xy * rng.standard_normal(tf.size)
    y = np.interp(tf, traj.t, traj.y) + sd_xy * rng.standard_normal(tf.size)
    th = np.interp(tf, traj.t, traj.theta) + sd_th * rng.standard_normal(tf.size)
    return tf, x, y, th


def one(field, settings, start, seed, noise_rng, args, geo) -> tuple[dict, dict]:
    r = simulate(field, settings, FiberStart(*map(float, start)), rng_seed=int(seed))
    row = outcome_row(r)
    exact, seen = {}, {}
    if row["status"] == "ok" and r.trajectory is not None:
        tr = r.trajectory
        exact = track_values(tr.t, tr.x, tr.y, tr.theta, geo, float(start[2]))
        seen = track_values(*observe_track(tr, args.fps, 1.0, 1.5, noise_rng), geo, float(start[2]))
    return {**row, **seen}, exact


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="configs/quick.yaml")
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--copies", type=int, default=4)
    ap.add_argument("--effect-copies", type=int, default=1)
    ap.add_argument("--effects", nargs="+", default=["friction=0.25"])
    ap.add_argument("--fps", type=float, default=100.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    cfg = load_config(args.config)
    field, _ = get_flow_field(cfg.flow, args.cache)
    geo = field.geometry
    rec = cfg.fiber.record.model_copy(update={"trajectories": True, "samples": 1000})
    base = cfg.fiber.model_copy(update={"record": rec})
    rng = np.random.default_rng([args.seed, 1])
    box = {}
    for c in ("theta0", "y0", "length"):
        v = axis_values(getattr(cfg.sweep, c))
        box[c] = (float(v.min()), float(v.max()))
    lo = np.array([box[c][0] for c in ("theta0", "y0", "length")])
    hi = np.array([box[c][1] for c in ("theta0", "y0", "length")])
    true = lo + (hi - lo) * rng.random((args.n, 3))
    nm = NoiseModel()
    t0 = time.perf_counter()
    sets: dict[str, list[pd.DataFrame]] = {}
    errors: dict[str, list[float]] = {}
    runs = {"baseline": ({}, args.copies)}
    for e in args.effects:
        runs[e] = (parse_effects([e]), args.effect_copies)
    for name, (eff, k_copies) in runs.items():
        st = base.model_copy(update={"effects": {**base.effects, **eff}})
        for k in range(k_copies):
            starts = nm.jitter_starts(true, np.random.default_rng([args.seed, 2, k, len(name)]))
            seeds = np.random.default_rng([args.seed, 3, k]).integers(0, 2**31 - 1, args.n)
            nrng = np.random.default_rng([args.seed, 4, k, len(name)])
            rows = []
            for i in range(args.n):
                row, exact = one(field, st, starts[i], seeds[i], nrng, args, geo)
                rows.append(row)
                for q, v in exact.items():
                    if np.isfinite(v) and np.isfinite(row[q]):
                        errors.setdefault(q, []).append(row[q] - v)
            df = pd.DataFrame(rows)
            z = noise_draws([args.seed, 5, k, len(name)], args.n)
            sets.setdefault(name, []).append(nm.observe(df, z))
    quantities = [*SUMMARY, *(q for q in errors)]
    result: dict[str, dict[str, float]] = {}
    B = {q: np.stack([d[q].to_numpy(float) for d in sets["baseline"]], 1) for q in quantities}
    for name in args.effects:
        result[name] = {}
        for q in quantities:
            b = B[q]
            if q in TIMES:
                b = log_scale(b)
            for d in sets[name]:
                e = d[q].to_numpy(float)
                e = log_scale(e) if q in TIMES else e
                diff = e - b.mean(axis=1)
                ok = np.isfinite(diff)
                if ok.sum() < 3:
                    z = float("nan")
                else:
                    z = float(diff[ok].mean() / (diff[ok].std(ddof=1) / np.sqrt(ok.sum())))
                result[name].setdefault(q, []).append(round(z, 2))
    print(f"{args.n} fibers, {args.copies} baseline copies, {time.perf_counter() - t0:.0f} s")
    print("shift z (effect copy vs baseline mean), per effect copy:")
    print(f"{'observable':>12} " + " ".join(f"{e:>18}" for e in args.effects))
    for q in quantities:
        print(f"{q:>12} " + " ".join(f"{str(result[e][q]):>18}" for e in args.effects))
    print("measurement error of the track observables (noisy track - exact), sd:")
    for q, v in errors.items():
        print(f"{q:>12} {np.std(v):.4g}  (n={len(v)})")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"z": result, "error_sd": {q: float(np.std(v)) for q, v in errors.items()}},
                      fh, indent=1)  # fmt: skip


if __name__ == "__main__":
    main()
