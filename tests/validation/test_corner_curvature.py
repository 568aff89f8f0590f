"""Validation of the near-wall resistance beside a curved surface (``fiber.contact.curvature``).

A bead near a pillar whose surface is curved in the plane of motion (a circle's
radius, a polygon's rounded corner r_c) and straight along the pillar's axis sees
the gap h + x²/(2R₁) + z²/(2R₂), R₁ = aR/(a + R), R₂ = a. The leading squeeze-film
force (Reynolds equation, exact solution p ∝ 1/h²) is the plane's times
2 q^{3/2}/(1 + q), q = R/(a + R); the model scales the plane's λ⊥ − 1 by it. Checked:
the plane as R → ∞; a sphere beside a sphere (R₂ = R₁ too) gives q², the leading term
of Jeffrey & Onishi's (1984) X₁₁ᴬ (Cooley & O'Neill's 1969 near-contact force of a
sphere approaching a fixed sphere); near contact the whole normal resistance then
agrees with Jeffrey & Onishi's singular terms to the difference of the logarithmic
terms; the squeeze-film formula against a numerical solution of the Reynolds equation;
the corner regions; the assembled terms.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.linalg import spsolve

from fibersweep.fiber.contact.bezier import smooth_curves
from fibersweep.fiber.contact.pillar import ROUGH, SMOOTH, Pillar
from fibersweep.fiber.hydro import wall_mobility as wm
from fibersweep.fiber.hydro.nearwall import (
    corner_radius_at,
    curvature_factor,
    squeeze_factor,
    wall_terms_at,
)

A = 2.0


def _jeffrey_onishi_x11a_singular(beta: float, xi: float) -> float:
    """Jeffrey & Onishi (1984) eq. (3.17): X₁₁ᴬ ≈ g₁/ξ + g₂ ln(1/ξ) (+ O(1)), units 6πμa₁,
    g₁ = 2β²/(1+β)³, g₂ = β(1 + 7β + β²)/(5(1+β)³), ξ = 2h/(a₁ + a₂), β = a₂/a₁."""
    g1 = 2.0 * beta**2 / (1.0 + beta) ** 3
    g2 = beta * (1.0 + 7.0 * beta + beta**2) / (5.0 * (1.0 + beta) ** 3)
    return g1 / xi + g2 * math.log(1.0 / xi)


def test_the_plane_is_the_limit_of_a_large_radius():
    """R → ∞: the factor tends to 1 as 1 − (3/2 − 1/2) a/R (to 2 (a/R)² ), and is 1 for inf."""
    assert curvature_factor(A, math.inf) == 1.0
    for r in (1e3, 1e4, 1e6):
        assert curvature_factor(A, r) == pytest.approx(1.0 - A / r, abs=2.0 * (A / r) ** 2)
    # monotone in R, in (0, 1]
    rs = np.logspace(-3, 6, 200)
    f = np.array([curvature_factor(A, r) for r in rs])
    assert np.all(np.diff(f) > 0) and f[0] > 0 and f[-1] <= 1.0


@pytest.mark.parametrize("beta", [0.3, 1.0, 2.0, 10.0])
def test_sphere_sphere_gives_jeffrey_onishi_leading_term(beta):
    """Two principal radii aR/(a+R) (a sphere of radius R = βa): the squeeze factor is q²,
    and q²/ε equals Jeffrey & Onishi's g₁/ξ (1e-12 relative)."""
    r = beta * A
    r1 = A * r / (A + r)
    q = r / (A + r)
    assert squeeze_factor(A, r1, r1) == pytest.approx(q * q, rel=1e-12)
    eps = 1e-4
    xi = 2.0 * eps * A / (A + r)
    g1 = 2.0 * beta**2 / (1.0 + beta) ** 3
    assert squeeze_factor(A, r1, r1) / eps == pytest.approx(g1 / xi, rel=1e-12)


