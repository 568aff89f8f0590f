"""The self-exclusion of non-neighbouring beads (fibersweep/fiber/models/exclusion.py).

Its law against the pillar contact's, its analytic Jacobian against central
differences, the balance of the pair forces, and the setting's plumbing.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.fiber.contact.pillar import ROUGH, PillarArrays, pillar_forces
from fibersweep.fiber.kernel.bundles import make_params
from fibersweep.fiber.models.exclusion import (
    GAP,
    exclusion_forces,
    exclusion_jacobian,
    min_self_distance,
)
from fibersweep.sweep.ids import fiber_result_settings

A = 2.0  # bead radius [µm]
CHI = 1.1  # fiber.contact.chi default
R_EQ = 2 * A
R_CUT = CHI * R_EQ
F_REF = 7690.0  # 6 pi mu a U for mu = 0.34 pN s/µm², U = 600 µm/s [pN]


def _forces(x, y, gap=GAP):
    fx = np.zeros_like(x)
    fy = np.zeros_like(y)
    pairs = exclusion_forces(x, y, gap, R_CUT, R_EQ, F_REF, fx, fy)
    return fx, fy, pairs


def _folded_chain(n=16, seed=0):
    """A chain of n beads 2a apart folded back on itself at bead n/2 (a hairpin whose arms
    are ~0.8-1.05 bead diameters apart) plus random jitter: many pairs inside the cutoff."""
    rng = np.random.default_rng(seed)
    half = n // 2
    x = np.concatenate([np.arange(half) * R_EQ, (half - 1 - np.arange(n - half)) * R_EQ + A])
    y = np.concatenate([np.zeros(half), np.full(n - half, R_EQ * 0.9)])
    return x + rng.uniform(-0.3, 0.3, n), y + rng.uniform(-0.3, 0.3, n)


def test_pair_law_is_the_rough_pillar_contact_law():
    """One fiber bead against one rough-pillar bead of the same radius (a_obs = a, so
    r_eq = 2a, R_ref = chi 2a) gets the force the pair law gives it, at distances from
    0.5 r_eq to beyond the cutoff: one contact model. Tolerance 1e-12 relative (the two
    codes evaluate the same formula)."""
    tiny = np.array([0.0, 0.0, 1e-12])  # a point-like outline at the pillar bead
    pil = PillarArrays(
        ROUGH, np.zeros((0, 2)), np.zeros(1), np.zeros(1), np.zeros((0, 3, 2)),
        R_CUT, R_EQ, F_REF, tiny,
    )  # fmt: skip
    for r in np.linspace(0.5 * R_EQ, 1.2 * R_CUT, 41):
        ang = 0.7
        bx = np.array([r * math.cos(ang)])
        by = np.array([r * math.sin(ang)])
        pf = [np.zeros(1) for _ in range(4)]
        pillar_forces(pil, bx, by, *pf)
        x = np.array([bx[0], 0.0, 0.0, 0.0])  # beads 0 and 3 (gap 3) at the same places
        y = np.array([by[0], 0.0, 0.0, 0.0])
        x[1:3] = [50.0, 60.0]  # middle beads far away
        fx, fy, _ = _forces(x, y, gap=3)
        assert fx[0] == pytest.approx(pf[0][0], rel=1e-12, abs=1e-12 * F_REF)
        assert fy[0] == pytest.approx(pf[1][0], rel=1e-12, abs=1e-12 * F_REF)
    # |F| = F_ref where the bead surfaces touch (r = 2a)
    fx, fy, pairs = _forces(np.array([0.0, 9.0, 99.0, R_EQ]), np.zeros(4), gap=3)
    assert pairs == 1 and math.hypot(fx[0], fy[0]) == pytest.approx(F_REF, rel=1e-12)


def test_zero_beyond_cutoff_and_for_neighbours():
    """Beads at or beyond R = chi 2a, and chain neighbours |i - j| < gap however close,
    get exactly zero force (not small: exactly 0.0, so far-apart fibers run bit for bit
    as without the force)."""
    x = np.array([0.0, 1.0, R_CUT, 2 * R_CUT, 2 * R_CUT + R_CUT * (1 + 1e-15)])
    y = np.zeros(5)
    fx, fy, pairs = _forces(x, y)
    # pairs |i-j| >= 2: (0,2) at R exactly, (0,3), (0,4), (1,3), (1,4), (2,4) all >= R
    assert pairs == 0
    assert np.all(fx == 0.0) and np.all(fy == 0.0)
    fx, fy, pairs = _forces(np.array([0.0, 0.5, 1.0]), np.zeros(3), gap=3)
    assert pairs == 0 and not np.any(fx)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_forces_sum_to_zero(seed):
    """Pair forces are equal and opposite and central: the total force and the total
    torque about the origin vanish to round-off (1e-12 of the sum of |F|)."""
    x, y = _folded_chain(seed=seed)
    fx, fy, pairs = _forces(x, y)
    assert pairs >= 5
    scale = np.sum(np.hypot(fx, fy))
    assert abs(fx.sum()) < 1e-12 * scale and abs(fy.sum()) < 1e-12 * scale
    torque = np.sum(x * fy - y * fx)
    assert abs(torque) < 1e-12 * scale * np.max(np.hypot(x, y))


def _fd_jacobian(x, y, h=1e-6):
    n = x.shape[0]
    jac = np.zeros((2 * n, 2 * n))
    for j in range(n):
        for comp, arr in enumerate((x, y)):
            arr[j] += h
            f1, g1, _ = _forces(x, y)
            arr[j] -= 2 * h
            f2, g2, _ = _forces(x, y)
            arr[j] += h
            jac[0::2, 2 * j + comp] = (f1 - f2) / (2 * h)
            jac[1::2, 2 * j + comp] = (g1 - g2) / (2 * h)
    return jac


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_jacobian_matches_central_differences(seed):
    """The analytic ∂F/∂q of a folded 16-bead chain against central differences (step
    1e-6 µm): within 1e-6 of max|J|. Tolerance: truncation O(h² F''') and round-off
    O(eps |F| / h) are ~1e-8 relative; a wrong term is O(1). Also: J is symmetric (F is a
    gradient), translations are zero modes, and it reports blocks outside the band."""
    x, y = _folded_chain(seed=seed)
    n = x.shape[0]
    jac = np.zeros((2 * n, 2 * n))
    far = exclusion_jacobian(x, y, GAP, R_CUT, R_EQ, F_REF, jac)
    ref = _fd_jacobian(x.copy(), y.copy())
    scale = np.max(np.abs(ref))
    assert scale > 0
    assert np.max(np.abs(jac - ref)) < 1e-6 * scale
    assert np.allclose(jac, jac.T, rtol=0, atol=1e-12 * scale)
    tx = np.tile([1.0, 0.0], n)
    ty = np.tile([0.0, 1.0], n)
    assert np.max(np.abs(jac @ tx)) < 1e-12 * scale * n
    assert np.max(np.abs(jac @ ty)) < 1e-12 * scale * n
    assert far  # the hairpin's arms couple beads far apart along the chain


def test_min_self_distance():
    """The smallest distance between beads |i - j| >= 2 apart, over rows (exact)."""
    b = np.array([[[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [1.0, 4.0]]])
    assert min_self_distance(b) == pytest.approx(math.hypot(1.0, 4.0))  # (0, 3)
    assert min_self_distance(b[0], gap=3) == pytest.approx(math.hypot(1.0, 4.0))
    assert min_self_distance(b[0, :2]) == math.inf


def test_setting_on_by_default_off_by_name_and_hidden_at_default():
    """fiber.self_exclusion is on by default for the bead-spring models, off when set
    false, meaningless (gap 0) for the rigid model; the dump (and so run ids, manifests)
    leaves it out at its default and writes it when false."""
    kw = dict(mu=0.34, u_center=600.0, x_stop=1e3, y_lo=0.0, y_hi=1e3, random=False)
    for integrator in ("bdf2", "ros2", "ros34pw2"):
        st = FiberSettings(model="bead-spring", integrator=integrator)
        p = make_params(st, **kw)
        assert p.excl_gap == GAP
        assert p.excl_eq == 2 * A and p.excl_cut == pytest.approx(CHI * 2 * A, rel=1e-15)
        assert p.excl_fref == pytest.approx(6 * math.pi * 0.34 * A * 600.0, rel=1e-15)
        off = st.model_copy(update={"self_exclusion": False})
        assert make_params(off, **kw).excl_gap == 0
    assert make_params(FiberSettings(), **kw).excl_gap == 0
    on = FiberSettings(model="bead-spring", integrator="ros2")
    assert "self_exclusion" not in on.model_dump()
    assert "self_exclusion" not in fiber_result_settings(on)
    off = FiberSettings(model="bead-spring", integrator="ros2", self_exclusion=False)
    assert off.model_dump()["self_exclusion"] is False
    assert FiberSettings.model_validate(off.model_dump()) == off
    assert FiberSettings.model_validate(on.model_dump()) == on
