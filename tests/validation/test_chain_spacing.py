"""Validation of bead-spring chains finer than touching beads (``fiber.bead_spacing``).

One fiber (radius a = 2 µm, length 92 µm, E = 1 MPa) discretised with beads b = 2a,
a, a/2 and a/4 apart (23, 45, 89 and 177 beads; ``fibersweep/fiber/models/spacing.py``):

- statics against Euler-Bernoulli: a free chain loaded by balanced transverse forces
  (a uniform load, or a central point load) relaxes, in a quiescent fluid, to the
  deflection of the simply supported beam;
- dynamics: the relaxation rate of its slowest bending mode and its drag per unit
  length converge with the spacing, and the touching chain is within a few per cent
  of the converged values;
- through the shipped pillar array (triangles, dx = 4 µm): where the touching chain
  resolves the shape (E = 1 MPa) it moves as the finer chains do; where it does not
  (E = 0.1 MPa, the fiber bent round the pillar), b = a and b = a/2 agree.

The statics and the relaxation are integrated by ROS2 (tolerance 1e-4 µm) with the flow
replaced by zeros and the fiber far from the pillar.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.fiber.hydro.rpy import rpy_matrix
from fibersweep.fiber.integrators.rosenbrock import integrate_rosenbrock
from fibersweep.fiber.kernel import record as R
from fibersweep.fiber.kernel.bundles import FlowArrays, build_kernel
from fibersweep.fiber.models.beadspring import bead_velocity, force_jacobian
from fibersweep.fiber.models.spacing import offsets
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.setup import prepare

A = 2.0  # bead radius [µm]
E = 1e6  # [Pa]
B = E * math.pi * A**4 / 4  # [pN µm²]
LENGTH = 92.0  # [µm]: an odd number of beads at every spacing below
FRACS = (1.0, 0.5, 0.25, 0.125)  # b / 2a


def _kernel(field, frac, t_stop):
    """(setup, kernel) of a run far from the pillar, stopping at t_stop, flow set to zero."""
    st = FiberSettings(model="bead-spring", integrator="ros2", young_modulus=E,
                       bead_spacing=frac, step={"tolerance": 1e-4})  # fmt: skip
    start = FiberStart(0.0, 2.0, LENGTH / field.geometry.pillar_base_length)
    setup = prepare(field, st, start, np.random.default_rng(0))
    k = build_kernel(setup, mode=1, t_stop=t_stop)
    z = np.zeros_like(k.flow.ux)
    return setup, k._replace(flow=FlowArrays(z, z.copy(), k.flow.dx))


def _straight(setup, frac):
    s = offsets(setup.n, A, frac)
    return np.column_stack([setup.x0 + s, np.full(setup.n, setup.y0_abs)])


def _integrate(k, q0, fext):
    """Bead positions (rows, n, 2) and times of a run to k.params.t_stop under forces fext."""
    n = q0.shape[0]
    q = q0.reshape(-1).copy()
    state = np.array([0.0, math.nan, 0.0, 1e-6, 0.0])
    scratch = [np.zeros(2 * n) for _ in range(4)]
    brecs, ts = [], []
    while True:
        rec = np.empty((20_000, R.NCOLS))
        brec = np.empty((20_000, n, 2))
        rows, code = integrate_rosenbrock(q, state, k, rec, brec, *scratch,
                                          np.ascontiguousarray(fext).reshape(-1))  # fmt: skip
        brecs.append(brec[:rows])
        ts.append(rec[:rows, R.T])
        if code != R.CHUNK_FULL:
            assert code == R.TIME_REACHED, R.STOP_REASONS.get(code)
            return np.concatenate(brecs), np.concatenate(ts)


def _slowest_mode(k, q0):
    """(σ [1/s], mode (n, 2)) of the slowest bending mode of the linearised q̇ = M F(q)."""
    flow, pillar, body, p, w, bw, effects, frame = k
    w.x[:] = q0[:, 0]
    w.y[:] = q0[:, 1]
    bead_velocity(frame, flow, pillar, body, p, w, bw, effects)
    force_jacobian(frame, pillar, p, w, bw)
    lam, vec = np.linalg.eig(bw.mob @ bw.jac)
    lam = -lam.real
    order = np.argsort(lam)
    assert np.all(np.abs(lam[order[:3]]) < 1e-6 * lam[order[-1]])  # 2 translations, rotation
    return float(lam[order[3]]), vec[:, order[3]].real.reshape(-1, 2)


def _midpoint_sag(b):
    """Deflection [µm] of the middle bead (n odd) from the chord of the end beads."""
    n = b.shape[0]
    ch = (b[-1] - b[0]) / np.linalg.norm(b[-1] - b[0])
    return float(np.dot(b[n // 2] - 0.5 * (b[0] + b[-1]), np.array([-ch[1], ch[0]])))


@pytest.mark.parametrize("frac", FRACS)
@pytest.mark.parametrize("load", ["uniform", "central"])
def test_finer_chain_bends_as_euler_bernoulli(coarse_field, frac, load):
    """A free chain under balanced transverse loads relaxes (12 times the slowest
    bending mode's time) to the simply supported beam of span Λ = (n − 1) b:
    - uniform load q [pN/µm] (q b per bead, q b/2 at the ends) balanced by −qΛ/2 at the
      end beads: midpoint sag 5qΛ⁴/384B;
    - central point load P balanced by −P/2 at the end beads (a cantilever of Λ/2
      clamped at the middle, by symmetry, under the end load P/2): PΛ³/48B.
    Loads sized for a sag of 0.1 % of Λ (linear regime). S and B are the continuum
    fiber's at every spacing, so the sag is the beam's whatever b. Tolerance 0.5 %: the
    discrete beam's error is O((b/Λ)²), (b/Λ)² = 0.2 % at b = 2a. Measured (uniform,
    central): +0.16 %, +0.40 % at b = 2a; +0.03 %, +0.09 % at a; +0.001 %, +0.017 % at
    a/2; −0.007 %, −0.002 % at a/4."""
    setup, k = _kernel(coarse_field, frac, 1.0)
    n = setup.n
    assert n % 2 == 1
    b = frac * 2 * A
    span = (n - 1) * b
    q0 = _straight(setup, frac)
    sigma, _ = _slowest_mode(k, q0)
    fy = np.zeros(n)
    if load == "uniform":
        q = 1e-3 * span * 384 * B / (5 * span**4)
        fy[:] = q * b
        fy[0] = fy[-1] = q * b / 2 - 0.5 * q * span
        expected = 5 * q * span**4 / (384 * B)
    else:
        P = 1e-3 * span * 48 * B / span**3
        fy[n // 2] = P
        fy[0] = fy[-1] = -P / 2
        expected = P * span**3 / (48 * B)
    _, k = _kernel(coarse_field, frac, 12.0 / sigma)
    beads, _ = _integrate(k, q0, np.column_stack([np.zeros(n), fy]))
    assert _midpoint_sag(beads[-1]) == pytest.approx(expected, rel=0.005)


def _sigma_l4(field, frac):
    setup, k = _kernel(field, frac, 1.0)
    assert (setup.n - 1) * frac * 2 * A + 2 * A == pytest.approx(LENGTH)
    sigma, _ = _slowest_mode(k, _straight(setup, frac))
    return sigma


def test_bending_relaxation_rate_converges_with_spacing(coarse_field):
    """The slowest bending mode's rate σ of the 92 µm fiber (same L at every spacing):
    b = a, a/2, a/4 agree within 1 % (measured 48.45, 48.23, 48.17 1/s: the RPY line's
    continuum limit), and the touching chain is within 4 % of them (measured 49.15 1/s,
    2.0 % faster: its drag per unit length is 1–2 % lower, next test). All lie between the
    free-draining chain's rate and resistive force theory's, as the touching chain's
    does (tests/validation/test_fiber_flexible.py)."""
    s = {frac: _sigma_l4(coarse_field, frac) for frac in FRACS}
    ref = s[0.125]
    for frac in (0.5, 0.25):
        assert s[frac] == pytest.approx(ref, rel=0.01)
    assert s[1.0] == pytest.approx(ref, rel=0.04)
    mu = coarse_field.fluid.viscosity
    zeta_rft = 4 * math.pi * mu / (math.log(LENGTH / (2 * A)) + 0.5)
    zeta_fd = 6 * math.pi * mu * A / (2 * A)
    for v in s.values():
        assert B * 4.730**4 / (zeta_fd * LENGTH**4) < v < B * 4.730**4 / (zeta_rft * LENGTH**4)


@pytest.mark.parametrize("frac", [0.5, 0.125])
def test_finer_chain_relaxes_at_its_rate(coarse_field, frac):
    """The integrator on overlapping beads: the chain bent along its slowest mode (0.05 µm)
    decays at that mode's rate σ within 2 % over 2/σ (ROS2, tolerance 1e-4 µm)."""
    setup, k = _kernel(coarse_field, frac, 1.0)
    q0 = _straight(setup, frac)
    sigma, v = _slowest_mode(k, q0)
    v *= 0.05 / np.max(np.abs(v))
    _, k = _kernel(coarse_field, frac, 2.0 / sigma)
    beads, t = _integrate(k, q0 + v, np.zeros((setup.n, 2)))
    vv = v.reshape(-1) / np.linalg.norm(v)
    a0 = float(np.dot((beads[0] - q0).reshape(-1), vv))
    a1 = float(np.dot((beads[-1] - q0).reshape(-1), vv))
    assert -math.log(a1 / a0) / t[-1] == pytest.approx(sigma, rel=0.02)


