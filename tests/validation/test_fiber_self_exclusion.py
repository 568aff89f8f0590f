"""A bead-spring fiber cannot pass through itself (``fiber.self_exclusion``, docs/flexible.md).

A soft fiber folded into a U is driven into itself by a converging flow, in the
three bead-spring integrators; and a stiff fiber past the pillar, whose distant
beads never meet, runs bit for bit the same with the setting on and off.
"""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.fiber.kernel import record as R
from fibersweep.fiber.kernel.bundles import FlowArrays, build_kernel
from fibersweep.fiber.models.exclusion import min_self_distance
from fibersweep.fiber.models.registry import get_integrator
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.setup import prepare

A = 2.0  # bead radius [µm]
PATHS = {  # integrator: its step settings; the fixed-step BDF2 and both Rosenbrock-W methods
    "bdf2": {},
    "ros2": {"tolerance": 1e-3},
    "ros34pw2": {"tolerance": 1e-5},
}


def _u_shape(xc, yc, n_arm=8, n_turn=4):
    """Bead centres (n, 2) of a U: two straight arms along x joined by n_turn joints turning
    180°/n_turn each; segments 2a (the springs' rest length). Arms 9.7 µm apart."""
    ang = np.concatenate(
        [np.zeros(n_arm), np.pi * (np.arange(1, n_turn) / n_turn), np.full(n_arm, np.pi)]
    )
    steps = 2 * A * np.column_stack([np.cos(ang), np.sin(ang)])
    b = np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)])
    return b - b.mean(axis=0) + np.array([xc, yc])


def _squeeze(field, yc, speed):
    """Flow u = (0, −speed · tanh((y − yc)/2 µm)) on the channel's grid: both arms of the
    U are driven towards the line y = yc, where they meet."""
    ny = field.ux.shape[1]
    yn = (np.arange(ny) + 0.5) * field.dx
    uy = -speed * np.tanh((yn - yc) / 2.0)
    return FlowArrays(
        np.zeros_like(field.ux), np.ascontiguousarray(np.broadcast_to(uy, field.uy.shape)),
        float(field.dx),
    )  # fmt: skip


def _squeezed_run(field, path, excl, t_stop=0.15):
    """Bead positions (rows, n, 2) of a 10 kPa U squeezed for t_stop [s] at 3 U_center."""
    st = FiberSettings(
        model="bead-spring", integrator=path, young_modulus=1e4, self_exclusion=excl,
        step=PATHS[path],
    )  # fmt: skip
    length = 20 * 2 * A / field.geometry.pillar_base_length  # 20 beads, as the U has
    setup = prepare(field, st, FiberStart(0.0, 0.45, length), np.random.default_rng(0))
    k = build_kernel(setup, mode=1, t_stop=t_stop)
    beads0 = _u_shape(setup.x0, setup.y0_abs)
    k = k._replace(flow=_squeeze(field, setup.y0_abs, 3.0 * setup.u_center))
    return k, beads0


def _run(k, beads0, path):
    rec, beads, code = get_integrator("bead-spring", path).integrate(k, 0.0, 0.0, 0.0, beads0)
    assert code == R.TIME_REACHED, R.STOP_REASONS.get(int(code))
    return rec, beads


@pytest.mark.parametrize("path", list(PATHS))
def test_fiber_driven_into_itself_does_not_pass_through(coarse_field, path):
    """A 10 kPa fiber folded into a U (arms 9.7 µm apart) in a flow converging on the U's
    axis at 3 U_center (a drag of up to ~3 F_ref per bead) for 0.15 s, ~50 times the
    3 ms the arms need to meet. Without self-exclusion the arms slide onto each other: the
    smallest distance between beads |i − j| >= 2 falls below a (measured: 0.000 µm, all
    three paths). With it, it stays above 2a (1 − 0.1): the contact law gives |F| = F_ref at
    2a and ~12 F_ref at 0.9 · 2a, so 10 % covers the load (measured: 3.849 µm = 0.962 · 2a,
    all three paths, 3.883 µm at the end); the run ends with the arms pressed together
    (closer than the cutoff)."""
    k, beads0 = _squeezed_run(coarse_field, path, True)
    assert k.body.s.shape[0] == beads0.shape[0]
    _, beads = _run(k, beads0, path)
    d_on = min_self_distance(beads)
    k_off, _ = _squeezed_run(coarse_field, path, False)
    _, beads_off = _run(k_off, beads0, path)
    d_off = min_self_distance(beads_off)
    assert d_off < A, f"{path}: without self-exclusion the arms stay {d_off:.2f} µm apart"
    assert d_on > 2 * A * (1 - 0.1), f"{path}: smallest non-neighbour distance {d_on:.3f} µm"
    assert min_self_distance(beads[-1]) < k.params.excl_cut  # the arms do touch at the end