@pytest.mark.parametrize("beta", [1.0, 2.0, 5.0])
def test_near_contact_resistance_against_jeffrey_onishi(beta):
    """The model's normal resistance beside a sphere of radius βa, 1 + q²(λ⊥ − 1) with the
    plane's exact λ⊥, against Jeffrey & Onishi's X₁₁ᴬ singular terms at ε = h/a = 1e-4 and
    1e-3: within |g₂ ln(1/ξ) − q²/5 ln(1/ε)| + 1.5 (the unmatched logarithm and a bound on
    the O(1) terms), which is under 1.2 % of X₁₁ᴬ at ε = 1e-3 and 0.15 % at 1e-4."""
    r = beta * A
    q = r / (A + r)
    for eps, rel in ((1e-4, 1.5e-3), (1e-3, 1.2e-2)):
        xi = 2.0 * eps * A / (A + r)
        jo = _jeffrey_onishi_x11a_singular(beta, xi)
        lam = float(wm.sphere_wall(eps).normal)
        model = 1.0 + squeeze_factor(A, A * q, A * q) * (lam - 1.0)
        g2 = beta * (1.0 + 7.0 * beta + beta**2) / (5.0 * (1.0 + beta) ** 3)
        bound = abs(g2 * math.log(1.0 / xi) - q * q / 5.0 * math.log(1.0 / eps)) + 1.5
        assert abs(model - jo) <= bound
        assert abs(model - jo) <= rel * jo


def test_squeeze_formula_against_a_numerical_reynolds_solution():
    """The squeeze-film force of the elliptic gap h₀(1 + X²/(2r₁) + Z²/(2r₂)) (lengths in
    units of √h₀-scaled coordinates) from a finite-difference solution of
    ∇·(h³∇p) = −12μU on a large square with p = 0 at its edge, against
    12πμU (R₁R₂)^{3/2}/((R₁+R₂) h₀): within 3 % (grid and domain truncation) for R₁/R₂ = 1,
    0.3, 0.1."""
    h0, mu, u = 1.0, 1.0, 1.0
    for r1, r2 in ((1.0, 1.0), (0.3, 1.0), (0.1, 1.0)):
        # domain: a few contact radii sqrt(2 R h0) along each axis
        lx, lz = 12.0 * math.sqrt(2 * r1 * h0), 12.0 * math.sqrt(2 * r2 * h0)
        n = 241
        xs = np.linspace(-lx, lx, n)
        zs = np.linspace(-lz, lz, n)
        dxg, dzg = xs[1] - xs[0], zs[1] - zs[0]
        gx, gz = np.meshgrid(xs, zs, indexing="ij")
        h = h0 + gx**2 / (2 * r1) + gz**2 / (2 * r2)
        h3 = h**3
        m = n - 2
        # conservative 5-point operator with face-averaged h³ (Dirichlet p = 0 outside)
        hx_p = 0.5 * (h3[1:-1, 1:-1] + h3[2:, 1:-1]).ravel()
        hx_m = 0.5 * (h3[1:-1, 1:-1] + h3[:-2, 1:-1]).ravel()
        hz_p = 0.5 * (h3[1:-1, 1:-1] + h3[1:-1, 2:]).ravel()
        hz_m = 0.5 * (h3[1:-1, 1:-1] + h3[1:-1, :-2]).ravel()
        main = -(hx_p + hx_m) / dxg**2 - (hz_p + hz_m) / dzg**2
        idx = np.arange(m * m)
        i_idx, j_idx = idx // m, idx % m
        rows, cols, vals = [idx], [idx], [main]
        for di, dj, coef in ((1, 0, hx_p / dxg**2), (-1, 0, hx_m / dxg**2),
                             (0, 1, hz_p / dzg**2), (0, -1, hz_m / dzg**2)):  # fmt: skip
            ii, jj = i_idx + di, j_idx + dj
            ok = (ii >= 0) & (ii < m) & (jj >= 0) & (jj < m)
            rows.append(idx[ok])
            cols.append((ii * m + jj)[ok])
            vals.append(coef[ok])
        mat = coo_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(m * m, m * m),
        ).tocsr()
        p = spsolve(mat, np.full(m * m, -12.0 * mu * u))
        force = p.sum() * dxg * dzg
        exact = 12.0 * math.pi * mu * u * (r1 * r2) ** 1.5 / ((r1 + r2) * h0)
        assert force == pytest.approx(exact, rel=0.03)


