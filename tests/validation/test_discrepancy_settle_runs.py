"""Follow-up fibers settle a two-way question, with real simulations (coarse field).

The hypotheses are fixed, as after a first analysis: the model as it is (A) and
a 10 % faster inlet (B). Follow-up fibers are synthesised with the truth B, then
with the truth A, at four random starts of the study box; each time the test
(:mod:`fibersweep.discrepancy.settle`) must pick the truth. A 10 % faster inlet
shortens every time by about 9 % against 1 % timing noise, a separation of
several noise units per fiber (the detection file's what-to-measure-next test
finds 5 fibers or fewer enough). Measured here (seed 41): the expected sums under
A and B are about +14 and -15 with sd 6.4, so four fibers reject the false one at
z of about 4.5 (power near 1); a wrong pick has probability at most alpha = 0.05
each time.
"""

from __future__ import annotations

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.copies import NoiseModel
from fibersweep.discrepancy.observables import scored
from fibersweep.discrepancy.schema import validate_measured
from fibersweep.discrepancy.settle import settle
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.discrepancy.synth import STUDY_BOX, synthesize


def test_follow_up_fibers_pick_the_truth_between_two_hypotheses(coarse_field):
    hyps = ({}, {"inlet_speed": 0.1})
    outcomes = {}
    with Simulator(coarse_field, FiberSettings(), workers=1, progress=False) as sim:
        for truth, tag in ((hyps[1], "B"), (hyps[0], "A")):
            table, _ = synthesize(coarse_field, FiberSettings(), STUDY_BOX, 4, truth, seed=41,
                                  workers=1, progress=False)  # fmt: skip
            data = validate_measured(table)
            obs = tuple(o for o in scored() if o in data.observed)
            st = settle(sim, NoiseModel(), hyps, ("model", "inlet +10 %"), "test",
                        data.table, data.starts, obs, np.random.default_rng(1), seed=3,
                        copies=12)  # fmt: skip
            outcomes[tag] = st
            assert st.simulations == 2 * 12 * 4
    assert outcomes["B"].outcome == "B", outcomes["B"].test
    assert outcomes["A"].outcome == "A", outcomes["A"].test
    # and the winner leaves no significant gap on them
    assert outcomes["B"].settled and outcomes["A"].settled
    # the expected sums are well apart: the fibers needed for power 0.8 are few
    assert outcomes["A"].test.fibers_to_settle <= 4


def test_follow_up_fibers_are_kept_by_their_measured_start(coarse_field):
    """synthesize_near: every kept fiber's reported start within the window (3 sd) of its
    centre, the shares 3 and 2, the true starts wider than the window (scatter 6 sd)."""
    from fibersweep.discrepancy.synth import synthesize_near

    noise = NoiseModel()
    centres = np.array([[0.0, 0.4, 1.0], [5.0, 0.3, 0.8]])
    t = synthesize_near(coarse_field, FiberSettings(), centres, 5, seed=2, workers=1)
    half = 3.0 * np.array([noise.theta0, noise.y0, noise.length])
    assert list(t["fiber_id"]) == ["m00-000", "m00-001", "m00-002", "m01-000", "m01-001"]
    starts = t[["theta0", "y0", "length"]].to_numpy()
    which = np.array([0, 0, 0, 1, 1])
    assert np.all(np.abs(starts - centres[which]) <= half + 1e-12)
    validate_measured(t)
