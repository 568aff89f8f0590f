"""The pillar array: geometry, the single-pillar cell it is built from, and its checks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.geometry.array import ArrayError, PillarArray
from fibersweep.units import Geometry


def test_cell_is_a_single_pillar_geometry():
    """The unit cell is the channel's Geometry: same shape object, lengths = periods."""
    a = PillarArray(pillar_shape="circle", pillar_size=40.0, period_x=100.0, period_y=90.0)
    g = a.cell_geometry
    assert isinstance(g, Geometry)
    assert (g.length, g.width, g.depth) == (100.0, 90.0, 40.0)
    x0, y0, x1, y1 = g.shape.bounds
    assert x0 == pytest.approx(100.0 - x1) and y0 == pytest.approx(90.0 - y1)  # box centred
    assert a.gap == pytest.approx(50.0)


@pytest.mark.parametrize("shape", ["triangle", "circle", "square"])
def test_images_are_translations_by_the_lattice(shape):
    a = PillarArray(pillar_shape=shape, pillar_size=30.0, period_x=70.0, period_y=60.0, shift=0.2)
    cx, cy = a.shape.centroid
    for r, c, sh in a.images(-100.0, -100.0, 100.0, 100.0, 5.0):
        ox, oy = sh.centroid
        assert ox - cx == pytest.approx(r * 70.0)
        assert oy - cy == pytest.approx(r * 0.2 * 60.0 + c * 60.0)
    assert a.tilt_deg == pytest.approx(math.degrees(math.atan(12.0 / 70.0)))


def test_fold_into_cell_is_consistent_with_rows():
    a = PillarArray(period_x=80.0, period_y=80.0, shift=0.1)
    x = np.array([-5.0, 85.0, 805.0])
    y = np.array([3.0, 3.0, 3.0])
    xl, yl = a.to_cell(x, y)
    assert np.allclose(xl, [75.0, 5.0, 5.0])
    # row r is the cell moved by (r λx, r ε λy): y folds by r * 8 µm
    assert np.allclose(yl, [(3.0 + 8.0) % 80.0, (3.0 - 8.0) % 80.0, (3.0 - 80.0) % 80.0])


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"pillar_size": 40.0, "period_y": 40.0}, "period_y"),  # touching across the flow
        ({"pillar_shape": "square", "pillar_size": 50.0, "period_x": 45.0}, "period_x"),
        ({"shift": 1.0}, "shift"),
        ({"shift": -0.1}, "shift"),
        ({"depth": 0.0}, "depth"),
    ],
)
def test_bad_arrays_name_the_field(kwargs, field):
    with pytest.raises(ArrayError) as err:
        PillarArray(**kwargs)
    assert err.value.field == field


def test_gap_narrower_than_the_fiber_is_refused():
    a = PillarArray(pillar_shape="circle", pillar_size=76.5, period_x=80.0, period_y=80.0)
    with pytest.raises(ArrayError, match="diameter") as err:
        a.check_fiber(bead_radius=2.0)
    assert err.value.field == "period_y"


def test_shift_must_be_whole_cells_and_the_message_proposes_one():
    a = PillarArray(period_y=100.0, shift=0.1)  # 10 µm
    assert a.check_lattice(2.0) == 5
    with pytest.raises(ArrayError, match="whole number of lattice cells") as err:
        a.check_lattice(4.0)  # 2.5 cells
    assert err.value.field == "shift"
    assert "shift = 0.08" in str(err.value) or "shift = 0.12" in str(err.value)
