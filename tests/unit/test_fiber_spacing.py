"""The bead spacing of a bead-spring chain
(fibersweep/fiber/models/spacing.py, ``fiber.bead_spacing``).

The setting's plumbing (hidden at its default, refused where it has no meaning),
the chain it builds, and the per-bead scalings that give the chain one continuum
limit: elastic energy, pillar contact and self-exclusion per unit length.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.errors import InputError
from fibersweep.fiber.contact.pillar import ROUGH, SMOOTH, PillarArrays, pillar_forces, rough_beads
from fibersweep.fiber.hydro.rpy import fiber_offsets
from fibersweep.fiber.kernel.bundles import make_params
from fibersweep.fiber.models.elastic import elastic_energy
from fibersweep.fiber.models.exclusion import GAP, exclusion_forces
from fibersweep.fiber.models.spacing import (
    bead_force_scale,
    exclusion_force_scale,
    exclusion_gap,
    n_beads,
    offsets,
    spacing_um,
)
from fibersweep.sweep.ids import fiber_result_settings

A = 2.0  # bead radius [µm]
KW = dict(mu=0.34, u_center=600.0, x_stop=1e3, y_lo=0.0, y_hi=1e3, random=False)


def test_default_spacing_is_the_touching_chain():
    """At ``bead_spacing`` 1 the chain is the source's exactly: round(L/2a) beads (the
    same rounding at exact halves), centres 2a apart, every scale factor 1.0, pair gap 2."""
    for L in np.arange(4.0, 200.0, 1.0):
        assert n_beads(L, A) == max(1, round(L / (2 * A)))
        assert n_beads(L, A, 1.0) == n_beads(L, A)
    for n in (2, 5, 22):
        assert np.array_equal(offsets(n, A), fiber_offsets(n, A))
    assert spacing_um(A) == 2 * A
    assert bead_force_scale(1.0) == 1.0 and exclusion_force_scale(1.0) == 1.0
    assert exclusion_gap(1.0) == GAP == 2


@pytest.mark.parametrize("frac", [0.5, 0.25, 1.0 / 3.0, 0.8])
def test_finer_chain_spans_the_length(frac):
    """n = round((L − 2a)/b) + 1 beads b = frac·2a apart: the bead surfaces span L to
    within half a spacing; the pair gap is ceil(4a/b) (4a: the arc below which two beads
    of one fiber never repel)."""
    b = frac * 2 * A
    for L in np.arange(8.0, 160.0, 1.7):
        n = n_beads(L, A, frac)
        assert abs((n - 1) * b + 2 * A - L) <= 0.5 * b + 1e-9
        s = offsets(n, A, frac)
        assert np.allclose(np.diff(s), b) and abs(s.mean()) < 1e-12
    g = exclusion_gap(frac)
    assert g * b >= 4 * A - 1e-9 and (g - 1) * b < 4 * A
    assert {0.5: 4, 0.25: 8, 1.0 / 3.0: 6, 0.8: 3}[frac] == g


def test_params_of_a_finer_chain():
    """The kernel scalars: at the default, those of the touching chain bit for bit (half
    spacing = a, gap 2, pair force scale F_ref); at b = a: b/2 = a/2, gap 4, F_ref/4."""
    st = FiberSettings(model="bead-spring", integrator="ros2")
    p = make_params(st, **KW)
    f_ref = 6 * math.pi * 0.34 * A * 600.0
    assert p.half_b == A and p.excl_gap == 2
    assert p.excl_fref == pytest.approx(f_ref, rel=1e-15)
    p2 = make_params(st.model_copy(update={"bead_spacing": 0.5}), **KW)
    assert p2.half_b == 0.5 * A and p2.excl_gap == 4
    assert p2.excl_fref == pytest.approx(0.25 * f_ref, rel=1e-15)
    assert p2.excl_cut == p.excl_cut and p2.excl_eq == p.excl_eq  # the surfaces' geometry
    assert p2.a == p.a and p2.stretch == p.stretch and p2.bend == p.bend


def test_setting_hidden_at_default_and_refused_where_meaningless():
    """``fiber.bead_spacing`` leaves the dump (so run ids and manifests) at 1, also when
    given explicitly; it is written when set; the rigid model and the effects refuse it."""
    on = FiberSettings(model="bead-spring", integrator="ros2")
    same = FiberSettings(model="bead-spring", integrator="ros2", bead_spacing=1.0)
    assert "bead_spacing" not in on.model_dump()
    assert on.model_dump() == same.model_dump()
    assert fiber_result_settings(on) == fiber_result_settings(same)
    fine = FiberSettings(model="bead-spring", integrator="ros2", bead_spacing=0.5)
    assert fine.model_dump()["bead_spacing"] == 0.5
    assert FiberSettings.model_validate(fine.model_dump()) == fine
    assert fiber_result_settings(fine) != fiber_result_settings(on)
    with pytest.raises(ValueError, match="bead_spacing"):
        FiberSettings(bead_spacing=0.5)  # rigid
    with pytest.raises(ValueError, match="friction"):
        FiberSettings(model="bead-spring", bead_spacing=0.5, effects={"friction": 0.2})
    for bad in (0.0, -0.5, 1.5):
        with pytest.raises(ValueError, match="bead_spacing"):
            FiberSettings(model="bead-spring", bead_spacing=bad)


def test_config_names_the_field():
    """A config that sets a finer spacing on the rigid model is refused naming the field."""
    from fibersweep.config import parse_config

    with pytest.raises((InputError, ValueError), match="bead_spacing"):
        parse_config({"fiber": {"bead_spacing": 0.5}})
    cfg = parse_config({"fiber": {"model": "bead-spring", "bead_spacing": 0.5}})
    assert cfg.fiber.bead_spacing == 0.5


def _arc(radius, length, frac):
    """Beads b apart on an arc of ``radius`` [µm] whose centreline spans ``length``."""
    b = frac * 2 * A
    n = int(round(length / b)) + 1
    phi = np.arange(n) * b / radius
    return radius * np.sin(phi), radius * (1 - np.cos(phi)), n, b


@pytest.mark.parametrize("frac", [1.0, 0.5, 0.25])
def test_elastic_energy_is_the_continuum_one(frac):
    """With the springs' length scale b/2, a uniformly bent chain stores B/2R² per unit
    length at its n − 2 joints, (n − 2) b B/2R², to O((b/R)²/12); a uniformly stretched one
    (S/2)ε² per unit length exactly: the same S and B at every spacing."""
    E = 1e5
    S = E * math.pi * A**2
    B = E * math.pi * A**4 / 4
    R = 20.0
    x, y, n, b = _arc(R, 60.0, frac)
    h = elastic_energy(x, y, 0.5 * b, S, B)
    cont = (n - 2) * b * B / (2 * R**2)
    assert h == pytest.approx(cont, rel=(b / R) ** 2 / 12 + 1e-3)
    eps = 1e-3
    xs = np.arange(n) * b * (1 + eps)
    hs = elastic_energy(xs, np.zeros(n), 0.5 * b, S, B)
    assert hs == pytest.approx(0.5 * S * eps**2 * (n - 1) * b, rel=1e-9)


def _wall(kind, f_ref):
    """A 400 µm wide pillar whose top side lies on y = 0 (rough: beads 1.2 µm apart)."""
    verts = np.array([[-200.0, -300.0], [200.0, -300.0], [200.0, 0.0], [-200.0, 0.0]])
    if kind == ROUGH:
        beads = rough_beads(verts, 0.6)
        r_eq = A + 0.6
        return PillarArrays(ROUGH, verts, beads[:, 0].copy(), beads[:, 1].copy(),
                            np.zeros((0, 3, 2)), 1.1 * r_eq, r_eq, f_ref)  # fmt: skip
    from fibersweep.fiber.contact.bezier import smooth_curves

    return PillarArrays(SMOOTH, verts, np.zeros(0), np.zeros(0), smooth_curves(verts, 2.0),
                        1.1 * A, A, f_ref)  # fmt: skip


@pytest.mark.parametrize("kind", [ROUGH, SMOOTH])
def test_contact_force_per_unit_length_does_not_depend_on_spacing(kind):
    """A straight chain held parallel to a pillar side, inside the contact layer: with the
    per-bead scale b/2a the force per unit length is that of the touching chain, exactly
    for the smooth pillar, to 1 % for the rough one (its 1.2 µm corrugation is sampled
    at other phases by other spacings). Averaged over the chain's offset along the side."""
    f_ref = 7690.0
    per_length = {}
    for frac in (1.0, 0.5, 0.25):
        b = frac * 2 * A
        pil = _wall(kind, f_ref * bead_force_scale(frac))
        n = int(round(100.0 / b))
        d = (A + 0.6 if kind == ROUGH else A) * 1.05
        tot = []
        for shift in np.linspace(0.0, 1.2, 7, endpoint=False):
            x = np.arange(n) * b - 50.0 + shift
            y = np.full(n, d)
            out = [np.zeros(n) for _ in range(4)]
            pillar_forces(pil, x, y, *out)
            tot.append(out[1].sum() / (n * b))
        per_length[frac] = float(np.mean(tot))
    assert per_length[1.0] > 0
    tol = 1e-12 if kind == SMOOTH else 0.01
    for frac in (0.5, 0.25):
        assert per_length[frac] == pytest.approx(per_length[1.0], rel=tol)


