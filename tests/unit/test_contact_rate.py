"""The contact force's decay rate that bounds the rigid model's explicit step.

fibersweep.fiber.integrators.contact_rate: without a mobility hook it is the former
bound m_tip Σ k_i bit for bit; beside a wall (``near_wall``) it is Σ k_i g_iᵀ N' g_i,
which must bound the largest decay rate of the body velocity's Jacobian (measured by
central differences of the rigid model's velocity) and, for one bead, equal it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.fiber.contact.pillar import SMOOTH, Pillar
from fibersweep.fiber.effects import DynamicsContext
from fibersweep.fiber.effects.near_wall import NearWall
from fibersweep.fiber.frame import CHANNEL
from fibersweep.fiber.integrators.contact_rate import contact_rate
from fibersweep.fiber.kernel.bundles import FlowArrays, assemble, make_params
from fibersweep.fiber.models.rigid import rigid_velocity
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate

A = 2.0  # bead radius [µm]
MU = 1.0 / (6.0 * math.pi * A)  # 6πμa = 1
DELTA = 0.05  # contact layer (the gap law's δ_r) [µm]
CIRCLE = np.array([20.0, 0.0, 40.0])  # a smooth circular pillar (x, y, R) [µm]


def _kernel(n: int, near_wall: bool):
    """A still fluid, the smooth circle with a contact layer DELTA, F_ref = 1 pN."""
    pillar = Pillar(SMOOTH, np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 3, 2)),
                    A + DELTA, A, 1.0, CIRCLE)  # fmt: skip
    flow = FlowArrays(np.zeros((64, 120)), np.zeros((64, 120)), 1.0)
    st = FiberSettings(bead_radius=A)
    params = make_params(st, mu=MU, u_center=1.0, x_stop=1e9, y_lo=-math.inf, y_hi=math.inf,
                         random=False, mode=1, t_stop=1.0)  # fmt: skip
    ctx = DynamicsContext(bead_radius=A, dx=1.0, depth=math.inf, viscosity=MU, n_beads=n,
                          pillar=pillar.arrays())  # fmt: skip
    effects = (NearWall(1.0).kernel(ctx),) if near_wall else ()
    return assemble(st, n, flow, pillar.arrays(), params, effects, CHANNEL)


def _rate_and_jacobian(k, q):
    """contact_rate at q = (x, y, θ) and the largest decay rate of −∂v/∂q there."""
    rigid_velocity(k.frame, k.flow, k.pillar, k.body, k.work, k.effects, *q)
    walls = [e for e in k.effects if hasattr(e, "nm")]  # the near_wall record holds N'
    nm_eff = walls[0].nm.copy() if walls else k.body.nm
    c, sn = math.cos(q[2]), math.sin(q[2])
    w = k.work
    rate = contact_rate(k.body.s, k.body.nm, nm_eff, k.body.tip_m, c, sn, w.fx, w.fy, w.st)
    stiff = float(w.st.sum())
    jac = np.empty((3, 3))
    for j in range(3):
        h = 1e-6 if j < 2 else 1e-6 / max(k.body.s[-1], 1e-6)  # ≪ DELTA: the law is resolved
        up = np.array(q, dtype=float)
        dn = np.array(q, dtype=float)
        up[j] += h
        dn[j] -= h
        vu = rigid_velocity(k.frame, k.flow, k.pillar, k.body, k.work, k.effects, *up)[:3]
        vd = rigid_velocity(k.frame, k.flow, k.pillar, k.body, k.work, k.effects, *dn)[:3]
        jac[:, j] = (np.array(vu) - np.array(vd)) / (2 * h)
    lam = float(np.max(-np.linalg.eigvals(jac).real))
    return rate, lam, stiff


def test_without_a_mobility_hook_the_rate_is_the_former_bound_bit_for_bit():
    """No effect: m_tip Σ k_i, the same product the step bound took before (bits)."""
    k = _kernel(5, near_wall=False)
    q = (20.0, 40.0 + A + 0.5 * DELTA, 0.0)  # lying on the pillar, its middle bead in the layer
    rate, lam, stiff = _rate_and_jacobian(k, q)
    assert stiff > 0.0
    assert rate == k.body.tip_m * stiff
    assert lam <= rate  # the former bound bounds it too


@pytest.mark.parametrize("depth_in_layer", [0.25, 0.5, 0.9])
def test_one_bead_beside_the_wall_the_rate_is_the_normal_modes(depth_in_layer):
    """A sphere inside the layer with ``near_wall``: the Jacobian's largest decay rate is
    k nᵀN'n, the contact's normal mode, within 1e-6. The central differences (1e-6 µm)
    stay inside the effect's reuse distance, so the wall terms are held, as in the model's
    own Jacobian: the velocity is N' F with one pair, whose Jacobian's normal eigenvalue is
    exactly k nᵀN'n (the pair law's tangential stiffness |F|/r, δ/(4r) ≈ 0.6 % of k, is a
    separate, slower mode); what is left is the differences' truncation, (1e-6/δ)² ≈ 4e-10,
    and rounding, about 1e-10. The wall's lubrication makes the rate at least 10 times
    smaller than the former bound m_tip k (λ⊥ ≈ a/h ≥ 40 at these gaps)."""
    k = _kernel(1, near_wall=True)
    h = DELTA * (1.0 - depth_in_layer)  # centre at r_eq + h from the outline
    q = (20.0, 40.0 + A + h, 0.0)
    rate, lam, stiff = _rate_and_jacobian(k, q)
    assert stiff > 0.0
    assert lam == pytest.approx(rate, rel=1e-6)
    assert rate <= k.body.tip_m * stiff / 10.0


def test_a_fiber_with_one_end_in_the_layer_is_bounded_by_the_rate():
    """A 6-bead fiber at 20° with its lower end inside the layer, ``near_wall`` on: the
    Jacobian's largest decay rate is at most the rate (the trace bound of N'G) plus the
    pair law's tangential stiffness the rate leaves out (δ/(4r) ≈ 0.6 % of k; allowed:
    10 %), and at least half of it (one bead in contact: the bound is nearly the mode);
    the rate is below m_tip Σ k."""
    k = _kernel(6, near_wall=True)
    th = math.radians(20.0)
    s0 = k.body.s[0]
    x = 20.0 - s0 * math.cos(th)  # bead 0 above the circle's top
    y = 40.0 + A + 0.5 * DELTA - s0 * math.sin(th)
    rate, lam, stiff = _rate_and_jacobian(k, (x, y, th))
    assert stiff > 0.0
    assert 0.5 * rate <= lam <= rate * 1.1
    assert rate < k.body.tip_m * stiff


def test_the_apex_run_with_all_on_keeps_its_outcome_in_the_steps_of_one_without(coarse_field):
    """The channel's rigid fiber with contact at the apex (y0/h 0.45, as the benchmarks),
    ``near_wall``, ``faxen``, curvature local (r_c 1 µm), gap law δ_r = 0.05 µm: with the
    former bound m_tip Σ k the run took 8859 steps (Above, δ = 0.1270769 h_obs); with the
    rate it keeps its class and δ within 1e-3 h_obs (the steps inside the layer are still
    bounded by the contact displacement, 0.02 µm: a path difference of that order, 1e-4 of
    h_obs, and 1e-3 leaves it ten times over; measured 1e-5) in at most 1.1 times the steps
    of the run without any of it (5302; measured 5149)."""
    off = FiberSettings()
    on = FiberSettings.model_validate(
        {**off.model_dump(),
         "contact": {**off.contact.model_dump(), "law": "gap", "gap_um": 0.05,
                     "curvature": "local", "corner_radius": 1.0},
         "effects": {"near_wall": 1.0, "faxen": 1.0}}
    )  # fmt: skip
    start = FiberStart(0.0, 0.45, 1.0)
    base = simulate(coarse_field, off, start)
    res = simulate(coarse_field, on, start)
    assert res.cls == "Above"
    assert res.delta == pytest.approx(0.1270769, abs=1e-3)
    assert res.n_steps <= 1.1 * base.n_steps
