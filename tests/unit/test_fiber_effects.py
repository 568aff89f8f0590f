"""The effects registry and the dynamic effects."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.errors import InputError
from fibersweep.fiber.effects import EFFECTS, DynamicsContext, build_effects
from fibersweep.fiber.effects.off_midplane import KERNEL_SECOND_MOMENT, layer_factor
from fibersweep.fiber.hydro.rpy import body_mobility
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate_for
from fibersweep.flow.field import FlowField, ib_phi
from fibersweep.units import Geometry

CTX = DynamicsContext(bead_radius=2.0, dx=4.0, depth=40.0)


def test_registry_lists_valid_names_on_unknown():
    with pytest.raises(InputError) as exc:
        build_effects({"frictoin": 0.2})
    msg = str(exc.value)
    assert "frictoin" in msg and "friction" in msg
    for name in ("friction", "pillar_hydro", "off_midplane", "brownian"):
        assert name in EFFECTS and name in msg


def test_zero_effects_are_dropped_and_nothing_reaches_the_kernel():
    es = build_effects({name: 0.0 for name in EFFECTS})
    assert es.effects == ()
    assert es.kernel(CTX) == ()
    assert not es.random


def test_kernel_records_are_sorted_by_name():
    """One set of effects gives one tuple type whatever the order it was named in
    (one compiled integrator per set)."""
    a = build_effects({"pillar_hydro": 1.0, "friction": 0.3, "off_midplane": 0.1}).kernel(CTX)
    b = build_effects({"off_midplane": 0.1, "friction": 0.3, "pillar_hydro": 1.0}).kernel(CTX)
    assert [type(r) for r in a] == [type(r) for r in b]
    assert [type(r).__name__ for r in a][0].startswith("Friction")


@pytest.mark.parametrize(
    "name, value",
    [
        ("friction", -1.0),
        ("pillar_hydro", -0.5),
        ("off_midplane", 0.5),
        ("brownian", -2.0),
        ("friction", math.nan),
    ],  # fmt: skip
)
def test_out_of_range_values_name_the_effect(name, value):
    with pytest.raises(InputError, match=f"effects.{name}"):
        build_effects({name: value})


def test_off_midplane_factor_against_discrete_kernel_average():
    """Kernel-averaged parabola ratio vs a direct sum over z nodes with the IB kernel:
    u(z) ∝ 1 − 4ζ²/H² sampled on nodes Δx apart, weighted by φ((z_c − z)/Δx). The
    closed form uses the continuous second moment 4/3 − 8/π²; the discrete sum depends on
    where the centre falls between nodes: tolerance 0.5 % at Δx/H = 0.1."""
    H, dx = 40.0, 4.0
    z = (np.arange(int(H / dx)) + 0.5) * dx

    def avg(zc):
        w = np.array([ib_phi((zc - zz) / dx) for zz in z])
        return np.sum(w * (1 - 4 * (z - H / 2) ** 2 / H**2)) / np.sum(w)

    for dz in (0.05, 0.1, 0.2):
        direct = avg(H / 2 + dz * H) / avg(H / 2)
        assert layer_factor(dz, dx, H) == pytest.approx(direct, rel=5e-3)
    assert layer_factor(0.0, dx, H) == 1.0
    assert KERNEL_SECOND_MOMENT == pytest.approx(
        sum(ib_phi(r) * r * r for r in np.linspace(-2, 2, 400001)) * 1e-5, rel=1e-4
    )


def test_off_midplane_slows_the_fiber():
    geo = Geometry(width=400, depth=40, length=400, pillar_height=20, pillar_x=370,
                   pillar_y_base=20)  # fmt: skip
    field = FlowField.from_function(lambda X, Y: (600.0 + 0 * X, 0 * X), geo, 4.0)
    st = FiberSettings(x0=100.0, effects={"off_midplane": 0.2})
    tr, _ = simulate_for(field, st, FiberStart(0.0, 9.0, 1.5), 0.1)
    speed = (tr.x[-1] - tr.x[0]) / (tr.t[-1] - tr.t[0])
    assert speed == pytest.approx(600.0 * layer_factor(0.2, 4.0, 40.0), rel=1e-9)


def test_brownian_diffusion_matches_the_body_mobility():
    """Zero flow: E[Δθ²] = 2 kT N_rr t and E[|Δr|²] = 2 kT (N_xx + N_yy) t (exact for
    Euler-Maruyama with this constant-in-body-frame mobility). 300 seeds: the variance
    estimate has 8 % relative standard error; tolerance 30 %."""
    geo = Geometry(width=400, depth=40, length=400, pillar_height=20, pillar_x=370,
                   pillar_y_base=20)  # fmt: skip
    field = FlowField.from_function(lambda X, Y: (0 * X, 0 * X), geo, 4.0)
    mult = 1e5
    st = FiberSettings(x0=150.0, effects={"brownian": mult})
    start = FiberStart(0.0, 9.0, 1.0)
    T = 1.0
    dth, dr2 = [], []
    for seed in range(300):
        tr, reason = simulate_for(field, st, start, T, rng_seed=seed)
        assert reason == ""
        dth.append(math.radians(tr.theta[-1] - tr.theta[0]))
        dr2.append((tr.x[-1] - tr.x[0]) ** 2 + (tr.y[-1] - tr.y[0]) ** 2)
    kT = mult * 1.380649e-5 * 295.0
    n = 6  # round(23.09 / 4)
    bm = body_mobility(n, 2.0, 0.34)
    assert np.var(dth) == pytest.approx(2 * kT * bm.N[2, 2] * T, rel=0.3)
    assert np.mean(dr2) == pytest.approx(2 * kT * (bm.N[0, 0] + bm.N[1, 1]) * T, rel=0.3)
    # reproducible with the seed
    a, _ = simulate_for(field, st, start, T, rng_seed=3)
    b, _ = simulate_for(field, st, start, T, rng_seed=3)
    np.testing.assert_array_equal(a.theta, b.theta)


def test_pillar_hydro_slows_a_fiber_passing_the_pillar():
    """Uniform flow, fiber tilted 5° just below the pillar base (no contact): the body
    velocity with the pillar's wall drag is (R + Kᵀ Z K)⁻¹ R V₀, Z from the Faxén law
    ζ = k 6πμa β/(1 − β) exp(−(h − a)/H), β = 9a/16h, all computed here in numpy from
    the dense RPY matrix. Tolerance 1e-9 (round-off)."""
    from fibersweep.fiber.contact.pillar import outline_distance
    from fibersweep.fiber.hydro.rpy import fiber_offsets, rigid_map, rpy_matrix

    geo = Geometry()
    field = FlowField.from_function(lambda X, Y: (600.0 + 0 * X, 0 * X), geo, 4.0)
    k_h, a, mu = 0.5, 2.0, 0.34
    xc = geo.base_center[0]
    d = 6.0  # centre 6 µm below the base
    start = FiberStart(5.0, -d / geo.pillar_height, 0.5)
    vel = []
    for eff in ({}, {"pillar_hydro": k_h}):
        tr, _ = simulate_for(field, FiberSettings(x0=xc, effects=eff), start, 1e-4)
        vel.append((tr.com_speed[0], tr.theta[1] - tr.theta[0]))
    n = 11
    off = fiber_offsets(n, a)
    th = math.radians(5.0)
    bx = xc + off * math.cos(th)
    by = geo.base_center[1] - d + off * math.sin(th)
    h = np.array([outline_distance(x, y, geo.vertices) for x, y in zip(bx, by, strict=True)])
    beta = 9 / 16 * a / np.maximum(h, a)
    zeta = k_h * 6 * math.pi * mu * a * beta / (1 - beta) * np.exp(-(np.maximum(h, a) - a) / 40.0)
    kmat = rigid_map(off)
    r = kmat.T @ np.linalg.solve(rpy_matrix(np.column_stack([off, 0 * off]), a, mu), kmat)
    v0 = np.array([600 * math.cos(th), -600 * math.sin(th), 0.0])  # body frame
    v = np.linalg.solve(r + kmat.T @ np.diag(np.repeat(zeta, 2)) @ kmat, r @ v0)
    assert vel[0][0] == pytest.approx(600.0, rel=1e-12)
    assert vel[1][0] == pytest.approx(math.hypot(v[0], v[1]), rel=1e-9)
    assert vel[1][0] < 0.99 * 600.0  # the effect is really probed
    assert vel[0][1] == pytest.approx(0.0, abs=1e-12) and vel[1][1] != 0.0  # it also turns


def test_coulomb_friction_sticks_or_slides():
    """One contacting bead (the head) with its contact force along +y (body frame = lab,
    θ = 0): strong friction stops its tangential (x) motion exactly; weak friction gives
    |F_t| = μ F_n and only slows it. Tolerances: round-off."""
    from fibersweep.fiber.effects.friction import coulomb_friction
    from fibersweep.fiber.hydro.rpy import fiber_offsets

    n = 8
    s = fiber_offsets(n, 2.0)
    nm = body_mobility(n, 2.0, 0.34).N
    fx = np.zeros(n)
    fy = np.zeros(n)
    fy[-1] = 100.0
    ft = np.zeros(n)
    v0 = (50.0, 0.0, 0.3)  # frictionless body velocity: head slides along +x

    def head_vx(v):
        return v[0]  # Ω ẑ × (s, 0) has no x part

    v = coulomb_friction(1.0, 0.0, s, nm, fx, fy, 1000.0, *v0, ft)  # needs ~3600 pN
    assert head_vx(v) == pytest.approx(0.0, abs=1e-9)
    assert abs(ft[-1]) == pytest.approx(50.0 / nm[0, 0], rel=1e-12) and abs(ft[-1]) < 1e5
    v = coulomb_friction(1.0, 0.0, s, nm, fx, fy, 0.01, *v0, ft)
    assert abs(ft[-1]) == pytest.approx(0.01 * 100.0, rel=1e-12)
    assert 0.0 < head_vx(v) < 50.0
    assert ft[:-1].tolist() == [0.0] * (n - 1)
