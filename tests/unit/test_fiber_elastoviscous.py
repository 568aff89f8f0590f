"""The elasto-viscous number μ̄ = 8πμγ̇L⁴/(Bc) against hand values and its invariances."""

from __future__ import annotations

import math

import pytest

from fibersweep.config import parse_config
from fibersweep.fiber.models.elastoviscous import (
    bending_stiffness,
    elastoviscous_number,
    pillar_shear_rate,
)


def test_value_by_hand():
    # L = 80 µm, E = 0.1 MPa, a = 2 µm, μ = 0.34 Pa s, γ̇ = 600 / 40 = 15 1/s:
    # B = 1e5 π (2e-6)^4 / 4 = 1.2566e-18 N m², c = -ln(0.025² e) = 6.3778,
    # μ̄ = 8π 0.34 15 (80e-6)^4 / (B c) = 655.0
    b = 1e5 * math.pi * (2e-6) ** 4 / 4
    c = -math.log(0.025**2 * math.e)
    want = 8 * math.pi * 0.34 * 15.0 * (80e-6) ** 4 / (b * c)
    assert bending_stiffness(1e5, 2.0) == pytest.approx(b, rel=1e-12)
    assert elastoviscous_number(0.34, 15.0, 80.0, 1e5, 2.0) == pytest.approx(want, rel=1e-12)
    assert want == pytest.approx(655.0, abs=0.5)


def test_dimensionless_and_inverse_in_stiffness():
    base = elastoviscous_number(0.34, 15.0, 80.0, 1e5, 2.0)
    # lengths scaled together leave it unchanged (it has no unit)
    assert elastoviscous_number(0.34, 15.0, 160.0, 1e5, 4.0) == pytest.approx(base, rel=1e-12)
    assert elastoviscous_number(0.34, 15.0, 80.0, 1e6, 2.0) == pytest.approx(base / 10, rel=1e-12)
    assert elastoviscous_number(0.68, 15.0, 80.0, 1e5, 2.0) == pytest.approx(2 * base, rel=1e-12)
    with pytest.raises(ValueError, match="diameter"):
        elastoviscous_number(0.34, 15.0, 4.0, 1e5, 2.0)


def test_shear_rate_of_the_channel_and_of_an_array():
    assert pillar_shear_rate(parse_config({}).flow) == pytest.approx(600.0 / 75.0)
    arr = parse_config({"flow": {"array": {"pillar_size": 40.0}}, "sweep": {"length": 40.0}})
    assert pillar_shear_rate(arr.flow) == pytest.approx(600.0 / 40.0)