def _arms(frac, d, shift, length=60.0):
    """Two straight parallel arms ``d`` apart as one chain folded at its end (indices run
    out along y = 0 and back along y = d, that arm moved by ``shift`` along x); returns
    x, y, n_arm, b."""
    b = frac * 2 * A
    m = int(round(length / b)) + 1
    xa = np.arange(m) * b
    x = np.concatenate([xa, xa[::-1] + shift])
    return x, np.concatenate([np.zeros(m), np.full(m, d)]), m, b


def _arm_force(frac, d, shift):
    """Force per unit length [pN/µm] pushing arm 1 away from arm 2, middle third of arm 1."""
    x, y, m, b = _arms(frac, d, shift)
    fx, fy = np.zeros_like(x), np.zeros_like(y)
    exclusion_forces(x, y, exclusion_gap(frac), 1.1 * 2 * A, 2 * A,
                     7690.0 * exclusion_force_scale(frac), fx, fy)  # fmt: skip
    mid = slice(m // 3, 2 * m // 3)
    return float(-fy[mid].mean() / b)


def test_self_exclusion_per_unit_length_does_not_depend_on_spacing():
    """Two arms of a folded chain lying side by side 0.98 · 2a apart repel, per unit
    length of arm, with the same force at every spacing once averaged over how the two
    arms' beads stand against each other (pair force scaled by (b/2a)², pairs ∝ 1/b²;
    the average of a lattice sum over its offset is the integral, so equal to 1e-9).
    At one offset the coarse chains sample the 2 µm wide pair law crudely: b = a is
    23 % above b = a/4 with the beads face to face, b = a/2 within 0.5 %."""
    d = 0.98 * 2 * A
    avg = {}
    for frac in (1.0, 0.5, 0.25, 0.125):
        b = frac * 2 * A
        avg[frac] = float(np.mean([_arm_force(frac, d, s)
                                   for s in np.linspace(0.0, b, 64, endpoint=False)]))  # fmt: skip
    assert avg[1.0] > 0
    for frac in (0.5, 0.25, 0.125):
        assert avg[frac] == pytest.approx(avg[1.0], rel=1e-9)
    face = {frac: _arm_force(frac, d, 0.0) for frac in (0.5, 0.25, 0.125)}
    assert face[0.25] == pytest.approx(face[0.125], rel=0.005)
    assert face[0.125] == pytest.approx(avg[1.0], rel=0.005)


@pytest.mark.parametrize("frac", [0.5, 0.25, 0.125])
def test_self_exclusion_leaves_a_physically_bent_chain_alone(frac):
    """A chain bent into a half circle of centreline radius 1.2a (arc 3.8a < 4a) has no
    pair inside the cutoff: the gap skips every pair a solid fiber of radius a can bring
    together by bending; the same chain straight has none either."""
    x, y, n, b = _arc(1.2 * A, math.pi * 1.2 * A, frac)
    fx, fy = np.zeros(n), np.zeros(n)
    assert exclusion_forces(x, y, exclusion_gap(frac), 2.2 * A, 2 * A, 1.0, fx, fy) == 0
    xs = np.arange(n) * b
    assert exclusion_forces(xs, 0 * xs, exclusion_gap(frac), 2.2 * A, 2 * A, 1.0, fx, fy) == 0
