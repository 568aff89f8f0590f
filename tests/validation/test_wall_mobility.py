"""Sphere near a plane wall: exact series, fitted kernels, and the published results.

Sources of the reference numbers (each test says which it uses):

* Brenner (1961), Chem. Eng. Sci. 16, 242, Table 1: λ⊥ for a rigid plane at
  α = 0.5 … 3.0 (h/a = cosh α), five significant digits. The values are those
  quoted from that table in the literature; they were not re-read from the
  paper for this test. The series reproduces each to half a unit of its last
  digit, which a misquoted value would not.
* Cox & Brenner (1967), Chem. Eng. Sci. 22, 1753: λ⊥ = 1/ε + (1/5) ln(1/ε) +
  0.971 near contact.
* Goldman, Cox & Brenner (1967a), Chem. Eng. Sci. 22, 637: near-contact forms
  of the parallel resistances, f_tt = −(8/15) ln ε + 0.9588, (3/4) f_tr =
  −(1/10) ln ε − 0.1895, (3/4) f_rr = −(2/5) ln ε + 0.3817; and the
  method-of-reflections (Faxén) far field of f_tt.
* Chaoui & Feuillebois (2003), Q. J. Mech. Appl. Math. 56, 381, Tables 11 and
  13: the same three resistances as Σ_k (φ_k ln ε + f_k) ε^k, k ≤ 5, fitted
  by the authors to their exact solution for ε ≤ 1 (16-digit coefficients, as
  transcribed in the optical tweezers toolbox's ``ChaouiSphere``); their
  constants refine Goldman, Cox & Brenner's.
* Goren & O'Neill (1971), Chem. Eng. Sci. 26, 325: the force on a sphere held
  at rest in the flow towards a wall u_z = −α z², 6πμa u_z(h) c_n, with
  c_n → 3.23 as the sphere touches the wall (the contact value as quoted in the
  deposition literature from their table; not re-read from the paper). Our
  solution is checked by what does not depend on a transcription: the same
  solver with Brenner's boundary data gives Brenner's λ⊥, its far field is
  the reflection result, and its double-precision sum agrees with a
  40-digit evaluation.
* Goldman, Cox & Brenner (1967b), Chem. Eng. Sci. 22, 653, the table of the
  force F^s and torque T^s on a fixed sphere in the shear γ̇z (at α = 3, 2,
  1.5, 1, 0.5, 0.3, 0.1, 0.08 and contact), as transcribed in a public script
  that interpolates it; their lubrication and reflection forms of the
  velocity of a free sphere.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.fiber.hydro import wall_mobility as wm
from fibersweep.fiber.hydro.first_reflection import wall_drag
from fibersweep.fiber.hydro.wall_exact import (
    brenner_normal,
    normal_push,
    parallel_resistances,
    terms_needed,
    translation_force,
)

# Brenner (1961) Table 1, rigid plane: (α, λ⊥)
BRENNER_1961 = (
    (0.5, 9.2518),
    (1.0, 3.0361),
    (1.5, 1.8375),
    (2.0, 1.4129),
    (2.5, 1.2220),
    (3.0, 1.1252),
)

# Chaoui & Feuillebois (2003): f_xx^t (Table 11), c_yx^t (Table 11), c_yy^r (Table 13);
# each (φ_0..φ_5, f_0..f_5) of Σ (φ_k ln ε + f_k) ε^k. In our conventions
# f_xx^t = f_tt, c_yx^t = (3/4) f_tr, c_yy^r = (3/4) f_rr.
CF_TT = (
    (
        -8 / 15,
        -64 / 375,
        0.011595712294862,
        -0.002559314461340,
        0.002165777707452,
        0.000351260314552,
    ),
    (
        0.954293724783876,
        0.429450132564500,
        -0.001897844702304,
        0.002058408405495,
        0.000096108639584,
        -0.001248147281379,
    ),
)
CF_TR = (
    (
        -1 / 10,
        -43 / 250,
        -0.036913066460225,
        0.001486892317125,
        0.000012689734456,
        0.000103798994187,
    ),
    (
        -0.192952745666190,
        0.100579155700110,
        0.094493729126963,
        0.003821112414990,
        -0.000819028830091,
        -0.000097511506358,
    ),
)
CF_RR = (
    (
        -2 / 5,
        -0.528001276176667,
        -0.212879560114862,
        -0.035965644690736,
        -0.006385459746252,
        0.000167620439255,
    ),
    (
        0.370892565890165,
        0.340079923061464,
        0.225531274283815,
        0.097897336215370,
        0.005878696055717,
        0.001503759398496,
    ),
)

# Goldman, Cox & Brenner (1967b): (α, F^s, T^s); h/a = cosh α, α = 0 is contact
GCB_1967B_SHEAR = (
    (3.0, 1.0587, 0.99981),
    (2.0, 1.1671, 0.99711),
    (1.5, 1.278, 0.99010),
    (1.0, 1.4391, 0.97419),
    (0.5, 1.616, 0.95374),
    (0.3, 1.6682, 0.94769),
    (0.1, 1.6969, 0.94442),
    (0.08, 1.6982, 0.94427),
    (0.0, 1.7005, 0.94399),
)


def _cf(coef, eps):
    phi, f = coef
    return sum((phi[k] * math.log(eps) + f[k]) * eps**k for k in range(6))


def _brenner_direct(alpha: float, n_terms: int) -> float:
    """Brenner's series exactly as printed (plain sinh: (2n + 1)α must stay below ~700)."""
    s = 0.0
    sa = math.sinh(alpha)
    for n in range(n_terms, 0, -1):
        num = 2.0 * math.sinh((2 * n + 1) * alpha) + (2 * n + 1) * math.sinh(2 * alpha)
        den = 4.0 * math.sinh((n + 0.5) * alpha) ** 2 - (2 * n + 1) ** 2 * sa**2
        s += n * (n + 1) / ((2 * n - 1) * (2 * n + 3)) * (num / den - 1.0)
    return 4.0 / 3.0 * sa * s


