"""Sphere near a plane wall: resistances, mobility and the push of a wall shear, for all gaps.

A sphere of radius a, centre at distance h from a no-slip plane, gap δ = h − a,
ε = δ/a, x = a/h = 1/(1 + ε), and L = ln(h/δ) = ln(1 + 1/ε) (≈ ln(1/ε) near
contact, ≈ x far away). All quantities are dimensionless (over 6πμa, 6πμa²,
6πμa³ as the motion requires) and depend on ε only.

Quiescent fluid (exact values: :mod:`fibersweep.fiber.hydro.wall_exact`):

* motion normal to the wall, drag 6πμaU λ⊥ (Brenner 1961); near contact
  λ⊥ = 1/ε + (1/5) ln(1/ε) + 0.9713 + O(ε ln ε) (Cox & Brenner 1967), far away
  λ⊥ = 1 + (9/8) x + O(x²) (Lorentz);
* motion parallel to it: translation f_tt, rotation f_rr and their coupling f_tr
  (O'Neill 1964, Dean & O'Neill 1963, Goldman, Cox & Brenner 1967a; conventions
  of wallexact); near contact f_tt = (8/15) ln(1/ε) + 0.9543, (3/4) f_tr =
  (1/10) ln(1/ε) − 0.1930, (3/4) f_rr = (2/5) ln(1/ε) + 0.3709 (Goldman, Cox &
  Brenner's forms with the constants of Chaoui & Feuillebois 2003), far away
  f_tt = 1 + (9/16) x + O(x³) (Faxén), f_tr = x⁴/8, (3/4) f_rr = 1 + (5/16) x³;
* a sphere free to rotate (torque-free) translating parallel to the wall has
  the drag λ∥ = f_tt − f_tr²/f_rr.

Each is its exact singular and far-field terms plus a fitted remainder
x^m [P(x) + (1 − x) L Q(x)] (P of degree 5, Q of degree 2; the (1 − x) L term
carries the ε ln ε behaviour at contact), fitted in relative error to the exact
values for 1e-6 ≤ ε ≤ 1e3 (``scripts/tools/fit_wall_mobility.py``), with P(0) set so
that the far field is exact to the order shown:

    λ⊥         = 1/ε + (1/5)(L − x) + 1 + x/8      + x² [P + (1 − x) L Q]   to x²: (9/8)²
    f_tt       = (8/15)(L − x) + 1 + (9/16) x       + x² [...]               to x²: (9/16)²
    f_tr       = (2/15)(L − x − x²/2 − x³/3)        + x⁴ [...]               to x⁴: 1/8
    (3/4) f_rr = (2/5)(L − x − x²/2) + 1            + x³ [...]               to x³: 5/16

Largest relative error against the exact values over that range (f_tr: relative
to f_tt): λ⊥ 5e-8, f_tt 9e-8, f_tr 1.7e-7, f_rr 6e-7; each is strictly
monotone in ε (tests/validation/test_wall_mobility.py). Below ε = 1e-6 the
exact singular terms dominate.

Shear flow along the wall, u = γ̇ z (Goldman, Cox & Brenner 1967b): a sphere
held fixed at h feels the force 6πμa γ̇h F^s and the torque 4πμa³γ̇ T^s
(F^s, T^s → 1 far away; 1.7005 and 0.9440 at contact).
F^s = 1 + (9/16) x + (81/256) x² + b₃ x³ + x⁴ [c₀ + c₁x + c₂x² + d (1 − x) L] and
T^s = 1 + x³ [same form] are fitted to their table with the contact values
imposed (largest error 8e-5 in F^s and 7e-5 in T^s, the table's last digit);
b₃ makes the free sphere's velocity below exact to x³. A force-free,
torque-free sphere then translates with

    U / (γ̇h) = [F^s + (2/3) x (f_tr/f_rr) T^s] / λ∥,

→ 1 − (5/16) x³ far away and → 0 like 1/ln(1/ε) at contact. With Goldman, Cox
& Brenner's lubrication forms of f_tt, f_tr, f_rr and their contact F^s, T^s
the same expression is (0.7431 ln ε − 0.5299)/(−0.2 ln² ε + 0.6376 ln ε −
0.3181) (within 1e-3 of this kernel for ε ≤ 1e-3); their quoted limit
0.7431/(0.6376 − 0.2 ln ε) is its leading term in 1/ln ε, 8 % low at ε = 3e-3
and still 4 % low at ε = 1e-6.

Flow towards the wall, u_z = −α z² (Goren & O'Neill 1971): a sphere held
fixed at h feels 6πμa u_z(h) c_n, and a force-free one crosses the wall's
planes with c_n u_z(h)/λ⊥ (exact values: :func:`~fibersweep.fiber.hydro.wall_exact.normal_push`).
c_n = 1 + (9/8) x + (81/64 + 1/3) x² + x³ [P + (1 − x) L Q], fitted as the
resistances are (largest relative error 1.3e-6 over 1e-6 ≤ ε ≤ 1e3), → 3.2293
at contact.

For a bead near a wall, :func:`bead_coefficients` returns the four numbers the
near-wall effect needs (:mod:`fibersweep.fiber.hydro.nearwall`) from one logarithm.

The kernels are Numba functions of floats (ε > 0; a caller clamps the gap of an
overlapping bead); :func:`sphere_wall` and :func:`wall_mobility` are the
checked Python entry points.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np

__all__ = [
    "MIN_GAP",
    "ORDERS",
    "SHEAR_FORCE_CONTACT",
    "SHEAR_FORCE_X3",
    "SHEAR_TORQUE_CONTACT",
    "SphereWall",
    "bead_coefficients",
    "coupling_resistance",
    "mobility_2d",
    "normal_push",
    "normal_resistance",
    "parallel_resistance",
    "rotation_resistance",
    "shear_force",
    "shear_torque",
    "shear_velocity",
    "sphere_wall",
    "torque_free_resistance",
    "wall_mobility",
]

#: Smallest gap ε = δ/a the fits were checked at; smaller gaps follow the exact
#: singular terms.
MIN_GAP = 1e-6
#: Power m of the fitted remainder of λ⊥, f_tt, f_tr and (3/4) f_rr.
ORDERS = (2, 2, 4, 3)
#: Goldman, Cox & Brenner (1967b): F^s and T^s of a sphere touching the wall.
SHEAR_FORCE_CONTACT = 1.7005
SHEAR_TORQUE_CONTACT = 0.94399
#: x³ coefficient of F^s that makes U/(γ̇h) = 1 − (5/16) x³ + O(x⁴) far away (Goldman,
#: Cox & Brenner 1967b), given f_tt = 1 + (9/16) x + (81/256) x² + (729/4096 − 1/8) x³.
SHEAR_FORCE_X3 = 729.0 / 4096.0 - 0.125 - 0.3125

# Remainder coefficients (P₀..P₅, Q₀..Q₂) from scripts/tools/fit_wall_mobility.py.
_PERP = (
    0.1656249999999999,
    -0.35716270100246744,
    0.3045916308598886,
    0.030489377183638564,
    -0.15035798855841379,
    0.053105556011736284,
    0.214595971917417,
    -0.24699048161606396,
    0.07832867488259403,
)
_TT = (
    0.04973958333333334,
    -1.2110760235183469,
    1.9137693312503372,
    -0.8548595988575003,
    -0.032680727310589575,
    0.060234654805218016,
    1.086553416762528,
    -1.3717115087611982,
    0.45548915375748955,
)
_TR = (
    0.09166666666666667,
    -2.6632179862480156,
    4.910457279251752,
    -2.5652580791228896,
    0.08582719917156216,
    0.12769941973733315,
    2.5925966168751695,
    -3.6857477756729753,
    1.3214529368333208,
)
_RR = (
    0.17916666666666667,
    -4.968187424598754,
    8.977037433650715,
    -4.626513814311965,
    0.2199919004329716,
    0.18939873411684793,
    4.8717268767376645,
    -6.65210718279662,
    2.3062279096554685,
)
_PUSH = (
    -0.5686574597404721,
    -1.9383713625209842,
    4.759750354838983,
    -3.5561377414710176,
    0.6945704389242235,
    0.1142213201099662,
    1.1491464204880388,
    -2.1312796228627455,
    0.9837200746819827,
)
#: x² coefficient of c_n far away: the wall's reflection (9/8)² and Faxén's 1/3.
PUSH_X2 = 81.0 / 64.0 + 1.0 / 3.0
# Shear factors: (c₀, c₁, c₂, d) from the same script.
_FS = (
    -0.0036800496116118353,
    0.16195065276640383,
    -0.0771553687797921,
    0.0020580602947516203,
)
_TS = (
    -0.21371689987485684,
    0.2293414238282689,
    -0.07163452395341205,
    0.0011747892450165553,
)


@nb.njit(cache=True, inline="always")
def _gap_vars(gap: float) -> tuple[float, float]:
    """x = a/h and L = ln(h/δ) for the gap ε = δ/a."""
    return 1.0 / (1.0 + gap), math.log1p(1.0 / gap)


@nb.njit(cache=True, inline="always")
def _remainder(c, x: float, lg: float, m: int) -> float:
    """x^m [P(x) + (1 − x) L Q(x)] with P = c[0..5], Q = c[6..8] (Horner)."""
    p = c[5]
    for k in range(4, -1, -1):
        p = p * x + c[k]
    q = c[8]
    for k in range(7, 5, -1):
        q = q * x + c[k]
    return x**m * (p + (1.0 - x) * lg * q)


@nb.njit(cache=True)
def normal_resistance(gap: float) -> float:
    """λ⊥: drag on a sphere moving normal to the wall over 6πμaU [-] (gap ε = δ/a > 0)."""
    x, lg = _gap_vars(gap)
    return 1.0 / gap + 0.2 * (lg - x) + 1.0 + 0.125 * x + _remainder(_PERP, x, lg, 2)


@nb.njit(cache=True)
def parallel_resistance(gap: float) -> float:
    """f_tt: drag on a non-rotating sphere translating parallel to the wall over 6πμaU [-]."""
    x, lg = _gap_vars(gap)
    return 8.0 / 15.0 * (lg - x) + 1.0 + 0.5625 * x + _remainder(_TT, x, lg, 2)


@nb.njit(cache=True)
def coupling_resistance(gap: float) -> float:
    """f_tr: torque on the translating sphere over 6πμa²U = force on the rotating one over
    6πμa²Ω [-] (rotation in the sense of rolling along the wall)."""
    x, lg = _gap_vars(gap)
    lg3 = lg - x - 0.5 * x * x - x * x * x / 3.0
    return 2.0 / 15.0 * lg3 + _remainder(_TR, x, lg, 4)


@nb.njit(cache=True)
def rotation_resistance(gap: float) -> float:
    """f_rr: torque on a sphere rotating about a wall-parallel axis over 6πμa³Ω [-] (→ 4/3)."""
    x, lg = _gap_vars(gap)
    lg2 = lg - x - 0.5 * x * x
    return 4.0 / 3.0 * (0.4 * lg2 + 1.0 + _remainder(_RR, x, lg, 3))


@nb.njit(cache=True)
def torque_free_resistance(gap: float) -> float:
    """λ∥ = f_tt − f_tr²/f_rr: drag on a torque-free sphere moving parallel to the wall [-]."""
    f_tr = coupling_resistance(gap)
    return parallel_resistance(gap) - f_tr * f_tr / rotation_resistance(gap)


@nb.njit(cache=True)
def normal_push(gap: float) -> float:
    """c_n: force on a fixed sphere in the flow u_z = −α z² over 6πμa u_z(h) [-] (→ 1, 3.2293)."""
    x, lg = _gap_vars(gap)
    return 1.0 + x * (1.125 + x * PUSH_X2) + _remainder(_PUSH, x, lg, 3)


@nb.njit(cache=True)
def shear_force(gap: float) -> float:
    """F^s: force on a fixed sphere in the wall shear γ̇z over 6πμa γ̇h [-]."""
    x, lg = _gap_vars(gap)
    c = _FS
    far = 1.0 + x * (0.5625 + x * (81.0 / 256.0 + x * SHEAR_FORCE_X3))
    return far + x**4 * (c[0] + c[1] * x + c[2] * x * x + c[3] * (1.0 - x) * lg)


@nb.njit(cache=True)
def shear_torque(gap: float) -> float:
    """T^s: torque on a fixed sphere in the wall shear γ̇z over 4πμa³γ̇ [-]."""
    x, lg = _gap_vars(gap)
    c = _TS
    return 1.0 + x * x * x * (c[0] + c[1] * x + c[2] * x * x + c[3] * (1.0 - x) * lg)


@nb.njit(cache=True)
def shear_velocity(gap: float) -> float:
    """U/(γ̇h): velocity of a force-free, torque-free sphere in the wall shear γ̇z [-]."""
    x = 1.0 / (1.0 + gap)
    f_tr = coupling_resistance(gap)
    f_rr = rotation_resistance(gap)
    lam = parallel_resistance(gap) - f_tr * f_tr / f_rr
    return (shear_force(gap) + 2.0 / 3.0 * x * f_tr / f_rr * shear_torque(gap)) / lam


@nb.njit(cache=True)
def bead_coefficients(gap: float, free_rotation: bool) -> tuple[float, float, float, float]:
    """Drag and flow push of a sphere at gap ε = δ/a from a wall, from one logarithm.

    Parameters
    ----------
    gap : float
        ε = δ/a > 0.
    free_rotation : bool
        True: a torque-free sphere (it rolls: λ∥ and the torque-free push); False: a
        sphere that does not rotate (a bead of a fiber, turning with the fiber).

    Returns
    -------
    (lam_t, lam_n, c_t, c_n) : floats [-]
        Drag along the wall (λ∥ or f_tt) and across it (λ⊥), over 6πμa; the force on
        the sphere held in the wall shear (F^s, or F^s + (2/3) x (f_tr/f_rr) T^s
        with rotation free) over 6πμa u_t(h); c_n over 6πμa u_n(h). A force-free
        sphere moves with (c_t/lam_t) u_t along the wall and (c_n/lam_n) u_n across.
    """
    x, lg = _gap_vars(gap)
    lam_n = 1.0 / gap + 0.2 * (lg - x) + 1.0 + 0.125 * x + _remainder(_PERP, x, lg, 2)
    lam_t = 8.0 / 15.0 * (lg - x) + 1.0 + 0.5625 * x + _remainder(_TT, x, lg, 2)
    c = _FS
    far = 1.0 + x * (0.5625 + x * (81.0 / 256.0 + x * SHEAR_FORCE_X3))
    c_t = far + x**4 * (c[0] + c[1] * x + c[2] * x * x + c[3] * (1.0 - x) * lg)
    c_n = 1.0 + x * (1.125 + x * PUSH_X2) + _remainder(_PUSH, x, lg, 3)
    if free_rotation:
        f_tr = 2.0 / 15.0 * (lg - x - 0.5 * x * x - x * x * x / 3.0) + _remainder(_TR, x, lg, 4)
        f_rr = 4.0 / 3.0 * (0.4 * (lg - x - 0.5 * x * x) + 1.0 + _remainder(_RR, x, lg, 3))
        d = _TS
        t_s = 1.0 + x * x * x * (d[0] + d[1] * x + d[2] * x * x + d[3] * (1.0 - x) * lg)
        lam_t -= f_tr * f_tr / f_rr
        c_t += 2.0 / 3.0 * x * f_tr / f_rr * t_s
    return lam_t, lam_n, c_t, c_n


@nb.njit(cache=True)
def mobility_2d(nx: float, ny: float, gap: float) -> tuple[float, float, float]:
    """In-plane mobility of a torque-free sphere near a wall with unit normal (nx, ny).

    M = λ∥⁻¹ (I − n n) + λ⊥⁻¹ n n, in units of 1/(6πμa); returns (M_xx, M_xy, M_yy).
    """
    mt = 1.0 / torque_free_resistance(gap)
    mn = 1.0 / normal_resistance(gap)
    d = mn - mt
    return mt + d * nx * nx, d * nx * ny, mt + d * ny * ny


@dataclass(frozen=True)
class SphereWall:
    """Every dimensionless coefficient of a sphere at gap ε = δ/a from a plane wall.

    Attributes are floats, or arrays of the shape of the gaps asked for: ``gap``
    ε; ``normal`` λ⊥; ``translation`` f_tt; ``coupling`` f_tr; ``rotation``
    f_rr; ``torque_free`` λ∥; ``shear_force`` F^s; ``shear_torque`` T^s;
    ``shear_velocity`` U/(γ̇h); ``normal_push`` c_n (module docstring for each).
    """

    gap: float | np.ndarray
    normal: float | np.ndarray
    translation: float | np.ndarray
    coupling: float | np.ndarray
    rotation: float | np.ndarray
    torque_free: float | np.ndarray
    shear_force: float | np.ndarray
    shear_torque: float | np.ndarray
    shear_velocity: float | np.ndarray
    normal_push: float | np.ndarray


def _checked_gap(gap) -> np.ndarray:
    g = np.asarray(gap, dtype=np.float64)
    if not np.all(np.isfinite(g)) or np.any(g <= 0.0):
        raise ValueError(f"gap δ/a must be finite and > 0, got {gap!r}")
    return g


def sphere_wall(gap) -> SphereWall:
    """The sphere-wall coefficients at gap(s) ε = δ/a > 0 (float or array).

    Raises
    ------
    ValueError
        A gap that is not finite or not positive.
    """
    g = _checked_gap(gap)
    kernels = (
        normal_resistance,
        parallel_resistance,
        coupling_resistance,
        rotation_resistance,
        torque_free_resistance,
        shear_force,
        shear_torque,
        shear_velocity,
        normal_push,
    )
    flat = g.ravel()
    vals = [np.array([k(float(e)) for e in flat]).reshape(g.shape) for k in kernels]
    if g.ndim == 0:
        return SphereWall(float(g), *(float(v) for v in vals))
    return SphereWall(g, *vals)


def wall_mobility(normal, gap: float) -> np.ndarray:
    """2x2 mobility of a torque-free sphere near a wall, in units of 1/(6πμa).

    Parameters
    ----------
    normal : array_like, shape (2,)
        Wall normal (normalised here; any non-zero length).
    gap : float
        ε = δ/a > 0.

    Returns
    -------
    ndarray, shape (2, 2)
        λ∥⁻¹ (I − n n) + λ⊥⁻¹ n n.
    """
    n = np.asarray(normal, dtype=np.float64)
    if n.shape != (2,) or not np.all(np.isfinite(n)) or not np.any(n):
        raise ValueError(f"normal must be a finite non-zero 2-vector, got {normal!r}")
    g = float(_checked_gap(gap))
    n = n / np.hypot(n[0], n[1])
    mxx, mxy, myy = mobility_2d(float(n[0]), float(n[1]), g)
    return np.array([[mxx, mxy], [mxy, myy]])
