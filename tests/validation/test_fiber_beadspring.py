"""The bead-spring default time step against a much smaller one (SPEC: the source used 1e-7 s)."""

from __future__ import annotations

import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.fiber.kernel.bundles import DEFAULT_DT
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate


@pytest.mark.slow
def test_default_dt_matches_a_fine_step(coarse_field):
    """A run with an apex contact (from x0 = 1100 µm): the default Δt = 5e-5 s against
    Δt = 1e-6 s (6.5e5 steps, ~4 min). Measured: δ equal to 1e-5, θ_c to 0.002°.
    Tolerances: δ 1e-3, θ_c 0.05°, contact time 1e-4 s. (Δt = 1e-7 s would take ~40 min
    on one core; Δt from 2e-4 s to 1e-6 s already agree to 3e-5 in δ.)"""
    start = FiberStart(8.0, 0.351, 0.75)
    runs = [
        simulate(
            coarse_field, FiberSettings(model="bead-spring", x0=1100.0, step={"dt": dt}), start
        )
        for dt in (DEFAULT_DT, 1e-6)
    ]
    a, b = runs
    assert a.cls == b.cls and a.contact and b.contact
    assert abs(a.delta - b.delta) < 1e-3
    assert abs(a.theta_c - b.theta_c) < 0.05
    assert abs(a.t_contact - b.t_contact) < 1e-4
