"""A flow grid as a declared candidate, then the measurement the report asks for.

Fibers are synthesised on a field of another grid (``--truth-dx``) and analysed with
the study model (dx = 4 µm) and ``flow.dx=<truth>`` declared. When the verdict is
ambiguous (or unexplained), the report's what-to-measure-next names the starts where
its two hypotheses differ most and how many fibers there would settle it. This script
then "measures" ``--factor`` times that many fibers (default 2: the report's count is
for power 0.8) on the truth field, shared out over the best starts, with the
workflow's own start and outcome noise, as an experimenter would: fibers arrive
scattered around each start, and those whose measured start lies within three
start-noise sd of it are kept. It puts them to the verdict's two hypotheses
(``discrepancy --followup``: the analysis of the first fibers stands, the follow-up
fibers test A against B).

Usage::

    python scripts/studies/discrepancy/grid_followup.py --truth-dx 5 --n 100 --seed 9521 \
        --out results/grid_followup

Writes ``summary.json`` in ``--out``: the first analysis's verdict and
what-to-measure-next, then the verdict after the follow-up fibers and their test
(:func:`fibersweep.discrepancy.report.summary`), runs and time.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from common import BOX, DEFAULT_CACHE, STUDY_FLOW, study_field  # noqa: E402

from fibersweep.config.fiber import FiberSettings  # noqa: E402
from fibersweep.config.flow import FlowSettings  # noqa: E402
from fibersweep.discrepancy.declared import parse_candidate  # noqa: E402
from fibersweep.discrepancy.report import summary  # noqa: E402
from fibersweep.discrepancy.schema import validate_measured  # noqa: E402
from fibersweep.discrepancy.synth import synthesize, synthesize_near  # noqa: E402
from fibersweep.discrepancy.workflow import (  # noqa: E402
    DiscrepancySettings,
    run_discrepancy,
    settle_result,
)
from fibersweep.flow.cache import get_flow_field  # noqa: E402

FIBER = FiberSettings()


def analyse(table: pd.DataFrame, field, declared, seed: int, workers: int, cache: str):
    """The workflow on ``table`` with ``declared`` (power off, what-to-measure-next on)."""
    s = DiscrepancySettings(seed=seed, workers=workers, declared=declared, power_fibers=0)
    t0 = time.perf_counter()
    res = run_discrepancy(validate_measured(table), field, FIBER, s, progress=False,
                          flow=STUDY_FLOW, cache_dir=cache)  # fmt: skip
    return res, time.perf_counter() - t0


def reported(res, seconds: float) -> dict:
    """What the report's summary.json says of the verdict and what to measure next."""
    s = summary(res)
    keep = ("verdict", "next", "settle", "n_fibers", "simulations")
    return {k: s[k] for k in keep} | {"seconds": round(seconds, 1)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--truth-dx", type=float, default=5.0, help="grid of the truth [µm]")
    ap.add_argument("--n", type=int, default=100, help="fibers of the first data set")
    ap.add_argument("--seed", type=int, default=9521)
    ap.add_argument("--max-more", type=int, default=300,
                    help="most fibers to add (0: the first analysis only)")  # fmt: skip
    ap.add_argument(
        "--factor",
        type=float,
        default=2.0,
        help="fibers measured per fiber the report asks for (it asks for power 0.8)",
    )
    ap.add_argument("--starts", type=int, default=5, help="best starts to share them over")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cache", default=DEFAULT_CACHE)
    ap.add_argument("--out", type=Path, default=Path("results/grid_followup"))
    a = ap.parse_args(argv)
    a.out.mkdir(parents=True, exist_ok=True)

    field = study_field(a.cache)
    truth_field, _ = get_flow_field(FlowSettings(dx=a.truth_dx), a.cache)
    declared = (parse_candidate(f"flow.dx={a.truth_dx:g}", FIBER, STUDY_FLOW),)
    table, _ = synthesize(truth_field, FIBER, BOX, a.n, seed=a.seed, workers=a.workers,
                          progress=False)  # fmt: skip
    res, sec = analyse(table, field, declared, a.seed, a.workers, a.cache)
    out = {"truth_dx": a.truth_dx, "n": a.n, "seed": a.seed, "first": reported(res, sec)}
    print(f"first ({len(table)} fibers): {res.verdict.text} [{res.simulations} runs, {sec:.0f} s]")
    nxt = res.extra.get("next")
    if res.verdict.kind != "named" and nxt is not None and nxt.fibers_to_settle and a.max_more:
        best = nxt.best[: a.starts]
        more = min(int(math.ceil(a.factor * nxt.fibers_to_settle)), a.max_more)
        out["fibers_added"] = {"fibers": more, "starts": len(best)}
        print(f"what to measure next: {nxt.labels[0]} against {nxt.labels[1]}; "
              f"{nxt.fibers_to_settle} fibers at the best starts; adding {more}")  # fmt: skip
        centres = np.array([[b.theta0, b.y0, b.length] for b in best])
        extra = synthesize_near(truth_field, FIBER, centres, more, seed=a.seed + 1000,
                                workers=a.workers)  # fmt: skip
        t0 = time.perf_counter()
        res2 = settle_result(res, validate_measured(extra), field, FIBER, progress=False,
                             flow=STUDY_FLOW, cache_dir=a.cache)  # fmt: skip
        sec2 = time.perf_counter() - t0
        out["followup"] = reported(res2, sec2)
        print(f"after {len(extra)} follow-up fibers: {res2.verdict.text} "
              f"[{res2.simulations - res.simulations} more runs, {sec2:.0f} s]")  # fmt: skip
    elif nxt is not None:
        print(f"what to measure next: {nxt.labels[0]} against {nxt.labels[1]}; "
              f"{nxt.fibers_to_settle} fibers at the best starts; none added")  # fmt: skip
    else:
        print("no follow-up:", res.extra.get("next_skipped", "nothing to separate"))
    (a.out / "summary.json").write_text(json.dumps(out, indent=2) + "\n", encoding="utf-8")
    print(f"wrote {a.out / 'summary.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