# ---------------------------------------------------------------- exact series


@pytest.mark.parametrize(("alpha", "table"), BRENNER_1961)
def test_brenner_series_matches_brenner_1961_table(alpha, table):
    """λ⊥ from the series against Brenner's Table 1: within the table's rounding (5e-5)."""
    assert abs(brenner_normal(math.cosh(alpha)) - table) <= 5e-5


@pytest.mark.parametrize("alpha", [0.3, 0.5, 1.0, 2.0, 3.0])
def test_brenner_series_converged_and_equal_to_printed_form(alpha):
    """The overflow-safe series equals the printed one summed far past convergence (up to
    300 terms, e^(−(2n+1)α) < 1e-70; 1e-12), and doubling its own length changes nothing
    (1e-14)."""
    h = math.cosh(alpha)
    lam = brenner_normal(h)
    assert lam == pytest.approx(_brenner_direct(alpha, min(300, int(340 / alpha))), rel=1e-12)
    assert lam == pytest.approx(brenner_normal(h, 2 * terms_needed(h)), rel=1e-14)


def test_brenner_series_limits():
    """Near contact Cox & Brenner's 1/ε + (1/5) ln(1/ε) + 0.971 (to 1e-3 at ε ≤ 1e-5, where
    the next term, O(ε ln ε), is below 1e-4); far away the reflection series of the
    mobility, 1 − (9/8) x + (1/2) x³, whose next term is O(x⁴) (|remainder| ≤ x⁴)."""
    for eps in (1e-6, 1e-5):
        assert brenner_normal(1 + eps) - 1 / eps - 0.2 * math.log(1 / eps) == pytest.approx(
            0.971, abs=1e-3
        )
    for h in (5.0, 10.0, 20.0, 50.0):
        x = 1 / h
        assert abs(1 / brenner_normal(h) - (1 - 9 / 8 * x + x**3 / 2)) <= x**4


@pytest.mark.parametrize("eps", [1e-6, 1e-4, 1e-2, 0.1, 0.5, 1.0, 3.0, 30.0])
def test_parallel_solution_is_reciprocal(eps):
    """The torque on the translating sphere and the force on the rotating one come from
    two different systems; reciprocity makes them equal (1e-10 of f_tt)."""
    f_tt, f_tr_t, f_tr_r, _ = parallel_resistances(1 + eps)
    assert abs(f_tr_t - f_tr_r) <= 1e-10 * f_tt


