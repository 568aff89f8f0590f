"""Exact Stokes resistances of a sphere near a plane wall (bispherical coordinates).

Reference solutions, evaluated to convergence; the fast kernels of
:mod:`fibersweep.fiber.hydro.wall_mobility` are fitted to them and tested against them.

A sphere of radius a has its centre at distance h from a no-slip plane;
δ = h − a is the gap, ε = δ/a. In bispherical coordinates the sphere is the
surface ξ = α with cosh α = h/a, the plane is ξ = 0, and every quantity is a
series over Legendre orders n whose terms decay like e^(−(2n+1)α): about
30/α terms give double precision, so a gap ε needs ~ 20/√ε terms.

Normal motion (Brenner 1961, Chem. Eng. Sci. 16, 242, his eq. 2.19): a sphere
moving towards the wall with speed U feels the drag 6πμaU λ⊥,

    λ⊥ = (4/3) sinh α Σ_{n≥1} n(n+1)/((2n−1)(2n+3))
         · [ (2 sinh((2n+1)α) + (2n+1) sinh 2α)
             / (4 sinh²((n+½)α) − (2n+1)² sinh² α) − 1 ].

Motion parallel to the wall (O'Neill 1964, Mathematika 11, 67, translation;
Dean & O'Neill 1963, Mathematika 10, 13, rotation about an axis parallel to the
wall; both as collected by Goldman, Cox & Brenner 1967, Chem. Eng. Sci. 22,
637): the velocity field is written with three families of coefficients
A_n, B_n, C_n (plus D_n, E_n derived from them), and the no-slip conditions
reduce to one three-term recurrence for A_n (n ≥ 1) with coefficients built
from k_n = (n + ½) coth((n + ½)α) − coth α; translation and rotation differ
only in its right-hand side and in two source terms of E_n and C_n. The force
is a sum of E_n + n(n+1) C_n, the torque a sum of all five families. The
recurrence is truncated at N ≈ 60/α + 40 (A_{N+1} = 0) and solved as a
tridiagonal system.

Conventions (all resistances positive, the sphere translating with U parallel
to the wall and rotating with Ω about the wall-parallel axis normal to U, in the
sense of rolling along the wall):

    F / (6πμa)  = −f_tt U + f_tr aΩ
    T / (6πμa²) =  f_tr U − f_rr aΩ

so f_tt → 1, f_rr → 4/3 (the free sphere's 8πμa³ over 6πμa³) and f_tr → 0 far
from the wall. Reciprocity makes the matrix symmetric: the torque on the
translating sphere and the force on the rotating one are computed from two
different systems, and their agreement is a check of the solution
(tests/validation/test_wall_mobility.py). Goldman, Cox & Brenner's
coefficients are F*_t^t = −f_tt, T*_t^t = (3/4) f_tr (torque over 8πμa²U),
F*_r^r = f_tr, T*_r^r = −(3/4) f_rr.

The flow's push normal to the wall (Goren & O'Neill 1971, Chem. Eng. Sci. 26,
325): a sphere held fixed at h in the axisymmetric flow towards the wall
u_z = −α z², u_r = α r z (the leading normal flow next to a no-slip wall, whose
normal velocity grows as the square of the distance), feels the force
6πμa u_z(h) c_n. In bispherical coordinates the total stream function is the
ambient ψ∞ = −(α/2) r² z² plus Brenner's general form, which vanishes with its
normal derivative on the plane; on the sphere it cancels ψ∞ and ∂ψ∞/∂ξ. With
(cosh ξ − μ)^(−1/2) = √2 Σ e^(−(n+½)ξ) P_n(μ) differentiated twice, ψ∞
expands as (cosh ξ − μ)^(−3/2) Σ G_n(ξ) C_{n+1}^(−1/2)(μ) with

    G_n = (√2/3) α c⁴ n(n+1) [(n − ½ + coth ξ) e^(−(n−½)ξ) − (n + 3/2 + coth ξ) e^(−(n+3/2)ξ)]

(c = a sinh α_s the focal distance), so the conditions decouple per order n
into 2×2 systems whose determinant is Brenner's (4/(2n+3)) [sinh²((n+½)α) −
(n+½)² sinh² α]. The force follows from the coefficients by Stimson &
Jeffery's sum. The same solver with Brenner's boundary data (a translating
sphere) returns his λ⊥ (tests/validation/test_wall_mobility.py). Far away
c_n = (1 + x²/3) λ⊥ + O(x³) = 1 + (9/8) x + (81/64 + 1/3) x² + O(x³) (Faxén's
a²∇²u/6 and the wall's reflection of the sphere's force); at contact it tends
to 3.23.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import solve_banded

__all__ = [
    "brenner_normal",
    "normal_push",
    "parallel_resistances",
    "terms_needed",
    "translation_force",
]

_SQRT2 = math.sqrt(2.0)


def _alpha(h_over_a: float) -> float:
    h = float(h_over_a)
    if not (math.isfinite(h) and h > 1.0):
        raise ValueError(f"h/a must be a finite number > 1, got {h_over_a!r}")
    return math.acosh(h)


def terms_needed(h_over_a: float) -> int:
    """Series length that converges to double precision at h/a (~ 60/α + 40).

    Capped so that no sinh((n + 3/2)α) overflows far from the wall, where a few
    terms suffice.
    """
    al = _alpha(h_over_a)
    return max(4, min(int(60.0 / al) + 40, int(690.0 / al) - 2))


def brenner_normal(h_over_a: float, n_terms: int | None = None) -> float:
    """Brenner's exact drag factor λ⊥ for motion normal to the wall.

    Parameters
    ----------
    h_over_a : float
        Centre-to-wall distance over the radius, > 1.
    n_terms : int, optional
        Terms of the series (default: :func:`terms_needed`).

    Returns
    -------
    float
        λ⊥ = F / (6πμaU) [-], ≥ 1.
    """
    al = _alpha(h_over_a)
    n_max = terms_needed(h_over_a) if n_terms is None else int(n_terms)
    n = np.arange(1, n_max + 1, dtype=float)
    # the bracket divided through by e^((2n+1)α), so that no term overflows; 1 − q by
    # expm1 and no second differences, as the denominator cancels to ~ n⁴α⁴ near contact
    q = np.exp(-(2 * n + 1) * al)
    one_q = -np.expm1(-(2 * n + 1) * al)
    t2 = (2 * n + 1) ** 2 * math.sinh(al) ** 2 * q
    num = (2 * n + 1) * math.sinh(2 * al) * q + t2 + 2.0 * q * one_q
    bracket = num / (one_q**2 - t2)
    terms = n * (n + 1) / ((2 * n - 1) * (2 * n + 3)) * bracket
    # sum the small terms first
    return float(4.0 / 3.0 * math.sinh(al) * np.sum(terms[::-1]))


def _recurrence(al: float, n_max: int) -> tuple[np.ndarray, np.ndarray]:
    """Banded matrix (3, N) of the A_n recurrence and k_n for n = 0 .. N + 2."""
    nn = np.arange(0, n_max + 3, dtype=float)
    k = (nn + 0.5) / np.tanh((nn + 0.5) * al) - 1.0 / math.tanh(al)
    n = nn[1 : n_max + 1]
    k_lo, k_n, k_hi = k[0:n_max], k[1 : n_max + 1], k[2 : n_max + 2]
    p = (2 * n - 1) * k_lo - (2 * n - 3) * k_n
    q = (2 * n + 5) * k_n - (2 * n + 3) * k_hi
    band = np.zeros((3, n_max))
    band[0, 1:] = (q * (n + 2) / (2 * n + 3))[:-1]  # A_{n+1}
    band[1] = -p * n / (2 * n + 1) - q * (n + 1) / (2 * n + 1)  # A_n
    band[2, :-1] = (p * (n - 1) / (2 * n - 1))[1:]  # A_{n-1}
    return band, k


def _force_and_torque(al, a_coef, k, e_src, c_src):
    """Force sum Σ (E_n + n(n+1) C_n) and torque sum over n = 0 .. N."""
    n_max = a_coef.shape[0]
    a_full = np.zeros(n_max + 2)  # A_0 .. A_{N+1}, both ends 0
    a_full[1 : n_max + 1] = a_coef
    n = np.arange(0, n_max + 1, dtype=float)
    a_lo = np.concatenate([[0.0], a_full[0:n_max]])
    a_n = a_full[0 : n_max + 1]
    a_hi = a_full[1 : n_max + 2]
    kn = k[0 : n_max + 1]
    e = e_src + kn * ((n - 1) * n / (2 * n - 1) * a_lo - (n + 1) * (n + 2) / (2 * n + 3) * a_hi)
    c = -2.0 * kn * ((n - 1) / (2 * n - 1) * a_lo - a_n + (n + 2) / (2 * n + 3) * a_hi) + c_src
    c[0] = 0.0
    b = (n - 1) * a_lo - (2 * n + 1) * a_n + (n + 2) * a_hi
    b[0] = 0.0
    d = 0.5 * (n + 1) * (n + 2) * a_hi - 0.5 * (n - 1) * n * a_lo
    ea = np.exp(-(2 * n + 1) * al)
    ct = 1.0 / math.tanh(al)
    torque = (2 + ea) * (n * (n + 1) * (2 * a_n + c * ct) - (2 * n + 1 - ct) * e) + (2 - ea) * (
        n * (n + 1) * b * ct - (2 * n + 1 - ct) * d
    )
    return float(np.sum((e + n * (n + 1) * c)[::-1])), float(np.sum(torque[::-1]))


def parallel_resistances(h_over_a: float, n_terms: int | None = None) -> tuple[float, ...]:
    """Exact resistances of a sphere moving parallel to the wall (module docstring).

    Parameters
    ----------
    h_over_a : float
        Centre-to-wall distance over the radius, > 1.
    n_terms : int, optional
        Truncation N of the recurrence (default: :func:`terms_needed`).

    Returns
    -------
    (f_tt, f_tr_translation, f_tr_rotation, f_rr) : tuple of float
        f_tt and f_rr [-]; the coupling twice, as the torque on the translating
        sphere and as the force on the rotating sphere (equal by reciprocity).
    """
    al = _alpha(h_over_a)
    n_max = terms_needed(h_over_a) if n_terms is None else int(n_terms)
    band, k = _recurrence(al, n_max)
    n = np.arange(1, n_max + 1, dtype=float)
    sa = math.sinh(al)
    n0 = np.arange(0, n_max + 1, dtype=float)
    s_n0 = np.sinh((n0 + 0.5) * al)

    # translation
    rhs = _SQRT2 * (
        2.0 / np.tanh((n + 0.5) * al)
        - 1.0 / np.tanh((n - 0.5) * al)
        - 1.0 / np.tanh((n + 1.5) * al)
    )
    a_t = solve_banded((1, 1), band, rhs)
    e_src = 2.0 * _SQRT2 * np.exp(-(n0 + 0.5) * al) / s_n0
    f_sum, t_sum = _force_and_torque(al, a_t, k, e_src, 0.0)
    f_tt = _SQRT2 / 6.0 * sa * f_sum
    f_tr_t = t_sum * sa**2 / (9.0 * _SQRT2)

    # rotation
    rhs = (
        (2 * n + 1) ** 2
        * (math.exp(al) / (2 * n - 1) + math.exp(-al) / (2 * n + 3))
        / np.sinh((n + 0.5) * al)
    )
    rhs -= (2 * n - 1) / np.sinh((n - 0.5) * al) + (2 * n + 3) / np.sinh((n + 1.5) * al)
    rhs *= -_SQRT2 * np.exp(-(n + 0.5) * al) / ((2 * n + 1) * sa)
    a_r = solve_banded((1, 1), band, rhs)
    ell = -(np.exp(-(n0 - 0.5) * al) / (2 * n0 - 1) - np.exp(-(n0 + 1.5) * al) / (2 * n0 + 3))
    ell /= _SQRT2
    e_src = (_SQRT2 * (2 * n0 + 1) * np.exp(-(n0 + 0.5) * al) - ell / sa) / s_n0
    c_src = 4.0 * ell / (sa * s_n0)
    f_sum, t_sum = _force_and_torque(al, a_r, k, e_src, c_src)
    f_tr_r = -_SQRT2 / 6.0 * sa**2 * f_sum
    f_rr = 4.0 / 9.0 * (1.0 - t_sum * sa**3 / (4.0 * _SQRT2))
    return f_tt, f_tr_t, f_tr_r, f_rr


def _axisymmetric_force(al: float, g: np.ndarray, dg: np.ndarray) -> float:
    """Force along the normal [over μ c U-scale] of the axisymmetric problem with sphere data G_n.

    ``g``, ``dg``: G_n(α) e^((n+½)α) and G_n'(α) e^((n+½)α), n = 1 .. N (scaled so
    that nothing overflows). The disturbance (cosh ξ − μ)^(−3/2) Σ U_n C_{n+1}^(−1/2),
    U_n = a_n (cosh((n−½)ξ) − cosh((n+3/2)ξ)) + b_n (sinh((n−½)ξ) − κ_n sinh((n+3/2)ξ)),
    κ_n = (2n−1)/(2n+3), vanishes with its normal derivative on the plane ξ = 0 and
    takes the values −G_n, −G_n' on the sphere ξ = α; the force is Stimson &
    Jeffery's (2√2π/c) Σ (a_n + b_n + c_n + d_n) = (2√2π/c) Σ 4 b_n/(2n+3), returned
    here without the factor 2√2π/c.
    """
    n = np.arange(1, g.shape[0] + 1, dtype=float)
    p = n - 0.5
    q = n + 1.5
    m = n + 0.5
    sa = math.sinh(al)
    # rows of the 2x2 system times e^(−(n+½)α): A11, A21 (A22 = p A11, A12 unused by b_n)
    e2 = np.exp(-2.0 * m * al)
    one_q = -np.expm1(-2.0 * m * al)
    a11 = -one_q * sa
    a21 = 0.5 * (p * (math.exp(-al) - e2 * math.exp(al)) - q * (math.exp(al) - e2 * math.exp(-al)))
    # determinant times e^(−(2n+1)α): (1/q) [(1 − e2)² − (2n+1)² sinh²α e2]
    det = (one_q**2 - (2.0 * m * sa) ** 2 * e2) / q
    b = (a21 * g - a11 * dg) / det * e2  # the rows carried e^(−(n+½)α), the data e^((n+½)α)
    terms = 4.0 * b / (2.0 * n + 3.0)
    return float(np.sum(terms[::-1]))


def _series_length(al: float) -> int:
    return max(4, int(60.0 / al) + 40)


def translation_force(h_over_a: float, n_terms: int | None = None) -> float:
    """λ⊥ from the axisymmetric solver of :func:`normal_push` with Brenner's boundary data.

    The sphere (radius 1) moves towards the plane with unit speed: ψ = −r²/2 on it,
    the data −G_n of that, G_n = −(c²/√2) n(n+1) [e^(−(n−½)α)/(2n−1) −
    e^(−(n+3/2)α)/(2n+3)]; the drag pushes it away from the plane. An
    independent route to :func:`brenner_normal` (which sums Brenner's closed form),
    used to check the solver.
    """
    al = _alpha(h_over_a)
    n_max = _series_length(al) if n_terms is None else int(n_terms)
    n = np.arange(1, n_max + 1, dtype=float)
    c = math.sinh(al)
    k = -(c * c / _SQRT2) * n * (n + 1)
    # G e^((n+½)α) and G' e^((n+½)α)
    g = k * (math.exp(al) / (2 * n - 1) - math.exp(-al) / (2 * n + 3))
    dg = k * (-(n - 0.5) * math.exp(al) / (2 * n - 1) + (n + 1.5) * math.exp(-al) / (2 * n + 3))
    return 2.0 * _SQRT2 * math.pi / c * _axisymmetric_force(al, g, dg) / (6.0 * math.pi)


def normal_push(h_over_a: float, n_terms: int | None = None) -> float:
    """Goren & O'Neill's c_n: force on a fixed sphere in the flow u_z = −α z² over 6πμa u_z(h).

    Parameters
    ----------
    h_over_a : float
        Centre-to-wall distance over the radius, > 1.
    n_terms : int, optional
        Terms of the series (default ~ 60/α + 40).

    Returns
    -------
    float
        c_n [-] (→ 1 far away, 3.23 at contact); a force-free sphere there moves
        across the wall with c_n u_z(h) / λ⊥.
    """
    al = _alpha(h_over_a)
    n_max = _series_length(al) if n_terms is None else int(n_terms)
    n = np.arange(1, n_max + 1, dtype=float)
    c = math.sinh(al)
    coth = 1.0 / math.tanh(al)
    k = _SQRT2 / 3.0 * c**4 * n * (n + 1)  # α = 1, a = 1
    p = n - 0.5
    q = n + 1.5
    ep = math.exp(al)
    em = math.exp(-al)
    g = k * ((p + coth) * ep - (q + coth) * em)
    inv_s2 = 1.0 / (c * c)
    dg = k * (-(inv_s2 + p * p + p * coth) * ep + (inv_s2 + q * q + q * coth) * em)
    force = 2.0 * _SQRT2 * math.pi / c * _axisymmetric_force(al, g, dg)
    h = float(h_over_a)
    return force / (6.0 * math.pi * (-h * h))
