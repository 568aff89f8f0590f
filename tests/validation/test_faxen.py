"""Validation of the ``faxen`` effect: a bead carried by the flow averaged over its surface.

Faxén's first law gives the exact velocity of a force-free sphere of radius a in a
Stokes flow that is at most quadratic: U = u + (a²/6)∇²u at its centre. In the plane
Poiseuille flow u = U₀(1 − (y − y_c)²/b²) x̂ that is U₀(1 − (y − y_c)²/b² − a²/(3b²)); in
a shear it is the flow at the centre. The effect adds the field's 5-point Laplacian,
computed once on the field's lattice, to the nodes the beads sample, so the
correction it adds is exact for a quadratic field; what remains is the interpolation of
u itself, the same with and without the effect.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.fiber.contact.pillar import ROUGH, Pillar
from fibersweep.fiber.effects import DynamicsContext, build_effects
from fibersweep.fiber.effects.faxen import Faxen, lattice_laplacian
from fibersweep.fiber.frame import CHANNEL, lattice
from fibersweep.fiber.kernel.bundles import FlowArrays, assemble, make_params
from fibersweep.fiber.models.beadspring import bead_velocity
from fibersweep.fiber.models.rigid import rigid_velocity, run_rigid
from fibersweep.flow.field import interpolate_ib

A = 3.0  # bead radius [µm]
MU = 1.0 / (6.0 * math.pi * A)
DX = 1.0
NX, NY = 64, 120
U0, YC, B = 5.0, 60.0, 50.0  # Poiseuille: centre speed [µm/s], centreline, half-width [µm]
# a pillar far away with no beads: no contact, nothing near
FAR = np.array([[-2000.0, -900.0], [2000.0, -900.0], [2000.0, -800.0], [-2000.0, -800.0]])


def _pillar() -> Pillar:
    return Pillar(ROUGH, FAR, np.zeros((0, 2)), np.zeros((0, 3, 2)), 1.1 * A, A, 1.0, np.zeros(3))


def _field(ux_of, uy_of) -> FlowArrays:
    xs = (np.arange(NX) + 0.5) * DX
    ys = (np.arange(NY) + 0.5) * DX
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    ux = np.ascontiguousarray(ux_of(gx, gy) + 0.0 * gx)
    uy = np.ascontiguousarray(uy_of(gx, gy) + 0.0 * gx)
    return FlowArrays(ux, uy, DX)


def _poiseuille() -> FlowArrays:
    return _field(lambda x, y: U0 * (1.0 - ((y - YC) / B) ** 2), lambda x, y: 0.0 * x)


def _kernel(flow, n=1, strength=1.0, model="rigid", t_stop=1.0):
    ctx = DynamicsContext(bead_radius=A, dx=DX, depth=math.inf, viscosity=MU, n_beads=n,
                          pillar=_pillar().arrays(), flow=flow)  # fmt: skip
    st = FiberSettings(bead_radius=A, model=model)
    params = make_params(
        st, mu=MU, u_center=1.0, x_stop=1e9, y_lo=-math.inf, y_hi=math.inf, random=False,
        mode=1, t_stop=t_stop,
    )  # fmt: skip
    effects = build_effects({"faxen": strength})
    assert effects.kernel(ctx) == ()  # no kernel record: nothing to do per step
    sampled = effects.sample_flow(flow, A)
    return assemble(st, n, sampled, _pillar().arrays(), params, (), CHANNEL)


def _velocity(k, x, y, th=0.3):
    out = rigid_velocity(k.frame, k.flow, k.pillar, k.body, k.work, k.effects, x, y, th)
    return np.array(out[:3])


def _interp(flow, x, y):
    u = np.zeros((1, 2))
    interpolate_ib(flow.ux, flow.uy, flow.dx, np.array([x]), np.array([y]), u)
    return u[0]


def test_the_lattice_laplacian_is_exact_for_a_quadratic_flow():
    """The 5-point Laplacian of the Poiseuille nodes is −2U₀/b² at every interior node
        (1e-12 relative), and that of a linear flow is zero at interior nodes (1e-12 of its
    largest node speed over Δx²)."""
    f = _poiseuille()
    lx, ly = lattice_laplacian(f.ux, f.uy, f.dx)
    assert np.allclose(lx[:, 1:-1], -2.0 * U0 / B**2, rtol=1e-12, atol=0.0)
    assert not ly.any()
    s = _field(lambda x, y: 0.7 * y + 0.3 * x, lambda x, y: -0.2 * y)
    lx, ly = lattice_laplacian(s.ux, s.uy, s.dx)
    # x is periodic: a field linear in x wraps at the x edges, so interior nodes only
    assert np.abs(lx[1:-1, 1:-1]).max() <= 1e-12 * 0.7 * NY
    assert np.abs(ly[1:-1, 1:-1]).max() <= 1e-12 * 0.2 * NY
    with pytest.raises(ValueError, match="2-D"):
        lattice_laplacian(np.zeros(3), np.zeros(3), 1.0)


@pytest.mark.parametrize("y", [60.0, 71.3, 90.6])
def test_a_sphere_in_a_poiseuille_flow_moves_with_faxens_velocity(y):
    """A force-free sphere (one bead) in the plane Poiseuille flow: its velocity with the
    effect minus without is Faxén's −U₀a²/(3b²) (1e-12 relative), none across (1e-12 of
    U₀); with the interpolation's own error (the cosine kernel's moments: its second moment
    at most 0.5429 Δx², its first at most 0.0211 Δx) it is Faxén's exact U₀(1 − ŷ² − a²/(3b²));
    through the integrator it travels that velocity for 1 s at constant y (1e-9)."""
    f = _poiseuille()
    on, off = _kernel(f), _kernel(f, strength=0.0)
    x = 20.37
    v_on, v_off = _velocity(on, x, y), _velocity(off, x, y)
    faxen = -U0 * A * A / (3.0 * B * B)
    # the term is read from the summed nodes u + c∇²u: the difference of two reads
    # carries their rounding, a few ulps of U0 (1e-14 U0), not of the term (1e-3 U0)
    assert v_on[0] - v_off[0] == pytest.approx(faxen, abs=1e-14 * U0)
    assert abs(v_on[1]) <= 1e-12 * U0
    exact = U0 * (1.0 - ((y - YC) / B) ** 2 - A * A / (3.0 * B * B))
    # the cosine kernel reads a quadratic with its moments: second 0.5 to 0.5429 Δx²,
    # first at most 0.0211 Δx in size (over every position between nodes)
    interp_err = U0 * (0.5429 * DX**2 + 2 * 0.0211 * DX * abs(y - YC)) / B**2
    assert v_on[0] == pytest.approx(exact, abs=interp_err)
    assert v_off[0] == pytest.approx(_interp(f, x, y)[0], rel=1e-12)
    rec, _, _ = run_rigid(on, x, y, 0.3)
    t, xe, ye = rec[-1, 0], rec[-1, 1], rec[-1, 2]
    assert t == pytest.approx(1.0, rel=1e-12)
    assert (xe - x) / t == pytest.approx(v_on[0], rel=1e-9)
    assert ye == pytest.approx(y, abs=1e-9)


def test_a_sphere_in_a_shear_flow_moves_with_the_flow_at_its_centre():
    """In a linear (shear and extension) flow the Laplacian vanishes: the velocity with the
    effect equals that without (1e-12 of the speed)."""
    f = _field(lambda x, y: 0.7 * (y - YC) + 2.0, lambda x, y: 0.1 * (x - 30.0))
    v_on, v_off = _velocity(_kernel(f), 30.2, 66.1), _velocity(_kernel(f, strength=0.0), 30.2, 66.1)
    assert np.allclose(v_on, v_off, rtol=0.0, atol=1e-12 * np.abs(v_off).max())


def test_a_fiber_and_a_chain_get_the_term_at_every_bead():
    """A 5-bead rigid fiber at 30° in the Poiseuille flow: the body velocity changes by the
    rigid projection of the uniform Faxén velocity −U₀a²/(3b²) x̂ (translation by it, no
    rotation: 1e-12); the bead-spring chain's bead velocities change by it at every bead
    (1e-12)."""
    f = _poiseuille()
    faxen = -U0 * A * A / (3.0 * B * B)
    on, off = _kernel(f, n=5), _kernel(f, n=5, strength=0.0)
    d = _velocity(on, 30.0, 64.0, 0.52) - _velocity(off, 30.0, 64.0, 0.52)
    assert d[0] == pytest.approx(faxen, abs=1e-14 * U0)  # rounding of U0, as above
    assert abs(d[1]) <= 1e-12 * U0 and abs(d[2]) <= 1e-12 * U0 / A
    out = []
    for k in (_kernel(f, n=3, model="bead-spring"), _kernel(f, n=3, strength=0.0,
                                                            model="bead-spring")):  # fmt: skip
        xs = 30.0 + 2.0 * A * np.arange(3) * math.cos(0.4)
        ys = 62.0 + 2.0 * A * np.arange(3) * math.sin(0.4)
        k.work.x[:] = xs
        k.work.y[:] = ys
        bead_velocity(k.frame, k.flow, k.pillar, k.body, k.params, k.work, k.bead, k.effects)
        out.append(k.bead.f.copy())
    diff = out[0] - out[1]
    assert np.allclose(diff[0::2], faxen, rtol=0.0, atol=1e-14 * U0)
    assert np.abs(diff[1::2]).max() <= 1e-12 * U0


def test_the_lattice_frame_reads_the_term_at_the_folded_position():
    """In an array frame the beads sample the summed nodes as they sample u. On a cell field
    periodic under the array's images (u = U₀(1 + 0.3 cos 2π(y − εx)/λ), padded by 3 nodes
    as an array run pads it), a bead and its images one row along x (shifted ελ) and one
    period along y get the same velocity (1e-14 U₀), and it differs from the velocity
    without the effect by a²/6 times the Laplacian read at the folded position (1e-14 U₀)."""
    from fibersweep.geometry.array import PillarArray

    lam, eps, pad = 40.0, 0.1, 3
    arr = PillarArray(pillar_shape="circle", pillar_size=10.0, period_x=lam, period_y=lam,
                      shift=eps, depth=40.0)  # fmt: skip
    n = int(lam / DX) + 2 * pad
    c = (np.arange(n) + 0.5) * DX - pad * DX  # node positions in the cell's coordinates
    gx, gy = np.meshgrid(c, c, indexing="ij")
    ux = np.ascontiguousarray(U0 * (1.0 + 0.3 * np.cos(2 * math.pi * (gy - eps * gx) / lam)))
    f = FlowArrays(ux, np.zeros_like(ux), DX)
    st = FiberSettings(bead_radius=A)
    params = make_params(st, mu=MU, u_center=1.0, x_stop=1e9, y_lo=-math.inf, y_hi=math.inf,
                         random=False, mode=1, t_stop=1.0)  # fmt: skip
    points = ((20.3, 21.7), (20.3 + lam, 21.7 + eps * lam), (20.3, 21.7 + lam))
    got = {}
    for k in (0.0, 1.0):
        flow = build_effects({"faxen": k}).sample_flow(f, A)
        kern = assemble(st, 1, flow, _pillar().arrays(), params, (), lattice(arr, pad, DX, 1))
        got[k] = [
            np.array(rigid_velocity(kern.frame, kern.flow, kern.pillar, kern.body, kern.work,
                                    kern.effects, x, y, 0.0)[:2])  # fmt: skip
            for x, y in points
        ]
    for v in got[1.0][1:]:
        assert np.allclose(v, got[1.0][0], rtol=0.0, atol=1e-14 * U0)
    lx, _ = lattice_laplacian(f.ux, f.uy, f.dx)
    u = np.zeros((1, 2))
    x0, y0 = points[0]
    interpolate_ib(lx, 0.0 * lx, DX, np.array([x0 + pad * DX]), np.array([y0 + pad * DX]), u)
    assert u[0, 0] != 0.0
    assert got[1.0][0][0] - got[0.0][0][0] == pytest.approx(A * A / 6.0 * u[0, 0], abs=1e-14 * U0)


def test_the_effect_is_registered_and_checks_its_range():
    """faxen = 0 is dropped (no record: off costs nothing); values outside [0, 2] are refused
    naming the field; k scales the term (1e-14)."""
    from fibersweep.errors import InputError

    assert build_effects({"faxen": 0.0}).effects == ()
    with pytest.raises(InputError, match="effects.faxen"):
        build_effects({"faxen": -0.1})
    f = _poiseuille()
    lx, ly = lattice_laplacian(f.ux, f.uy, f.dx)
    s = Faxen(2.0).sample_flow(f, A)
    assert np.allclose(s.ux - f.ux, 2.0 * A * A / 6.0 * lx, rtol=1e-14, atol=1e-14 * U0)
    assert s.dx == f.dx and not (s.uy - f.uy).any()
    assert build_effects({}).sample_flow(f, A) is f  # off: the field itself


def test_channel_and_array_runs_sample_the_summed_field(coarse_field):
    """Both run paths hand the kernels u + (a²/6)∇²u when the effect is on (1e-14 of the
    field's largest speed) and the field itself when it is off: the channel's
    (:func:`build_kernel`, on the tests' coarse field) and the array's (:func:`array_kernel`)."""
    from fibersweep.fiber.kernel.bundles import build_kernel
    from fibersweep.fiber.result import FiberStart
    from fibersweep.fiber.rows import PAD, array_kernel
    from fibersweep.fiber.setup import prepare
    from fibersweep.geometry.array import PillarArray

    a = 2.0
    for k in (0.0, 1.0):
        st = FiberSettings(bead_radius=a, effects={"faxen": k})
        setup = prepare(coarse_field, st, FiberStart(0.0, 0.8, 1.0), np.random.default_rng(0))
        flow = build_kernel(setup).flow
        lx, _ = lattice_laplacian(coarse_field.ux, coarse_field.uy, coarse_field.dx)
        scale = np.abs(coarse_field.ux).max()
        want = coarse_field.ux + k * a * a / 6.0 * lx
        assert np.allclose(flow.ux, want, rtol=0.0, atol=1e-14 * scale)
    arr = PillarArray(pillar_shape="circle", pillar_size=10.0, period_x=40.0, period_y=40.0,
                      shift=0.1, depth=40.0)  # fmt: skip

    class Cell:  # the part of a CellField the kernel reads
        array = arr
        dx = DX

        def extended(self, pad):
            n = int(40.0 / DX) + 2 * pad
            c = (np.arange(n) + 0.5) * DX - pad * DX
            gx, gy = np.meshgrid(c, c, indexing="ij")
            u = U0 * (1.0 + 0.3 * np.cos(2 * math.pi * (gy - 0.1 * gx) / 40.0))
            return np.ascontiguousarray(u), np.zeros_like(u)

    ux, uy = Cell().extended(PAD)
    lx, _ = lattice_laplacian(ux, uy, DX)
    for k in (0.0, 1.0):
        st = FiberSettings(bead_radius=A, effects={"faxen": k})
        kern = array_kernel(Cell(), st, 1, mu=MU, u_center=U0, x_end=1e9)
        assert np.allclose(kern.flow.ux, ux + k * A * A / 6.0 * lx, rtol=0.0, atol=1e-14 * U0)