def test_parallel_solution_matches_chaoui_feuillebois_near_contact():
    """f_tt, f_tr, f_rr against Chaoui & Feuillebois's near-contact series, ε from 1e-6 to 1:
    agreement within 1e-8 of f_tt (their series are fits good to about that)."""
    for eps in np.logspace(-6, 0, 25):
        f_tt, _, f_tr, f_rr = parallel_resistances(1 + eps)
        assert abs(f_tt - _cf(CF_TT, eps)) <= 1e-8 * f_tt
        assert abs(0.75 * f_tr - _cf(CF_TR, eps)) <= 1e-8 * f_tt
        assert abs(0.75 * f_rr - _cf(CF_RR, eps)) <= 1e-8 * f_rr


def test_parallel_solution_lubrication_and_far_field():
    """Near contact (ε = 1e-6, where O(ε ln ε) < 2e-5): the constants of the logarithmic
    forms are Chaoui & Feuillebois's to 1e-4, and Goldman, Cox & Brenner's to 0.012 (their
    four-digit constants, 0.9588, 0.1895, 0.3817, are off by 0.0045, 0.0035 and 0.011).
    Far away: Faxén's 1 − (9/16) x + x³/8 − (45/256) x⁴ − x⁵/16 for 1/f_tt, 1 − (5/16) x³
    for (4/3)/f_rr (remainders O(x⁶): ≤ x⁶), and f_tr = x⁴/8 (1 + O(x): within x)."""
    eps = 1e-6
    lg = math.log(eps)
    f_tt, _, f_tr, f_rr = parallel_resistances(1 + eps)
    consts = (f_tt + 8 / 15 * lg, 0.75 * f_tr + lg / 10, 0.75 * f_rr + 0.4 * lg)
    for got, cf, gcb in zip(
        consts, (0.9543, -0.1930, 0.3709), (0.9588, -0.1895, 0.3817), strict=True
    ):
        assert got == pytest.approx(cf, abs=1e-4)
        assert got == pytest.approx(gcb, abs=0.012)
    for h in (5.0, 10.0, 20.0, 50.0):
        x = 1 / h
        f_tt, _, f_tr, f_rr = parallel_resistances(h)
        faxen = 1 - 9 / 16 * x + x**3 / 8 - 45 / 256 * x**4 - x**5 / 16
        assert abs(1 / f_tt - faxen) <= x**6
        assert abs(4 / 3 / f_rr - (1 - 5 / 16 * x**3)) <= x**6
        assert abs(f_tr / (x**4 / 8) - 1) <= x


# ---------------------------------------------------------------- fitted kernels


def _check_gaps() -> np.ndarray:
    """Gaps between the fit's nodes (scripts/tools/fit_wall_mobility.py), 1e-6 to 1e3."""
    return np.concatenate([np.logspace(-6, 0, 49)[1::2], np.logspace(0, 3, 17)[1::2]])


def test_kernels_against_exact_solutions():
    """λ⊥, f_tt, f_tr, f_rr of the kernels against the exact series, ε from 1e-6 to 1e3:
    relative error ≤ 1e-6 (f_tr relative to f_tt; the fit's own largest errors are 5e-8,
    9e-8, 1.7e-7 and 6e-7)."""
    gaps = _check_gaps()
    sw = wm.sphere_wall(gaps)
    for i, eps in enumerate(gaps):
        f_tt, _, f_tr, f_rr = parallel_resistances(1 + eps)
        lam = brenner_normal(1 + eps)
        assert sw.normal[i] == pytest.approx(lam, rel=1e-6)
        assert sw.translation[i] == pytest.approx(f_tt, rel=1e-6)
        assert abs(sw.coupling[i] - f_tr) <= 1e-6 * f_tt
        assert sw.rotation[i] == pytest.approx(f_rr, rel=1e-6)
        assert sw.torque_free[i] == pytest.approx(f_tt - f_tr**2 / f_rr, rel=1e-6)


