"""Published Stokes-flow cases: a sphere's drag in an array, between plates, at a wall; its spin.

Each case builds its box, runs to a steady state and returns the measured
number with its reference (the formulas are cited where they are defined).
Lengths and speeds in lattice units.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from fibersweep.resolved.box import Box
from fibersweep.resolved.lattice import FluidSettings, Lattice
from fibersweep.resolved.particle import Body, BodyState
from fibersweep.resolved.run import Coupled

__all__ = [
    "CaseResult",
    "sangani_acrivos_k",
    "faxen_midplane",
    "brenner_normal",
    "array_drag",
    "slit_drag",
    "wall_drag",
    "steady",
    "shear_spin",
    "jeffery_period",
]


@dataclass(frozen=True)
class CaseResult:
    """A measured value beside its reference.

    Attributes
    ----------
    value, reference : float
    steps : int
        Lattice steps run.
    seconds : float
        Wall time.
    detail : dict
        Case parameters (radius, box, solid fraction, ...).
    """

    value: float
    reference: float
    steps: int
    seconds: float
    detail: dict

    @property
    def error(self) -> float:
        """Relative error value/reference − 1."""
        return self.value / self.reference - 1.0


def sangani_acrivos_k(phi: float) -> float:
    """Drag factor K of a simple cubic array of spheres at solid fraction ``phi``.

    Hasimoto's (1959) series completed by Sangani & Acrivos (1982),
    K = 1/(1 − 1.7601 χ + χ³ − 1.5593 χ⁶ + 3.9799 χ⁸ − 3.0734 χ¹⁰), χ = φ^(1/3);
    it reproduces Zick & Homsy's (1982) table, K = 2.008, 2.810, 4.292 at
    φ = 0.027, 0.064, 0.125, to 0.2 % (0.8 % low at their φ = 0.216, K = 7.442;
    checked in the tests).
    """
    c = phi ** (1.0 / 3.0)
    return 1.0 / (1 - 1.7601 * c + c**3 - 1.5593 * c**6 + 3.9799 * c**8 - 3.0734 * c**10)


def faxen_midplane(x: float) -> float:
    """Drag factor of a sphere moving parallel to two plates, on the midplane.

    Faxén's result (Happel & Brenner 1965, eq. 7-4.39): λ = 1/(1 − 1.004 x +
    0.418 x³ + 0.21 x⁴ − 0.169 x⁵), x = a/l, l the distance from the centre to
    each plate (valid to x ≈ 0.5; Ganatos et al. 1980 agree there within 1 %).
    """
    return 1.0 / (1 - 1.004 * x + 0.418 * x**3 + 0.21 * x**4 - 0.169 * x**5)


def brenner_normal(h_over_a: float, terms: int = 200) -> float:
    """Brenner's (1961) exact drag factor of a sphere moving normal to a plane wall.

    λ = (4/3) sinh α Σ n(n+1)/((2n−1)(2n+3)) [(2 sinh((2n+1)α) + (2n+1) sinh 2α) /
    (4 sinh²((n+½)α) − (2n+1)² sinh² α) − 1], cosh α = h/a (h: centre to wall).
    """
    al = math.acosh(h_over_a)
    s = 0.0
    for n in range(1, terms + 1):
        if (2 * n + 1) * al > 700:  # the bracket is 1 + O(e^-(2n+1)α): the rest is below 1e-300
            break
        num = 2 * math.sinh((2 * n + 1) * al) + (2 * n + 1) * math.sinh(2 * al)
        den = 4 * math.sinh((n + 0.5) * al) ** 2 - (2 * n + 1) ** 2 * math.sinh(al) ** 2
        s += n * (n + 1) / ((2 * n - 1) * (2 * n + 3)) * (num / den - 1)
    return 4.0 / 3.0 * math.sinh(al) * s


def steady(run: Coupled, check: int = 200, tol: float = 1e-5, max_steps: int = 200_000
           ) -> tuple[np.ndarray, np.ndarray, int]:  # fmt: skip
    """Step a held body until its force changes by less than ``tol`` (relative) per ``check`` steps.

    Returns the force, torque and steps taken.
    """
    prev = None
    for s in range(check, max_steps + 1, check):
        for _ in range(check):
            f, t = run.step()
        scale = max(float(np.abs(f).max()), float(np.abs(t).max()), 1e-300)
        now = np.concatenate([f, t])
        if prev is not None and float(np.abs(now - prev).max()) < tol * scale:
            return f, t, s
        prev = now
    raise RuntimeError(f"no steady state in {max_steps} steps")


def array_drag(radius: float, n: int, tau: float = 1.0, force: float = 1e-6) -> CaseResult:
    """Drag factor K of a fixed sphere in a periodic cube of side ``n`` (a simple cubic array).

    The fluid is driven by a uniform body force g; the force on the sphere in
    a mean pressure gradient G = g is G V_cell = F/(1 − φ) (F the momentum
    exchanged with the fluid, which alone feels g), so
    K = F/((1 − φ) 6π μ a U), U the superficial velocity (the box average).
    """
    t0 = time.perf_counter()
    box = Box(n, n, n, periodic_y=True, z_mode="periodic")
    fluid = FluidSettings(tau=tau)
    lat = Lattice(box, fluid, force=(force, 0.0, 0.0))
    body = Body(radius)
    run = Coupled(lat, body, BodyState(np.full(3, n / 2.0)), motion="held")
    f, _, steps = steady(run)
    _, u = lat.velocity()
    us = float(u[0].sum()) / n**3
    phi = body.volume / n**3
    k = f[0] / ((1 - phi) * 6 * math.pi * fluid.nu * radius * us)
    return CaseResult(float(k), sangani_acrivos_k(phi), steps, time.perf_counter() - t0,
                      {"radius": radius, "box": n, "phi": phi, "tau": tau})  # fmt: skip


def _held_run(box: Box, radius: float, centre, velocity, tau: float, force=(0.0, 0.0, 0.0)):
    """Steady force on a held sphere (surface moving with ``velocity``), the fluid's total u_x."""
    fluid = FluidSettings(tau=tau)
    lat = Lattice(box, fluid, force=force)
    run = Coupled(lat, Body(radius), BodyState(np.asarray(centre, float), u=velocity),
                  motion="held")  # fmt: skip
    f, _, steps = steady(run)
    _, u = lat.velocity()
    return f, float(u[0].sum()), steps, fluid


