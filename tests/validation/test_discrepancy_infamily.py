"""The in-family check, reduced: data made by exactly the family the workflow fits.

A verdict "unexplained" on such data is false: the fitted family holds the truth.
It can come from the model's copies differing from the data in something else
than the effect (then the true model itself leaves a gap), or from a fitted value
that the gap test after the fit sees through (docs/validation/discrepancy.md,
*Data made by the fitted family*). The full table is
``scripts/studies/discrepancy/study_infamily.py``; these are its reduced cases on
the tests' coarse field, with ``configs/quick.yaml``'s start box (every fiber of
one length, the box of the issue's data sets).

Tolerances: the gap test at the truth is a level-0.05 test; over 4 data sets at
most 1 rejects (P(X >= 2) = 0.014 for a binomial(4, 0.05)). A single data set's
verdict "unexplained" in family has probability at most about alpha = 0.05 when the
method holds (plus the chance of a miss near the limit), so a single-seed case
fails by chance about once in twenty runs of a fresh seed; its seed is fixed.
"""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.copies import CopyMaker, NoiseModel
from fibersweep.discrepancy.declared import parse_candidate
from fibersweep.discrepancy.gap import assess_gap, value_matrices
from fibersweep.discrepancy.schema import validate_measured
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.discrepancy.synth import synthesize
from fibersweep.discrepancy.workflow import DiscrepancySettings, run_discrepancy

#: configs/quick.yaml's sweep box: every fiber of length 1 (fibersweep.api.compare.sweep_box).
QUICK_BOX = {"theta0": (-8.0, 8.0), "y0": (0.05, 0.9), "length": (1.0, 1.0)}

#: Twice the N = 100 detection limits (friction 0.18, inlet_speed 0.0115).
PAIR = {"friction": 0.36, "inlet_speed": 0.023}


@pytest.mark.slow
def test_the_true_model_leaves_no_gap_on_a_one_length_box(coarse_field):
    """4 data sets of 100 fibers with the pair hidden, against 8 copies of the true
    model: at most 1 of 4 with a gap (2.5 minutes on 2 free cores)."""
    gaps = []
    for seed in (1, 2, 3, 4):
        table, _ = synthesize(coarse_field, FiberSettings(), QUICK_BOX, 100, PAIR, seed=seed,
                              workers=2, progress=False)  # fmt: skip
        data = validate_measured(table)
        with Simulator(coarse_field, FiberSettings(), workers=2, progress=False) as sim:
            maker = CopyMaker(data.starts, NoiseModel(), seed + 104729, sim)
            assert list(maker.fixed) == [2]  # one length: the copies start at it
            cps = maker.copies(range(8), PAIR)
        values = value_matrices(data.table.reset_index(drop=True), cps, tuple(data.observed))
        gaps.append(assess_gap(values, np.random.default_rng([seed, 97])).flagged)
    assert sum(bool(g) for g in gaps) <= 1, gaps


@pytest.mark.slow
def test_flexible_fibers_of_the_quick_box_are_not_unexplained(coarse_field, coarse_settings):
    """The issue's data set: E = 3e5 Pa, 100 fibers of the quick box, seed 5, the
    stiffness declared. Not "unexplained", and nothing but the stiffness named
    (about 4.5 minutes on two free cores)."""
    stiff = parse_candidate("fiber.young_modulus=1e4..3e7", FiberSettings(), coarse_settings)
    truth = FiberSettings(model="bead-spring", integrator="ros2", young_modulus=3e5)
    table, _ = synthesize(coarse_field, truth, QUICK_BOX, 100, seed=5, workers=2,
                          progress=False)  # fmt: skip
    s = DiscrepancySettings(seed=5, workers=2, declared=(stiff,), power_fibers=0,
                            next_copies=0)  # fmt: skip
    res = run_discrepancy(validate_measured(table), coarse_field, FiberSettings(), s,
                          progress=False, flow=coarse_settings)  # fmt: skip
    assert res.verdict.kind != "unexplained", res.verdict.text
    named = {n for alt in res.verdict.alternatives for n in alt}
    assert named <= {stiff.name}, res.verdict.text