def _drag_per_length(frac, mu):
    """(ζ∥, ζ⊥) [pN s/µm²]: total force per unit length and speed of the straight chain
    translating along and across its axis (RPY grand mobility solved for the forces)."""
    n = int(round((LENGTH - 2 * A) / (frac * 2 * A))) + 1
    s = offsets(n, A, frac)
    m = rpy_matrix(np.column_stack([s, np.zeros(n)]), A, mu)
    par = np.linalg.solve(m, np.tile([1.0, 0.0], n)).reshape(n, 2)[:, 0].sum() / LENGTH
    perp = np.linalg.solve(m, np.tile([0.0, 1.0], n)).reshape(n, 2)[:, 1].sum() / LENGTH
    return float(par), float(perp)


def test_drag_per_unit_length_converges_with_spacing():
    """The drag per unit length of the 92 µm chain of radius-a beads converges as b
    shrinks (the RPY line integral, whose overlapping branch keeps it finite): b = a and
    a/2 within 1 % of a/4 (measured along: 0.6925, 0.6938, 0.6941; across: 1.0380,
    1.0426, 1.0439 pN s/µm² at μ = 0.34 Pa s), the touching chain 1.0 % (along) and 2.1 %
    (across) lower (0.6872, 1.0220). All within 6 % of a cylinder of diameter 2a
    (Tirado & García de la Torre 1979, p = L/2a = 23: ζ∥ = 2πμ/(ln p − 0.207 + 0.980/p −
    0.133/p²) = 0.7191, ζ⊥ = 4πμ/(ln p + 0.839 + 0.185/p + 0.233/p²) = 1.0727): the fine
    chains lie 3.5 % (along) and 2.7 % (across) below it."""
    mu = 0.34
    z = {frac: _drag_per_length(frac, mu) for frac in FRACS}
    for frac in (0.5, 0.25):
        for i in (0, 1):
            assert z[frac][i] == pytest.approx(z[0.125][i], rel=0.01)
    assert z[1.0][0] == pytest.approx(z[0.125][0], rel=0.03)
    assert z[1.0][1] == pytest.approx(z[0.125][1], rel=0.04)
    assert z[1.0][0] < z[0.5][0] and z[1.0][1] < z[0.5][1]
    p = LENGTH / (2 * A)
    par = 2 * math.pi * mu / (math.log(p) - 0.207 + 0.980 / p - 0.133 / p**2)
    perp = 4 * math.pi * mu / (math.log(p) + 0.839 + 0.185 / p + 0.233 / p**2)
    for zz in z.values():
        assert zz[0] == pytest.approx(par, rel=0.06)
        assert zz[1] == pytest.approx(perp, rel=0.06)