TRI = np.array([[0.0, 0.0], [86.6, 0.0], [43.3, 75.0]])


def test_the_corner_regions_of_rough_and_smooth_pillars():
    """Beyond a vertex (between its sides' normals) the radius is r_c, on a face inf; the
    smooth pillar's corner region is between the normals at its curve's ends."""
    rc = 1.0
    curves = smooth_curves(TRI, rc)
    below_left = (-1.0, -1.0)  # beyond vertex 0 of both sides
    on_base = (40.0, -3.0)  # below the base
    for kind, cv in ((ROUGH, np.zeros((0, 3, 2))), (SMOOTH, curves)):
        assert corner_radius_at(kind, TRI, cv, *below_left, rc) == rc
        assert corner_radius_at(kind, TRI, cv, *on_base, rc) == math.inf
        assert corner_radius_at(kind, TRI, cv, 43.3, 78.0, rc) == rc  # above the apex
    # just beside the base next to vertex 0: the rough pillar's face, the smooth pillar's
    # rounded corner (its tangent point lies r_c·√3 from the vertex along the base)
    assert corner_radius_at(ROUGH, TRI, np.zeros((0, 3, 2)), 0.5, -2.0, rc) == math.inf
    assert corner_radius_at(SMOOTH, TRI, curves, 0.5, -2.0, rc) == rc


def test_assembled_terms_scale_the_normal_resistance_only():
    """Beside a circle of radius 20 µm at ε = 0.1: with curvature the normal ΔR is the plane's
    times curvature_factor(a, 20) and the tangential ΔR and push are unchanged (1e-12); at a
    rough triangle's vertex the normal ΔR is scaled by curvature_factor(a, r_c); without it
    every term is bit for bit the plane's."""
    circ = Pillar(ROUGH, np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 3, 2)), 2.2, 2.0,
                  1.0, np.array([0.0, 0.0, 20.0]))  # fmt: skip
    pos = np.array([[20.0 + A * 1.1, 0.0]])  # on the +x axis: normal = x
    vel = np.array([[0.3, 1.0]])
    kw = dict(bead_radius=A, viscosity=1.0, depth=math.inf)
    r0, e0 = wall_terms_at(circ, pos, vel, **kw)
    r1, e1 = wall_terms_at(circ, pos, vel, curved=True, **kw)
    r2, e2 = wall_terms_at(circ, pos, vel, curved=False, corner_radius=5.0, **kw)
    assert r0.tobytes() == r2.tobytes() and e0.tobytes() == e2.tobytes()
    f = curvature_factor(A, 20.0)
    assert r1[0, 0, 0] == pytest.approx(f * r0[0, 0, 0], rel=1e-12)
    assert r1[0, 1, 1] == pytest.approx(r0[0, 1, 1], rel=1e-12)
    assert np.allclose(e1, e0, rtol=1e-12, atol=0.0)
    tri = Pillar(ROUGH, TRI, np.zeros((0, 2)), np.zeros((0, 3, 2)), 2.2, 2.0, 1.0, np.zeros(3))
    d = A * 1.1 / math.sqrt(2.0)
    pos = np.array([[-d, -d]])  # beyond vertex 0, on its bisector-ish diagonal
    r0, _ = wall_terms_at(tri, pos, vel, **kw)
    r1, _ = wall_terms_at(tri, pos, vel, curved=True, corner_radius=1.0, **kw)
    n = np.array([-1.0, -1.0]) / math.sqrt(2.0)
    t = np.array([1.0, -1.0]) / math.sqrt(2.0)
    fr = curvature_factor(A, 1.0)
    assert n @ r1[0] @ n == pytest.approx(fr * (n @ r0[0] @ n), rel=1e-12)
    assert t @ r1[0] @ t == pytest.approx(t @ r0[0] @ t, rel=1e-12)
    # the two worked numbers of the issue: fiber bead at a 0.6 µm corner, a DLD sphere
    assert curvature_factor(2.0, 0.6) == pytest.approx(0.180, abs=5e-4)
    assert curvature_factor(7.5, 20.0) == pytest.approx(0.718, abs=5e-4)