@pytest.mark.parametrize("path", ["ros2", "ros34pw2", pytest.param("bdf2", marks=pytest.mark.slow)])
def test_stiff_fiber_is_bit_identical_with_and_without(coarse_field, path):
    """A 26 MPa fiber (L = 0.6 l_obs, apex contact) past the pillar: its distant beads never
    come within the cutoff, so every recorded row and bead position is the same bit for bit
    with ``self_exclusion`` on and off (tolerance: none)."""
    out = []
    for excl in (True, False):
        st = FiberSettings(
            model="bead-spring", integrator=path, self_exclusion=excl, step=PATHS[path]
        )
        setup = prepare(coarse_field, st, FiberStart(0.0, 0.45, 0.6), np.random.default_rng(0))
        k = build_kernel(setup)
        integrator = get_integrator("bead-spring", path)
        out.append(integrator.integrate(k, setup.x0, setup.y0_abs, setup.th0, None))
    (r1, b1, c1), (r0, b0, c0) = out
    assert c1 == c0 == R.PASSED
    assert np.any(r1[:, R.CONTACT] > 0)  # it did touch the pillar
    assert np.array_equal(r1, r0, equal_nan=True)
    assert np.array_equal(b1, b0)
    assert min_self_distance(b1) > 1.5 * 2 * A


@pytest.mark.parametrize("path", ["bdf2", "ros2"])
def test_kernel_jacobians_hold_the_pairs(coarse_field, path):
    """Both Jacobians of the model (analytic ``force_jacobian`` of the Rosenbrock-W path, and
    ``force_jacobian_fd`` of the fixed step) of a U whose arms are pressed together
    (0.95 · 2a apart, far from the pillar) against central differences (step 1e-6 µm) of
    the chain's whole force, springs and pairs: within 1e-6 of max |J| (truncation and
    round-off ~1e-8 relative; a missing pair block is O(1)). The fixed step reports that
    J left its band, so its W = M J is taken dense."""
    from fibersweep.fiber.models.beadspring import bead_velocity, force_jacobian, force_jacobian_fd

    st = FiberSettings(model="bead-spring", integrator=path, young_modulus=1e4)
    length = 20 * 2 * A / coarse_field.geometry.pillar_base_length
    setup = prepare(coarse_field, st, FiberStart(0.0, 0.45, length), np.random.default_rng(0))
    k = build_kernel(setup)
    flow, pillar, body, p, w, bw, effects, frame = k
    b = _u_shape(setup.x0, setup.y0_abs)  # arms: beads 0-8 and 11-19
    b[11:, 1] -= (b[11, 1] - b[0, 1]) - 0.95 * 2 * A  # second arm 0.95 · 2a from the first

    def force(q):
        w.x[:] = q[0::2]
        w.y[:] = q[1::2]
        bead_velocity(frame, flow, pillar, body, p, w, bw, effects)
        return np.column_stack([w.fx, w.fy]).reshape(-1).copy()

    q0 = b.reshape(-1).copy()
    h = 1e-6
    ref = np.empty((q0.size, q0.size))
    for c in range(q0.size):
        qp = q0.copy()
        qp[c] += h
        qm = q0.copy()
        qm[c] -= h
        ref[:, c] = (force(qp) - force(qm)) / (2 * h)
    force(q0)
    assert np.max(w.dist) > pillar.r_cut  # no pillar contact: F is springs and pairs
    if path == "bdf2":
        dense = force_jacobian_fd(frame, pillar, p, w, bw)
        assert dense
    else:
        force_jacobian(frame, pillar, p, w, bw)
    scale = np.max(np.abs(ref))
    assert np.max(np.abs(bw.jac - ref)) < 1e-6 * scale