def test_kernels_far_field_limits():
    """Lorentz and Faxén: the mobilities 1/λ⊥ = 1 − (9/8) x and 1/λ∥ = 1 − (9/16) x to
    first order in x = a/h (the remainders are O(x³) for both: ≤ x³ at x ≤ 0.01)."""
    for h in (100.0, 1000.0):
        x = 1 / h
        sw = wm.sphere_wall(h - 1)
        assert abs(1 / sw.normal - (1 - 9 / 8 * x)) <= x**2 * 2
        assert abs(1 / sw.torque_free - (1 - 9 / 16 * x)) <= x**3


def test_kernels_lubrication_limits():
    """At ε = 1e-6 and 1e-5: λ⊥ − 1/ε − (1/5) ln(1/ε) → 0.9713 (Cox & Brenner; 1e-3) and
    f_tt − (8/15) ln(1/ε) → 0.9543 (Chaoui & Feuillebois; 1e-3, the O(ε ln ε) terms being
    below 2e-4)."""
    for eps in (1e-6, 1e-5):
        sw = wm.sphere_wall(eps)
        assert sw.normal - 1 / eps - 0.2 * math.log(1 / eps) == pytest.approx(0.9713, abs=1e-3)
        assert sw.translation - 8 / 15 * math.log(1 / eps) == pytest.approx(0.9543, abs=1e-3)


def test_kernels_monotone_in_the_gap():
    """Every coefficient is strictly monotone over ε from 1e-7 to 1e4 (20001 points)."""
    sw = wm.sphere_wall(np.logspace(-7, 4, 20001))
    for name in ("normal", "translation", "coupling", "rotation", "torque_free", "shear_force"):
        assert np.all(np.diff(getattr(sw, name)) < 0), name
    for name in ("shear_torque", "shear_velocity"):
        assert np.all(np.diff(getattr(sw, name)) > 0), name


# ---------------------------------------------------------------- shear


@pytest.mark.parametrize(("alpha", "force", "torque"), GCB_1967B_SHEAR)
def test_shear_factors_match_goldman_cox_brenner_table(alpha, force, torque):
    """F^s and T^s against Goldman, Cox & Brenner's (1967b) table: within 1e-4 (the fit to
    their eight finite gaps, with the contact values imposed, errs by at most 8e-5)."""
    gap = max(math.cosh(alpha) - 1, 1e-12)
    assert wm.shear_force(gap) == pytest.approx(force, abs=1e-4)
    assert wm.shear_torque(gap) == pytest.approx(torque, abs=1e-4)


def test_shear_velocity_limits():
    """Velocity of a free sphere in the wall shear. Far away Goldman, Cox & Brenner's
    reflection result U/(γ̇h) = 1 − (5/16) x³ (remainder ≤ x⁴ for h/a ≥ 5). Near contact
    the force and torque balance with their lubrication forms and contact F^s, T^s,
    (0.7431 ln ε − 0.5299)/(−0.2 ln² ε + 0.6376 ln ε − 0.3181), within 1e-3 for
    ε ≤ 1e-3, where its neglected O(ε ln ε) and the constants' last digits are below
    that. (Their quoted 0.7431/(0.6376 − 0.2 ln ε) is its leading term in 1/ln ε.)"""
    for h in (5.0, 10.0, 30.0):
        x = 1 / h
        assert abs(1 - wm.shear_velocity(h - 1) - 5 / 16 * x**3) <= x**4
    for eps in (1e-6, 1e-5, 1e-4, 1e-3):
        lg = math.log(eps)
        lub = (0.7431 * lg - 0.5299) / (-0.2 * lg * lg + 0.6376 * lg - 0.3181)
        assert wm.shear_velocity(eps) == pytest.approx(lub, rel=1e-3)


# ---------------------------------------------------------------- mobility and inputs


def test_mobility_2d_is_the_wall_frame_tensor():
    """M = λ∥⁻¹ (I − nn) + λ⊥⁻¹ nn for any wall normal: symmetric, n an eigenvector with
    1/λ⊥, the tangent with 1/λ∥, and the same for n and −n (to rounding)."""
    gap = 0.05
    sw = wm.sphere_wall(gap)
    for ang in np.linspace(0, 2 * np.pi, 7):
        n = np.array([math.cos(ang), math.sin(ang)])
        t = np.array([-n[1], n[0]])
        m = wm.wall_mobility(3 * n, gap)
        assert np.allclose(m, m.T, rtol=0, atol=1e-15)
        assert np.allclose(m @ n, n / sw.normal, rtol=1e-14, atol=1e-15)
        assert np.allclose(m @ t, t / sw.torque_free, rtol=1e-14, atol=1e-15)
        assert np.allclose(wm.wall_mobility(-n, gap), m, rtol=1e-14, atol=1e-15)


