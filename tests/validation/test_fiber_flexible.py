"""Validation of the adaptive bead-spring integrators ROS2 and ROS34PW2 (docs/flexible.md).

Every test runs with both Rosenbrock-W methods (``fiber.integrator``), same
tolerances. The fiber is integrated by :func:`integrate_rosenbrock` in a quiescent
fluid (the run's flow replaced by zeros, the fiber far from the pillar) or in a uniform shear,
and compared with analytic results: Euler-Bernoulli beam deflection, the
relaxation rate of the slowest bending mode, the elasto-viscous buckling
threshold in shear; and with the rigid model and the fixed-step bead-spring
model on the pillar.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.fiber.effects import registry
from fibersweep.fiber.hydro.rpy import fiber_offsets
from fibersweep.fiber.integrators.rosenbrock import integrate_rosenbrock
from fibersweep.fiber.kernel import record as R
from fibersweep.fiber.kernel.bundles import FlowArrays, build_kernel
from fibersweep.fiber.models.beadspring import bead_velocity, force_jacobian
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.fiber.setup import prepare

A = 2.0  # bead radius [µm]
METHODS = ("ros2", "ros34pw2")  # fiber.integrator


def _kernel(field, E, length, t_stop, flow=None, tol=1e-4, method="ros2"):
    """Kernel of a run far from the pillar in mode 1 (stop at t_stop), flow replaced."""
    step = {"tolerance": tol}
    st = FiberSettings(model="bead-spring", integrator=method, young_modulus=E, step=step)
    setup = prepare(field, st, FiberStart(0.0, 2.0, length), np.random.default_rng(0))
    k = build_kernel(setup, mode=1, t_stop=t_stop)
    if flow is None:
        z = np.zeros_like(k.flow.ux)
        flow = FlowArrays(z, z.copy(), k.flow.dx)
    # no trap rule in a quiescent fluid: the fiber is never in contact anyway
    return setup, k._replace(flow=flow)


def _integrate(k, q0, fext=None, h0=1e-6):
    """Positions (rows, n, 2) and times of an integration to k.params.t_stop."""
    q = q0.reshape(-1).copy()
    n = q0.shape[0]
    fext = np.zeros(2 * n) if fext is None else fext.reshape(-1).copy()
    state = np.array([0.0, math.nan, 0.0, h0, 0.0])
    scratch = [np.zeros(2 * n) for _ in range(4)]
    recs, brecs = [], []
    while True:
        rec = np.empty((20_000, R.NCOLS))
        brec = np.empty((20_000, n, 2))
        rows, code = integrate_rosenbrock(q, state, k, rec, brec, *scratch, fext)
        recs.append(rec[:rows])
        brecs.append(brec[:rows])
        if code != R.CHUNK_FULL:
            assert code == R.TIME_REACHED, R.STOP_REASONS.get(code)
            return np.concatenate(brecs), np.concatenate(recs)[:, R.T]


def _straight(setup, n):
    s = fiber_offsets(n, A)
    return np.column_stack([setup.x0 + s, np.full(n, setup.y0_abs)])


@pytest.mark.ci
@pytest.mark.slow
@pytest.mark.parametrize("method", METHODS)
def test_uniform_load_bends_as_euler_bernoulli(coarse_field, method):
    """A free fiber loaded by a uniform transverse load q [pN/µm] balanced by the two
    opposite point loads qΛ/2 at its end beads (Λ = (n-1)2a the span) is in equilibrium
    as a simply supported beam: midpoint sag below the chord 5 q Λ⁴ / (384 B),
    B = E π a⁴/4. Load chosen so that the sag is 0.1 % of Λ (linear regime).
    Tolerance 2 %: the discrete chain (22 beads) differs from the continuum beam by
    O((2a/Λ)²) ≈ 0.2 %, the end loads sit on beads of half a segment's load."""
    E = 1e6
    setup, _ = _kernel(coarse_field, E, 1.0, 1.0)
    n = setup.n
    span = (n - 1) * 2 * A
    B = E * math.pi * A**4 / 4
    q_load = 1e-3 * span * 384 * B / (5 * span**4)
    fy = np.full(n, q_load * 2 * A)
    fy[0] = fy[-1] = q_load * A - 0.5 * q_load * span
    fext = np.column_stack([np.zeros(n), fy])
    # run 12 relaxation times of the slowest mode: the sag is within e^-12 of equilibrium
    _, k = _kernel(coarse_field, E, 1.0, 1.0)
    sigma, _ = _slowest_bending_mode(k, _straight(setup, n))
    _, k = _kernel(coarse_field, E, 1.0, 12.0 / sigma, method=method)
    beads, _ = _integrate(k, _straight(setup, n), fext)
    b = beads[-1]
    mid = 0.5 * (b[0] + b[-1])
    chord = (b[-1] - b[0]) / np.linalg.norm(b[-1] - b[0])
    normal = np.array([-chord[1], chord[0]])
    sag = (
        float(np.dot(b[n // 2] - mid, normal))
        if n % 2
        else float(np.dot(0.5 * (b[n // 2] + b[n // 2 - 1]) - mid, normal))
    )
    expected = 5 * q_load * span**4 / (384 * B)
    assert sag == pytest.approx(expected, rel=0.02)


def _slowest_bending_mode(k, q0):
    """(σ [1/s], v (2n)) of the slowest non-zero mode of the linearised q̇ = M F(q)."""
    flow, pillar, body, p, w, bw, effects, frame = k
    n = q0.shape[0]
    w.x[:] = q0[:, 0]
    w.y[:] = q0[:, 1]
    bead_velocity(frame, flow, pillar, body, p, w, bw, effects)
    force_jacobian(frame, pillar, p, w, bw)
    lam, vec = np.linalg.eig(bw.mob @ bw.jac)
    lam = -lam.real
    order = np.argsort(lam)
    # three zero modes (two translations, one rotation), then the slowest bending mode
    assert np.all(np.abs(lam[order[:3]]) < 1e-6 * lam[order[-1]])
    i = order[3]
    return float(lam[i]), vec[:, i].real.reshape(n, 2)


@pytest.mark.ci
@pytest.mark.slow
@pytest.mark.parametrize("method", METHODS)
def test_bent_fiber_relaxes_at_the_bending_rate(coarse_field, method):
    """A fiber bent along the slowest bending mode of the linearised model (amplitude
    0.05 µm) decays as exp(-σt): the measured rate over 2/σ matches σ within 2 %
    (ROS2 with tol 1e-4 µm; the mode's own nonlinearity is O(amplitude²)).
    σ itself lies between the free-free Euler-Bernoulli rates B β⁴/(ζ⊥ L⁴), β = 4.730, of
    the free-draining chain (ζ⊥ = 6πμa / 2a, no hydrodynamic interactions: slower) and
    of resistive force theory (ζ⊥ = 4πμ/(ln(L/2a) + 0.5), local slender-body drag:
    faster). Measured: σ = 57.7 1/s at E = 1 MPa, 0.34 Pa s, L = 88 µm, between 32.8
    and 88.2 (0.65 of the RFT rate; RFT's local drag is known only to O(1/ln(L/a))).
    """
    E = 1e6
    setup, k = _kernel(coarse_field, E, 1.0, 1.0)
    n = setup.n
    q0 = _straight(setup, n)
    sigma, v = _slowest_bending_mode(k, q0)
    v *= 0.05 / np.max(np.abs(v))
    _, k = _kernel(coarse_field, E, 1.0, 2.0 / sigma, method=method)
    beads, t = _integrate(k, q0 + v)
    vv = v.reshape(-1) / np.linalg.norm(v)

    def amp(b):
        return float(np.dot((b - q0).reshape(-1), vv))

    a0 = amp(beads[0])
    a1 = amp(beads[-1])
    rate = -math.log(a1 / a0) / t[-1]
    assert rate == pytest.approx(sigma, rel=0.02)
    L = n * 2 * A
    B = E * math.pi * A**4 / 4
    mu = coarse_field.fluid.viscosity
    zeta_rft = 4 * math.pi * mu / (math.log(L / (2 * A)) + 0.5)
    zeta_fd = 6 * math.pi * mu * A / (2 * A)
    assert B * 4.730**4 / (zeta_fd * L**4) < sigma < B * 4.730**4 / (zeta_rft * L**4)


@pytest.mark.slow
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("start", [FiberStart(0.0, 0.45, 0.75), FiberStart(8.0, 0.351, 0.75)])
def test_stiff_limit_agrees_with_rigid(coarse_field, start, method):
    """At E = 26 MPa (the source's value) the ROS2 bead-spring run gives the rigid
    model's class, and δ within 0.01 (the rigid/bead-spring agreement the project
    requires of the fixed-step model, docs/validation/fiber-models.md)."""
    r = simulate(coarse_field, FiberSettings(x0=1100.0), start)
    st = FiberSettings(model="bead-spring", integrator=method, x0=1100.0)
    b = simulate(coarse_field, st, start)
    assert b.status == "ok" and r.status == "ok"
    assert b.cls == r.cls
    assert abs(b.delta - r.delta) < 0.01
    assert b.min_end_to_end > 0.999  # it stays straight


@pytest.mark.slow
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("E", [26e6, 0.1e6])
def test_ros2_matches_fixed_step_bead_spring(coarse_field, E, method):
    """Same model, two integrators: ROS2 (tol 0.01 µm) against the fixed Δt = 5e-5 s
    BDF2 (itself within 1e-5 in δ of Δt = 1e-6 s at 26 MPa,
    test_fiber_beadspring.py). Tolerances: same class, δ 2e-3, θ_c 0.5°."""
    start = FiberStart(8.0, 0.351, 0.75)
    fixed = FiberSettings(model="bead-spring", young_modulus=E, x0=1100.0)
    a = simulate(coarse_field, fixed, start)
    st = FiberSettings(model="bead-spring", integrator=method, young_modulus=E, x0=1100.0)
    b = simulate(coarse_field, st, start)
    assert a.cls == b.cls
    assert abs(a.delta - b.delta) < 2e-3
    assert abs(a.theta_c - b.theta_c) < 0.5


def _effect_cases():
    out = []
    for name, cls in sorted(registry.EFFECTS.items()):
        out.append(pytest.param(name, cls, id=name))
    return out


@pytest.mark.slow
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize(("name", "cls"), _effect_cases())
def test_every_effect_runs_or_is_refused(coarse_field, name, cls, method):
    """Each registered effect either runs in the ROS2 model (same class as the
    fixed-step bead-spring model with it, δ within 5e-3) or, if it does not list the
    model, is refused with an error naming the effect and the model."""
    from fibersweep.errors import InputError

    value = 0.2  # inside every effect's valid range
    start = FiberStart(8.0, 0.351, 0.75)
    st = FiberSettings(model="bead-spring", integrator=method, x0=1100.0, effects={name: value})
    if "bead-spring" not in cls.models:
        with pytest.raises(InputError, match=name):
            simulate(coarse_field, st, start, rng_seed=1)
        return
    b = simulate(coarse_field, st, start, rng_seed=1)
    a = simulate(coarse_field, st.model_copy(update={"integrator": "bdf2"}), start, rng_seed=1)
    assert b.status == "ok" and a.status == "ok"
    assert a.cls == b.cls
    assert abs(a.delta - b.delta) < 5e-3


def _growth_rate(field, E, mbar, method="ros2"):
    """Growth rate / ε̇ of a symmetric bending perturbation of a straight fiber held on
    the compressional axis of u = (-ε̇ (x - x0), ε̇ (y - y0)), with
    μ̄ = 8πμ ε̇ L⁴ / (B c), c = -ln(ε² e), ε = a/L (Young & Shelley 2007's number)."""
    setup, k = _kernel(field, E, 1.0, 1.0)
    n = setup.n
    L = n * 2 * A
    B = E * math.pi * A**4 / 4
    mu = field.fluid.viscosity
    c = -math.log((A / L) ** 2 * math.e)
    edot = mbar * B * c / (8 * math.pi * mu * L**4)
    nx, ny = k.flow.ux.shape
    dx = k.flow.dx
    # the field's nodes sit at cell centres, (i + 1/2) dx
    X, Y = np.meshgrid((np.arange(nx) + 0.5) * dx, (np.arange(ny) + 0.5) * dx, indexing="ij")
    flow = FlowArrays(-edot * (X - setup.x0), edot * (Y - setup.y0_abs), dx)
    s = fiber_offsets(n, A)
    # symmetric about the midpoint: the rotation (antisymmetric) is not excited
    d = 1e-3 * (np.cos(math.pi * s / L) + 0.3 * np.cos(3 * math.pi * s / L))
    q0 = np.column_stack([setup.x0 + s, setup.y0_abs + d])
    T = 6.0 / edot
    _, k = _kernel(field, E, 1.0, T, flow=flow, method=method)
    beads, t = _integrate(k, q0)

    def dev(b):
        ch = (b[-1] - b[0]) / np.linalg.norm(b[-1] - b[0])
        z = (b - b[0]) @ np.array([-ch[1], ch[0]])
        return float(np.std(z))

    i = int(np.searchsorted(t, T / 2))
    return math.log(dev(beads[-1]) / dev(beads[i])) / (t[-1] - t[i]) / edot


@pytest.mark.slow
@pytest.mark.parametrize("method", METHODS)
def test_compressed_fiber_buckles_at_the_elastoviscous_threshold(coarse_field, method):
    """Becker & Shelley (2001): a slender filament in shear buckles when
    η = 8πμγ̇L⁴/(B c) > 306.4, c = -ln(ε² e), ε = a/L; at 45° the shear compresses it
    at ε̇ = γ̇/2, so in a planar compressional flow along the fiber the threshold is
    μ̄ = 8πμ ε̇ L⁴/(B c) = 153.2 (Young & Shelley 2007). That number holds for the
    slender-body drag ζ⊥ = 8πμ/c; the bead chain's drag differs, and the threshold
    scales as 1/ζ⊥. The chain's ζ⊥ is measured independently by the relaxation rate σ
    of its slowest free bending mode (σ = B β⁴/(ζ⊥ L⁴), β = 4.730), giving the
    predicted threshold μ̄* = 153.2 σ / σ_SB (σ_SB with ζ⊥ = 8πμ/c): 109.6 here
    (E = 1 MPa, 22 beads). Tolerance 15 % (the buckling and relaxation mode shapes
    differ): the perturbation decays at 0.85 μ̄* and grows at 1.15 μ̄*.
    Measured: the growth rate crosses zero at μ̄ ≈ 107.6 (runs at 100, 110, 120),
    i.e. 0.70 of 153.2 unscaled, 0.98 of μ̄*."""
    E = 1e6
    setup, k = _kernel(coarse_field, E, 1.0, 1.0)
    n = setup.n
    sigma, _ = _slowest_bending_mode(k, _straight(setup, n))
    L = n * 2 * A
    B = E * math.pi * A**4 / 4
    c = -math.log((A / L) ** 2 * math.e)
    sigma_sb = B * 4.730**4 * c / (8 * math.pi * coarse_field.fluid.viscosity * L**4)
    pred = 153.2 * sigma / sigma_sb
    assert _growth_rate(coarse_field, E, 0.85 * pred, method) < 0.0
    assert _growth_rate(coarse_field, E, 1.15 * pred, method) > 0.0
