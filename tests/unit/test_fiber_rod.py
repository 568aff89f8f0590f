"""The rod's constants EA = E π a², EI = E π a⁴ / 4 are written once and read by all three users."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.fiber.kernel.bundles import make_params
from fibersweep.fiber.models.deformation import deformation
from fibersweep.fiber.models.elastoviscous import bending_stiffness
from fibersweep.fiber.models.rod import Rod, rod


def test_values_by_hand_and_units():
    # E = 0.1 MPa = 1e5 pN/µm², a = 2 µm: EA = 4e5 π pN, EI = 4e5 π pN µm²
    r = rod(1e5, 2.0)
    assert r == Rod(stretch=pytest.approx(4e5 * math.pi), bend=pytest.approx(4e5 * math.pi))
    # the same rod in SI: a = 2e-6 m gives N and N m² (1 pN µm² = 1e-24 N m²)
    si = rod(1e5, 2e-6)
    assert si.stretch == pytest.approx(r.stretch * 1e-12, rel=1e-14)
    assert si.bend == pytest.approx(r.bend * 1e-24, rel=1e-14)
    with pytest.raises(AttributeError):
        r.bend = 0.0  # frozen


@pytest.mark.parametrize("e, a", [(1e5, 2.0), (1e4, 2.0), (2.6e7, 1.5), (1e6, 1.5), (3.3e5, 0.7)])
def test_every_user_reads_the_one_rod(e, a):
    """Bit for bit: the kernel's S and B, the tension observable's S, the elasto-viscous B."""
    r = rod(e, a)
    # the kernel's constants, with the expression the kernels always used
    p = make_params(
        FiberSettings(model="bead-spring", bead_radius=a, young_modulus=e),
        mu=0.34,
        u_center=600.0,
        x_stop=100.0,
        y_lo=a,
        y_hi=100.0,
        random=False,
    )
    assert p.stretch == e * math.pi * a**2 == r.stretch
    assert p.bend == e * math.pi * a**4 / 4.0 == r.bend
    # the tension of one segment stretched by d: T = (S / 2a) d, S the rod's
    d = 0.25
    beads = np.array([[[0.0, 0.0], [2.0 * a + d, 0.0]]])
    out = deformation(beads, np.zeros(1), np.zeros((0, 2)), np.array([1e3, 1e3, 1.0]), 1.0, a, e)
    assert out["max_tension"] == r.stretch / (2.0 * a) * ((2.0 * a + d) - 2.0 * a)
    assert bending_stiffness(e, a) == rod(e, a * 1e-6).bend