@pytest.mark.parametrize("gap", [0.0, -0.1, math.nan, math.inf])
def test_wrappers_reject_bad_gaps(gap):
    with pytest.raises(ValueError, match="gap"):
        wm.sphere_wall(gap)
    with pytest.raises(ValueError, match="gap"):
        wm.wall_mobility([1.0, 0.0], gap)


def test_wall_mobility_rejects_bad_normal():
    for bad in ([0.0, 0.0], [1.0], [math.nan, 1.0]):
        with pytest.raises(ValueError, match="normal"):
            wm.wall_mobility(bad, 0.1)


# ---------------------------------------------------------------- today's pillar_hydro


def test_pillar_hydro_is_the_first_reflection_of_the_parallel_drag():
    """``pillar_hydro`` at k = 1 without screening adds β/(1 − β), β = (9/16) x, to every
    bead's drag: far away it is the theory's λ∥ − 1 to O(x³) (both 9/16 x + (9/16)² x²;
    |difference| ≤ x³). Near contact it is isotropic and stays finite, where the theory
    is anisotropic: at ε = 0.1, 1 + ζ = 2.05 against λ∥ = 2.26 (within 10 %) and
    λ⊥ = 11.4 (5.6 times)."""
    a = 2.0
    mu = 1.0 / (6.0 * math.pi * a)  # 6πμa = 1: ζ is the dimensionless excess drag
    for h in (5.0, 10.0, 20.0):
        zeta = np.zeros(1)
        wall_drag(np.array([h * a]), a, 1.0, 1e300, mu, zeta)
        x = 1 / h
        assert abs(zeta[0] - (wm.sphere_wall(h - 1).torque_free - 1)) <= x**3
    zeta = np.zeros(1)
    wall_drag(np.array([1.1 * a]), a, 1.0, 1e300, mu, zeta)
    sw = wm.sphere_wall(0.1)
    assert 1 + zeta[0] == pytest.approx(2.05, abs=0.01)
    assert sw.torque_free == pytest.approx(2.26, abs=0.01)
    assert sw.normal == pytest.approx(11.4, abs=0.1)


# ---------------------------------------------------------------- the flow's normal push


@pytest.mark.parametrize("eps", [1e-6, 1e-4, 1e-2, 0.1, 0.5, 1.0, 3.0, 30.0, 1e3])
def test_axisymmetric_solver_gives_brenner_with_his_boundary_data(eps):
    """The solver of c_n (plane and sphere conditions per order n, Stimson & Jeffery's force
    sum) fed a sphere translating towards the wall returns Brenner's λ⊥, summed from his
    closed form: 1e-10 relative (measured 4e-15 and below for ε ≥ 1e-2; 3e-12 and 4e-12
    at ε = 1e-4 and 1e-6, where both sums lose digits to the determinant's cancellation)."""
    assert translation_force(1 + eps) == pytest.approx(brenner_normal(1 + eps), rel=1e-10)


def _normal_push_mp(h: float, digits: int = 40) -> float:
    """c_n from the unscaled series in 40-digit arithmetic (the double-precision sum divides
    every order by e^((2n+1)α) and uses Brenner's factored determinant)."""
    mp = pytest.importorskip("mpmath")
    mp.mp.dps = digits
    al = mp.acosh(mp.mpf(h))
    c = mp.sinh(al)
    total = mp.mpf(0)
    for n in range(1, int(60 / float(al)) + 41):
        p, q = n - mp.mpf(1) / 2, n + mp.mpf(3) / 2

        def pk(m, xi):
            return (m * m + m / mp.tanh(xi)) * mp.e ** (-m * xi)

        def dpk(m, xi):
            return -m / mp.sinh(xi) ** 2 * mp.e ** (-m * xi) - m * pk(m, xi)

        k = 2 * mp.sqrt(2) / 3 * c**4 * n * (n + 1)
        g = k * (pk(p, al) / (2 * n - 1) - pk(q, al) / (2 * n + 3))
        dg = k * (dpk(p, al) / (2 * n - 1) - dpk(q, al) / (2 * n + 3))
        a11 = mp.cosh(p * al) - mp.cosh(q * al)
        a12 = mp.sinh(p * al) - p / q * mp.sinh(q * al)
        a21 = p * mp.sinh(p * al) - q * mp.sinh(q * al)
        b = (a21 * g - a11 * dg) / (p * a11 * a11 - a12 * a21)
        total += 4 * b / (2 * n + 3)
    force = 2 * mp.sqrt(2) * mp.pi / c * total
    return float(force / (6 * mp.pi * (-h * h)))


