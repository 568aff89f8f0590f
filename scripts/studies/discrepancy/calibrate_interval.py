"""Calibrate the score test's critical value on simulated data sets, and check it on others.

The 95 % interval of a refitted value (:func:`fibersweep.discrepancy.estimate.score_interval`)
is the stretch where the score test's |T| stays below ``scale`` x Student's quantile.
With ``scale`` = 1 it covered 34 of 40 hidden single effects at N = 20 (per-fiber
slopes are step-like, and T between evaluated values is an interpolation). This
script reads the single-effect data sets of ``scripts/studies/discrepancy/study_coverage.py`` (each
JSON
keeps the refit's per-fiber losses, ``profile``) and finds, per data set, the
smallest ``scale`` whose interval holds the truth. The calibrated ``scale`` is the
split-conformal quantile of these: the k-th smallest of n with k = ceil((n + 1) x
0.95), so that a new data set drawn like these is covered with probability at least
0.95 (exchangeability; no model of T). ``--check`` reads the intervals of other
data sets (new seeds) at ``scale`` = 1 and at the calibrated value::

    python scripts/studies/discrepancy/study_coverage.py --kinds single --sets 40 --max-sets 80 \
        --n 20 --copies 4 --seed-offset 2000 --out results/cal_a
    python scripts/studies/discrepancy/study_coverage.py --kinds single --sets 40 --max-sets 80 \
        --n 20 --copies 4 --seed-offset 2000 --first 50 --out results/cal_b
    python scripts/studies/discrepancy/calibrate_interval.py results/cal_a --check results/cal_b

The read-out is offline: a data set's evaluated values are those its refit chose
with the scale of its own run (the interval step evaluates the interval's ends).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from fibersweep.discrepancy.estimate import Fit, score_interval
from fibersweep.discrepancy.scores import conformal_quantile

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from common import wilson  # noqa: E402


def load(out: Path) -> list[tuple[dict, Fit]]:
    """(row, refit) of every fitted single-effect data set under ``out`` with a profile."""
    sets = []
    for p in sorted(out.glob("single/seed*.json")):
        r = json.loads(p.read_text())
        if r["rows"] and "profile" in r:
            x = r["rows"][0]
            prof = tuple((float(v), np.asarray(loss, dtype=float)) for v, loss in r["profile"])
            sets.append((x, Fit(x["effect"], float(x["value"]), 0.0, 0.0, (), prof)))
    return sets


def holds(x: dict, fit: Fit, scale: float) -> bool:
    lo, hi, _, _ = score_interval(fit, scale=scale)
    return lo <= x["truth"] <= hi


def needed(x: dict, fit: Fit, top: float = 64.0, steps: int = 30) -> float:
    """Smallest scale whose interval holds the truth (bisection; inf beyond ``top``)."""
    if holds(x, fit, 0.0):
        return 0.0
    hi = 1.0
    while not holds(x, fit, hi):
        if hi >= top:
            return math.inf
        hi *= 2.0
    lo = 0.0 if hi == 1.0 else hi / 2.0
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if holds(x, fit, mid) else (mid, hi)
    return hi


def coverage(sets: list[tuple[dict, Fit]], scale: float) -> tuple[int, float]:
    """Data sets whose interval holds the truth, and the mean width / |truth|."""
    k, widths = 0, []
    for x, fit in sets:
        lo, hi, _, _ = score_interval(fit, scale=scale)
        k += lo <= x["truth"] <= hi
        widths.append((hi - lo) / abs(x["truth"]))
    return k, float(np.mean(widths))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("calibrate", type=Path, help="study_coverage output (single kind)")
    ap.add_argument("--check", type=Path, help="other data sets: coverage at the scale")
    ap.add_argument("--level", type=float, default=0.95)
    args = ap.parse_args()
    cal = load(args.calibrate)
    f = np.array([needed(x, fit) for x, fit in cal])
    scale = conformal_quantile(f, args.level)
    print(f"calibration: {len(cal)} data sets ({args.calibrate})")
    print("  scale needed, largest six:", ", ".join(f"{v:.3f}" for v in np.sort(f)[-6:]))
    print(f"  held at scale 1: {int((f <= 1.0).sum())}/{len(f)}")
    print(f"  split-conformal scale (k = ceil((n + 1) {args.level:g})): {scale:.3f}")
    for name, sets in [("calibration", cal)] + (
        [("check", load(args.check))] if args.check else []
    ):
        for s in (1.0, scale):
            k, w = coverage(sets, s)
            lo, hi = wilson(k, len(sets))
            print(f"  {name}: scale {s:.3f}: covered {k}/{len(sets)} = {k / len(sets):.2f} "
                  f"[{lo:.2f}, {hi:.2f}], mean width / |truth| {w:.3f}")  # fmt: skip


if __name__ == "__main__":
    main()