def slit_drag(radius: float, gap: int, width: int, tau: float = 1.0, speed: float = 1e-4
              ) -> CaseResult:  # fmt: skip
    """Drag factor of a sphere moving along x on the midplane of a slit of ``gap`` nodes.

    The box is ``width`` × ``width`` × ``gap``, periodic in x and y, no-slip
    plates at z = 0 and z = gap; the sphere is held (quasi-steady Stokes flow).
    An isolated sphere between plates carries no net flux of fluid and sphere
    together; Stokes flow being linear, two steady runs give it: (A) the sphere's
    surface moving at ``speed`` in a fluid without body force, (B) the sphere at
    rest in the slit's Poiseuille flow of a body force g; the drag is
    F_A + c F_B with c setting the total flux Q_A + c Q_B + U V_sphere to zero.
    Reference: Faxén's midplane law at a/l = radius/(gap/2). The periodic images
    in x and y bias it (the tests bound that by two widths).
    """
    t0 = time.perf_counter()
    box = Box(width, width, gap, periodic_y=True, z_mode="walls")
    c0 = (width / 2, width / 2, gap / 2)
    fa, qa, sa, fluid = _held_run(box, radius, c0, (speed, 0.0, 0.0), tau)
    fb, qb, sb, _ = _held_run(box, radius, c0, (0.0, 0.0, 0.0), tau, force=(1e-6, 0.0, 0.0))
    vol = Body(radius).volume
    c = -(qa + speed * vol) / qb
    drag = fa[0] + c * fb[0]
    lam = -drag / (6 * math.pi * fluid.nu * radius * speed)
    x = radius / (gap / 2.0)
    return CaseResult(float(lam), faxen_midplane(x), sa + sb, time.perf_counter() - t0,
                      {"radius": radius, "gap": gap, "width": width, "a_over_l": x, "tau": tau,
                       "flux_weight": c})  # fmt: skip


