"""Fibers meeting a circular or square pillar: stopped at the surface, rough and smooth.

The flow is an analytic stand-in: uniform 600 µm/s with the pillar's nodes at
rest, so the drag keeps pushing the fiber into the pillar while it slides round
it (harsher than the real field, which slows down at the upstream face). Only
the contact force keeps the fiber out. Bounds as for the triangle
(tests/validation/test_fiber_pillar.py): with the rough pillar no bead surface
crosses the exact outline (clearance > 0; the pillar beads stick out by a_obs);
with the smooth pillar the force law gives F_ref at R = a and a fiber pushed
harder sits slightly inside R = a: overlap below 0.25 a.
"""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.config.fiber import ContactSettings, FiberSettings
from fibersweep.fiber.contact.pillar import contact_forces, make_pillar
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.flow.field import FlowField
from fibersweep.units import Geometry

SHAPES = {
    "circle": Geometry(pillar_shape="circle"),
    "square": Geometry(pillar_shape="square"),
    "diamond": Geometry(pillar_shape="square", pillar_rotation=45.0),
}


# (y0/h, θ0 [deg]) aimed at the lower face, the middle and the upper corner, one turned broadside
STARTS = ((0.2, -10.0), (0.45, 0.0), (0.5, 60.0), (0.8, 0.0))


def _uniform(geo: Geometry) -> FlowField:
    return FlowField.from_function(lambda X, Y: (600.0 + 0 * X, 0 * X), geo, 4.0, with_pillar=True)


@pytest.mark.parametrize("pillar", ["rough", "smooth"])
@pytest.mark.parametrize("name", list(SHAPES))
def test_fiber_is_stopped_at_the_surface(name, pillar):
    geo = SHAPES[name]
    field = _uniform(geo)
    x0 = geo.centroid[0] - 1.5 * geo.pillar_height
    st = FiberSettings(x0=x0, contact={"pillar": pillar})
    a = st.bead_radius
    bound = 0.0 if pillar == "rough" else -0.25 * a
    touched = 0
    for y0, theta0 in STARTS:
        r = simulate(field, st, FiberStart(theta0, y0, 0.8))
        assert r.status == "ok", (name, pillar, y0, theta0, r)
        assert r.min_clearance > bound, (name, pillar, y0, theta0, r.min_clearance)
        touched += bool(r.contact)
        if r.contact:  # it reached the surface: within a bead radius of the outline
            assert r.min_clearance < a, (name, pillar, y0, theta0, r.min_clearance)
    assert touched >= 3  # the starts aim at the pillar: most of them touch it


@pytest.mark.parametrize("name", list(SHAPES))
def test_smooth_force_is_normal_and_reaches_f_ref_at_one_radius(name):
    """A bead at R = a outside the smooth outline, beside the middle of a face (or anywhere
    on the circle), feels F_ref along the outward normal (tolerance 1e-9 relative)."""
    geo = SHAPES[name]
    a, f_ref = 2.0, 1.0
    pil = make_pillar(geo, ContactSettings(pillar="smooth", corner_radius=2.0), a, f_ref)
    shape = geo.shape
    if name == "circle":
        angles = np.linspace(0.0, 2 * np.pi, 7, endpoint=False)
        foot = np.column_stack([shape.cx + shape.radius * np.cos(angles),
                                shape.cy + shape.radius * np.sin(angles)])  # fmt: skip
    else:
        v = shape.vertices
        foot = 0.5 * (v + np.roll(v, -1, axis=0))  # mid-faces
    _, normal, _ = shape.nearest(foot[:, 0], foot[:, 1])
    f, d = contact_forces(pil, foot + a * normal)
    np.testing.assert_allclose(d, a, rtol=1e-9)
    np.testing.assert_allclose(f, f_ref * normal, atol=1e-9 * f_ref)
