"""Estimates of what a one-way sphere model of DLD leaves out, beside its critical diameter.

For the circle array of ``array_dc.py`` (G = 40 µm, H = 40 µm, dx = 2 µm)
at each ``--shifts`` ε it prints:

* the steric bound 2β of the simulated gap profile ū(s) (depth-integrated,
  across the gap at the pillar's top; :func:`fibersweep.flow.cell.first_streamline_width`);
* the same bound when the sphere samples the flow over its size: Faxén's
  ū_F = ū + (a²/6) ∂²ū/∂s² across the gap (the depth's own curvature scales ū
  by one factor at the midplane and moves no streamline), solved for
  D = 2β_F(a = D/2);
* confinement by the top and bottom walls: Faxén's midplane drag factor of a
  sphere between two walls, λ_c = 1/(1 − 1.004 x + 0.418 x³ + 0.21 x⁴ − 0.169 x⁵),
  x = a/(H/2), and what it does to the pillar's anisotropy at a contact gap
  (ε_w = δ/a = 0.1): λ⊥/λ∥ alone against (λ_c − 1 + λ⊥)/(λ_c − 1 + λ∥);
* the local plane against the pillar's curvature: near contact the normal
  resistance of a sphere beside a cylinder of radius R is the plane's times
  R/(a + R) (gap paraboloid radii aR/(a + R) and a, against a and a).

    python3 scripts/studies/arrays/dld_estimates.py [--shifts 0.1 0.2] [--diameters 15 20 25]
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.optimize import brentq

from fibersweep.config import parse_config
from fibersweep.fiber.hydro.wall_mobility import sphere_wall
from fibersweep.flow.cell import solve_cell

G = 40.0
H = 40.0
R_PILLAR = 20.0


def gap_profile(cfg) -> tuple[np.ndarray, np.ndarray]:
    """(s [µm], ū(s)) across the gap above the pillar's top, depth-integrated (any scale)."""
    array = cfg.flow.array.to_array()
    dx = cfg.flow.dx
    u = solve_cell(cfg.flow).u
    _, _, _, y1 = array.shape.bounds
    outline = array.shape.outline(720)
    x_top = outline[np.argmax(outline[:, 1]), 0]
    prof = u[0].sum(axis=0)[:, int(x_top / dx)]
    y = (np.arange(prof.size) + 0.5) * dx
    d = (y - y1) % array.period_y
    inside = d < array.gap
    order = np.argsort(d[inside])
    return d[inside][order], prof[inside][order]


def first_width(s: np.ndarray, u: np.ndarray, eps: float, gap: float) -> float:
    """β: ∫_0^β u ds = ε ∫_0^G u ds, u constant over each node's share of the gap (the
    rule of :func:`fibersweep.flow.cell.first_streamline_width`)."""
    edges = np.concatenate([[0.0], 0.5 * (s[1:] + s[:-1]), [gap]])
    q = np.concatenate([[0.0], np.cumsum(u * np.diff(edges))])
    return float(np.interp(eps * q[-1], q, edges))


def faxen_bound(s: np.ndarray, u: np.ndarray, eps: float, gap: float) -> float:
    """D with D = 2 β_F(a = D/2), ū_F = ū + a²/6 ū'' (ū'' by central differences)."""
    upp = np.gradient(np.gradient(u, s), s)

    def miss(d: float) -> float:
        a = 0.5 * d
        return 2.0 * first_width(s, u + a * a / 6.0 * upp, eps, gap) - d

    return brentq(miss, 1.0, 0.9 * gap)


def confinement(a: float) -> float:
    x = a / (0.5 * H)
    return 1.0 / (1.0 - 1.004 * x + 0.418 * x**3 + 0.21 * x**4 - 0.169 * x**5)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shifts", type=float, nargs="+", default=[0.1, 0.2])
    ap.add_argument("--diameters", type=float, nargs="+", default=[15.0, 20.0, 25.0])
    args = ap.parse_args()
    for eps in args.shifts:
        cfg = parse_config({
            "flow": {"dx": 2.0, "array": {"pillar_shape": "circle", "shift": eps}},
            "sweep": {"length": [20.0]},
            "run": {"output": "unused", "cache_dir": ".fibersweep-cache"},
        })  # fmt: skip
        s, u = gap_profile(cfg)
        beta = first_width(s, u, eps, G)
        fax = faxen_bound(s, u, eps, G)
        print(f"eps = {eps:g}: steric 2β of the simulated profile {2 * beta:.1f} µm; "
              f"with Faxén's in-plane sampling D = 2β_F(D/2) = {fax:.1f} µm")  # fmt: skip
    sw = sphere_wall(0.1)
    lam_n, lam_t = float(sw.normal), float(sw.torque_free)
    print(
        f"pillar wall at gap 0.1 a: λ⊥ = {lam_n:.2f}, λ∥ = {lam_t:.2f}, λ⊥/λ∥ = {lam_n / lam_t:.2f}"
    )
    for d in args.diameters:
        a = 0.5 * d
        lc = confinement(a)
        ratio = (lc - 1 + lam_n) / (lc - 1 + lam_t)
        curv = R_PILLAR / (a + R_PILLAR)
        print(f"D = {d:g} µm: D/H = {d / H:.2f}; two-wall drag λ_c = {lc:.2f}; "
              f"anisotropy {lam_n / lam_t:.2f} -> {ratio:.2f} with it; "
              f"sphere-cylinder / sphere-plane near contact R/(a+R) = {curv:.2f}")  # fmt: skip


if __name__ == "__main__":
    main()