@pytest.mark.parametrize("eps", [1e-4, 1e-2, 0.5, 9.0])
def test_normal_push_double_precision_sum_against_40_digits(eps):
    """The double-precision c_n against the unscaled series in 40 digits: 1e-12 (measured
    7e-14 at ε = 1e-4, 2e-15 elsewhere); doubling the terms changes it by < 1e-14."""
    got = normal_push(1 + eps)
    assert got == pytest.approx(_normal_push_mp(1 + eps), rel=1e-12)
    longer = normal_push(1 + eps, n_terms=2 * (int(60 / math.acosh(1 + eps)) + 40))
    assert longer == pytest.approx(got, rel=1e-14)


def test_normal_push_far_field_and_contact():
    """Far away c_n = (1 + x²/3) λ⊥ + O(x³) = 1 + (9/8) x + (81/64 + 1/3) x² + O(x³): Faxén's
    a²∇²u/6 of the quadratic flow and the wall's reflection of the sphere's own force (the
    stresslet's reflection is O(x³)); remainder ≤ x³ for h/a ≥ 5 (measured 0.57 to 0.63 x³).
    At contact c_n → 3.23, Goren & O'Neill's value (0.005: we get 3.2293 at ε = 1e-6, and
    c_n changes like −3 ε there: by 2.8e-5 from ε = 1e-5 to 1e-6)."""
    for h in (5.0, 10.0, 30.0, 100.0):
        x = 1 / h
        far = 1 + 9 / 8 * x + (81 / 64 + 1 / 3) * x * x
        assert abs(normal_push(h) - far) <= x**3
    c0 = normal_push(1 + 1e-6)
    assert c0 == pytest.approx(3.23, abs=0.005)
    assert 0 < c0 - normal_push(1 + 1e-5) < 4e-5


def test_normal_push_kernel_against_exact_and_monotone():
    """The fitted c_n against the exact series on the check gaps (1e-6 to 1e3): relative error
    ≤ 2e-6 (the fit's own largest is 1.3e-6); strictly decreasing in ε (20001 gaps from 1e-7
    to 1e4); and a force-free sphere's normal velocity c_n/λ⊥ vanishes like c_n(0) ε at
    contact (1e-3 at ε = 1e-6)."""
    for eps in _check_gaps():
        assert wm.normal_push(eps) == pytest.approx(normal_push(1 + eps), rel=2e-6)
    sw = wm.sphere_wall(np.logspace(-7, 4, 20001))
    assert np.all(np.diff(sw.normal_push) < 0)
    sw = wm.sphere_wall(1e-6)
    assert sw.normal_push / sw.normal / 1e-6 == pytest.approx(3.2293, rel=1e-3)


def test_bead_coefficients_are_the_kernels():
    """The fused per-bead kernel returns the separate kernels' values (one logarithm shared):
    λ∥ or f_tt, λ⊥, the held sphere's shear force (rolling or not) and c_n, to 1e-14."""
    for eps in (1e-6, 1e-3, 0.1, 0.3, 1.0, 10.0, 300.0):
        sw = wm.sphere_wall(eps)
        free = wm.bead_coefficients(eps, True)
        fixed = wm.bead_coefficients(eps, False)
        want_free = (sw.torque_free, sw.normal, sw.torque_free * sw.shear_velocity, sw.normal_push)
        want_fixed = (sw.translation, sw.normal, sw.shear_force, sw.normal_push)
        assert free == pytest.approx(want_free, rel=1e-14)
        assert fixed == pytest.approx(want_fixed, rel=1e-14)
