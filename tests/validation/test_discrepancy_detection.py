"""Power analysis and what-to-measure-next on the coarse grid (real simulations, in-process)."""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.candidates import get_candidates
from fibersweep.discrepancy.copies import CopyMaker, NoiseModel
from fibersweep.discrepancy.next_measure import discriminate
from fibersweep.discrepancy.observables import scored
from fibersweep.discrepancy.power import analyse_power
from fibersweep.discrepancy.report_figures import next_figure
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.discrepancy.synth import STUDY_BOX as BOX
from fibersweep.plots.style import paper_style


def _starts(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(*BOX[c], n) for c in ("theta0", "y0", "length")])


def test_identical_hypotheses_cannot_be_separated_and_a_speed_change_can(coarse_field, tmp_path):
    grid = _starts(6, 1)
    measured = _starts(4, 2)
    with Simulator(coarse_field, FiberSettings(), workers=1, progress=False) as sim:
        same = discriminate(sim, NoiseModel(), ({}, {}), measured, scored(), grid=grid)
        # common random numbers: the same hypothesis twice gives the same runs, D = 0
        assert np.all(same.d == 0.0) and same.fibers_to_settle is None
        fast = discriminate(
            sim, NoiseModel(), ({}, {"inlet_speed": 0.1}), measured, scored(), grid=grid
        )
    # a 10 % faster inlet shortens every time by ~9 % against 1 % timing noise: a time
    # observable separates them, and a handful of fibers (<= 5) settle it
    assert fast.best[0].observable in ("t_pass", "dwell")
    assert fast.fibers_to_settle is not None and fast.fibers_to_settle <= 5
    with paper_style():
        png = next_figure(fast, measured[:, :2], tmp_path / "next.png")
    assert png.stat().st_size > 0


@pytest.mark.slow
def test_power_limits_and_look_alikes(coarse_field):
    rng = np.random.default_rng(3)
    cands = get_candidates(["inlet_speed", "off_midplane"])
    with Simulator(coarse_field, FiberSettings(), workers=2, progress=False) as sim:
        maker = CopyMaker(_starts(16, 4), NoiseModel(), 5, sim)
        pw = analyse_power(maker, cands, 100, scored(), rng, n_sim=16)
    lim = {(e.name, np.sign(e.probe)): e.limit for e in pw.effects}
    # the probes (inlet ±0.15, off_midplane 0.25) are far beyond what 100 fibers see:
    # every limit exists and lies strictly inside the probe
    for (name, sign), v in lim.items():
        probe = {"inlet_speed": 0.15, "off_midplane": 0.25}[name]
        assert v is not None and 0 < sign * v < probe, (name, sign, v)
    # a slower inlet and an off-midplane fiber both slow every fiber: look-alikes
    assert any(
        {a.split("@")[0], b.split("@")[0]} == {"inlet_speed", "off_midplane"}
        for a, b, _ in pw.lookalikes
    ), pw.cosines