@pytest.fixture(scope="module")
def array_field():
    """Triangles 40 µm high, 80 µm periods, ε = 0.1, at dx = 4 µm (one cell)."""
    from fibersweep.config.flow import FlowSettings
    from fibersweep.flow.cell import field_of, solve_cell

    flow = FlowSettings.model_validate({"dx": 4.0, "array": {}})
    return field_of(flow, solve_cell(flow))


def _through_rows(field, E_pa, frac, y0, length):
    from fibersweep.fiber.run import simulate

    st = FiberSettings(model="bead-spring", integrator="ros2", young_modulus=E_pa,
                       bead_spacing=frac, array_rows=5)  # fmt: skip
    r = simulate(field, st, FiberStart(0.0, y0, length))
    assert r.status == "ok" and r.rows == 5, r
    return r


def test_touching_chain_moves_as_the_finer_ones_where_it_resolves_the_shape(array_field):
    """E = 1 MPa, L = 60 µm through 5 rows from y0 = 0.6 (largest curvature 0.015 1/µm,
    radius 30a): b = 2a, a and a/2 take the same mode; the touching chain's lateral shift
    per row is within 0.2 µm (2.3 %) of the finer chains' (its drag per unit length is
    1–2 % lower, test above; measured 8.714 against 8.789 and 8.793 µm) and its largest
    curvature within 20 % (measured 0.0156, 0.0143, 0.0135 1/µm: a three-bead estimate)."""
    r = {frac: _through_rows(array_field, 1e6, frac, 0.6, 60.0) for frac in (1.0, 0.5, 0.25)}
    assert r[1.0].mode == r[0.5].mode == r[0.25].mode == "displacement"
    for frac in (0.5, 0.25):
        assert abs(r[1.0].shift_per_row - r[frac].shift_per_row) < 0.2
        assert r[1.0].max_curvature == pytest.approx(r[frac].max_curvature, rel=0.2)


@pytest.mark.parametrize("y0", [0.6, 0.9])
def test_finer_chains_agree_where_the_touching_one_does_not_resolve(array_field, y0):
    """E = 0.1 MPa, L = 48 µm bent round the pillars (wrap 11–16°): b = a and b = a/2
    (23 and 45 beads) take the same mode, their shift per row agrees within 0.05 µm
    (measured 0.004 µm at both starts), their largest curvature within 10 % and largest
    wrap within 1° (measured 6 % and 0.3° at y0 = 0.6, 0.2 % and 0.2° at 0.9): the
    spacing b = a is converged for these shapes."""
    a, b = (_through_rows(array_field, 1e5, frac, y0, 48.0) for frac in (0.5, 0.25))
    assert a.mode == b.mode
    assert abs(a.shift_per_row - b.shift_per_row) < 0.05
    assert a.max_curvature == pytest.approx(b.max_curvature, rel=0.1)
    assert abs(a.max_wrap - b.max_wrap) < 1.0
