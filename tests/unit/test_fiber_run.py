"""simulate(): bad input raises InputError naming the parameter; blow-ups return failed."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.errors import InputError
from fibersweep.fiber.models.elastic import elastic_energy, elastic_forces
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.flow.field import FlowField
from fibersweep.units import Geometry

GEO = Geometry()


@pytest.fixture(scope="module")
def hele_shaw():
    """Uniform 600 µm/s with the pillar nodes zeroed (a crude analytic stand-in)."""
    return FlowField.from_function(lambda X, Y: (600.0 + 0 * X, 0 * X), GEO, 4.0, with_pillar=True)


@pytest.mark.parametrize(
    "start, name",
    [
        (FiberStart(math.nan, 0.5, 1.0), "theta0"),
        (FiberStart(0.0, math.inf, 1.0), "y0"),
        (FiberStart(0.0, 0.5, 0.02), "length"),
        (FiberStart(0.0, 0.5, -1.0), "length"),
        (FiberStart(0.0, 6.0, 1.0), "y0"),  # outside the channel
        (FiberStart(0.0, -5.5, 1.0), "y0"),
    ],
)
def test_bad_start_names_the_parameter(hele_shaw, start, name):
    with pytest.raises(InputError, match=name):
        simulate(hele_shaw, FiberSettings(), start)


def test_start_overlapping_the_pillar(hele_shaw):
    x0 = GEO.centroid[0]
    with pytest.raises(InputError, match="overlaps the pillar"):
        simulate(hele_shaw, FiberSettings(x0=x0), FiberStart(0.0, 0.3, 1.0))


def test_unknown_effect(hele_shaw):
    with pytest.raises(InputError, match="valid names"):
        simulate(hele_shaw, FiberSettings(effects={"magic": 1.0}), FiberStart(0.0, 0.5, 1.0))


def test_time_limit_is_a_failed_result_not_an_exception(hele_shaw):
    st = FiberSettings(step={"t_max": 0.05})
    r = simulate(hele_shaw, st, FiberStart(0.0, 0.8, 1.0))
    assert r.status == "failed" and r.reason == "time limit" and r.cls == ""
    assert math.isnan(r.delta)


def test_blow_up_is_a_failed_result():
    bad = FlowField.from_function(lambda X, Y: (600.0 + 0 * X, 0 * X), GEO, 4.0)
    ux = bad.ux.copy()
    ux[200:, :] = np.nan
    bad = FlowField(ux, bad.uy, bad.dx, bad.geometry, bad.fluid, bad.solid)
    r = simulate(bad, FiberSettings(), FiberStart(0.0, 0.8, 1.0))
    assert r.status == "failed" and r.reason == "nan"


def test_elastic_forces_are_minus_the_energy_gradient():
    """Central differences of H (step 1e-5 µm): tolerance 1e-4 relative to max |F|."""
    rng = np.random.default_rng(2)
    n = 8
    s = np.arange(n) * 4.0
    x = s + rng.normal(scale=0.3, size=n)
    y = 0.1 * s**1.5 / 10 + rng.normal(scale=0.3, size=n)
    a, S, B = 2.0, 26e6 * math.pi * 4.0, 26e6 * math.pi * 16.0 / 4.0
    fx, fy = np.zeros(n), np.zeros(n)
    elastic_forces(x, y, a, S, B, fx, fy)
    h = 1e-5
    num = np.zeros((n, 2))
    for i in range(n):
        for c, arr in enumerate((x, y)):
            arr[i] += h
            ep = elastic_energy(x, y, a, S, B)
            arr[i] -= 2 * h
            em = elastic_energy(x, y, a, S, B)
            arr[i] += h
            num[i, c] = -(ep - em) / (2 * h)
    scale = np.abs(num).max()
    np.testing.assert_allclose(np.column_stack([fx, fy]), num, atol=1e-4 * scale)
    # a straight chain at rest length carries no force
    fx0, fy0 = np.zeros(n), np.zeros(n)
    elastic_forces(s.astype(float), np.zeros(n), a, S, B, fx0, fy0)
    assert np.abs(fx0).max() < 1e-6 and np.abs(fy0).max() < 1e-6


def test_the_run_path_dispatches_on_the_field(hele_shaw):
    """One path, two cases: a unit cell is the array's, any other field the channel's."""
    from fibersweep.fiber.array_run import ARRAY
    from fibersweep.fiber.channel import CHANNEL
    from fibersweep.fiber.run import CASES, case_of
    from fibersweep.flow.cell import CellField

    assert CASES[-1] is CHANNEL  # the channel takes any field: asked last
    assert case_of(hele_shaw) is CHANNEL
    assert case_of(object.__new__(CellField)) is ARRAY