def wall_drag(radius: float, h: float, width: int, height: int, tau: float = 1.0,
              speed: float = 1e-4) -> CaseResult:  # fmt: skip
    """Drag factor of a sphere moving towards a plane wall, centre at ``h`` from it.

    Box ``width`` × ``width`` × ``height``: the wall at z = 0, a second no-slip
    wall at z = height, periodic in x and y; the sphere (held, its surface
    moving at −``speed`` along z) is quasi-steady. Reference: Brenner's series at
    h/a; the far wall and the periodic images add to the drag, bounded in the
    tests by two box sizes.
    """
    t0 = time.perf_counter()
    box = Box(width, width, height, periodic_y=True, z_mode="walls")
    c = width / 2.0
    f_near, _, s1, fluid = _held_run(box, radius, (c, c, h), (0.0, 0.0, -speed), tau)
    lam_near = -f_near[2] / (6 * math.pi * fluid.nu * radius * -speed)
    return CaseResult(float(lam_near), brenner_normal(h / radius), s1, time.perf_counter() - t0,
                      {"radius": radius, "h_over_a": h / radius, "width": width,
                       "height": height, "tau": tau})  # fmt: skip


def shear_spin(radius: float, half_length: float, angle_deg: float, width: int, gap: int,
               tau: float = 1.0, shear: float = 2e-5) -> tuple[float, int, float]:  # fmt: skip
    """Torque-free spin of a body held in simple shear with its axis at ``angle_deg`` to the flow.

    Box ``width`` (x) × ``width`` (y) × ``gap`` (z), periodic in x and y, plates at
    z = 0 and z = gap sliding at ∓γ̇ gap/2 along x (u = γ̇ (z − gap/2)); the body at
    the centre, its axis in the x–z plane. Returns (ω_y/γ̇ with the sign of the
    vorticity, −½ for a sphere's rate ½, so reported as a positive rate; steps; s).
    """
    t0 = time.perf_counter()
    uw = shear * gap / 2.0
    box = Box(width, width, gap, periodic_y=True, z_mode="walls",
              wall_velocity=np.array([[-uw, 0.0, 0.0], [uw, 0.0, 0.0]]))  # fmt: skip
    lat = Lattice(box, FluidSettings(tau=tau))
    z = (np.arange(gap) + 0.5 - gap / 2.0) * shear
    u0 = np.zeros((3, gap, width, width))
    u0[0] = z[:, None, None]
    lat.init_velocity(u0)
    a = math.radians(angle_deg)
    st = BodyState(np.array([width / 2, width / 2, gap / 2]), p=(math.cos(a), 0.0, math.sin(a)))
    run = Coupled(lat, Body(radius, half_length), st, motion="spin")
    prev, steps = None, 0
    while steps < 200_000:
        for _ in range(200):
            run.step()
        steps += 200
        w = run.state.w[1]
        if prev is not None and abs(w - prev) < 1e-5 * abs(w):
            break
        prev = w
    return float(run.state.w[1] / shear), steps, time.perf_counter() - t0


def jeffery_period(radius: float, half_length: float, width: int, gap: int, tau: float = 1.0
                   ) -> tuple[float, float, int, float]:  # fmt: skip
    """Jeffery period γ̇T/2π and equivalent aspect ratio r_e of a rod from its two extreme spins.

    In Jeffery's orbit (any axisymmetric body, Bretherton 1962) the spin is
    γ̇/(r_e² + 1) with the axis along the flow and γ̇ r_e²/(r_e² + 1) along the
    gradient, so r_e = √(ω⊥/ω∥) and γ̇T/2π = r_e + 1/r_e = γ̇/√(ω∥ ω⊥).
    Returns (γ̇T/2π, r_e, steps, seconds).
    """
    w_par, s1, t1 = shear_spin(radius, half_length, 0.0, width, gap, tau)
    w_perp, s2, t2 = shear_spin(radius, half_length, 90.0, width, gap, tau)
    w_par, w_perp = abs(w_par), abs(w_perp)
    return 1.0 / math.sqrt(w_par * w_perp), math.sqrt(w_perp / w_par), s1 + s2, t1 + t2
