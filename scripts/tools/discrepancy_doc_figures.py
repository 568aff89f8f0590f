"""Figures of docs/discrepancy.md (coarse grid, in-process, a few minutes on one core).

1. ``discrepancy_gap_pair.png``: 20 measured-like fibers with friction = 0.8 and
   inlet_speed = 0.15 hidden, the workflow on the library subset {friction,
   inlet_speed} with a small plan; the out-of-sample gap before and after the
   named pair (the report's ``gap_before_after.png``).
2. ``discrepancy_next_measure.png``: where one fiber best separates
   inlet_speed = -0.06 from off_midplane = 0.10 (look-alikes) around 20 starts.

Usage::

    python scripts/tools/discrepancy_doc_figures.py --cache .fibersweep-cache/tests
"""

from __future__ import annotations

import argparse
import logging
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

from fibersweep.config import Config
from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.copies import NoiseModel
from fibersweep.discrepancy.next_measure import discriminate, start_grid
from fibersweep.discrepancy.observables import scored
from fibersweep.discrepancy.report import write_report
from fibersweep.discrepancy.report_figures import next_figure
from fibersweep.discrepancy.schema import validate_measured
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.discrepancy.synth import synthesize
from fibersweep.discrepancy.workflow import DiscrepancySettings, run_discrepancy
from fibersweep.plots.style import paper_style

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
from common import BOX, DEFAULT_CACHE, study_field, uniform_starts  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", default=DEFAULT_CACHE)
    ap.add_argument("--out", default="docs/figures")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    field = study_field(args.cache)
    hidden = {"friction": 0.8, "inlet_speed": 0.15}
    table, _ = synthesize(field, FiberSettings(), BOX, 20, hidden, seed=5, workers=1,
                          progress=False)  # fmt: skip
    settings = DiscrepancySettings(
        seed=5, workers=1, effects=("friction", "inlet_speed"), copies=3, fit_copies=2,
        candidates=2, fit_evals=4, refits=1, pairs=1, power_fibers=0, next_copies=0,
        n_perm=999,
    )  # fmt: skip
    res = run_discrepancy(validate_measured(table), field, FiberSettings(), settings,
                          progress=False)  # fmt: skip
    print(f"pair example: {res.verdict.text}")
    with tempfile.TemporaryDirectory() as tmp:
        write_report(res, tmp, Config().model_dump(mode="json"))
        shutil.copy(Path(tmp) / "gap_before_after.png", out / "discrepancy_gap_pair.png")
    rng = np.random.default_rng(0)
    meas = uniform_starts(rng, 20)
    with Simulator(field, FiberSettings(), workers=1, progress=False) as sim:
        nx = discriminate(
            sim, NoiseModel(), ({"inlet_speed": -0.06}, {"off_midplane": 0.10}), meas,
            scored(), grid=start_grid(meas, 5, 6, 2),
        )  # fmt: skip
    print(f"next measure: {nx.fibers_to_settle} fibers at the best starts, "
          f"{nx.fibers_to_separate_measured} at the measured ones")  # fmt: skip
    with paper_style():
        next_figure(nx, meas[:, :2], out / "discrepancy_next_measure.png")


if __name__ == "__main__":
    main()
