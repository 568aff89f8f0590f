"""A resolved sphere in a tilted array's shifted-periodic cell: bump or zigzag, D_c by bisection.

The cell is that of :mod:`fibersweep.flow.cell` (pillar centred, x faces
shifted by ε λy), solved here on the resolved lattice with its z-midplane as a
mirror (the sphere's centre stays on it). The empty cell is driven by a body
force along x and one along y, combined (Stokes flow is linear) so that the
mean flow runs along x, as in :func:`fibersweep.flow.cell.solve_cell`.

Decision: the sphere starts on the apex of a pillar, its surface ``start_gap``
from it, and is followed (unwrapped across the cell's faces) past the next
``passes`` pillars; at the x of each pillar's centre it is above that pillar
(it was bumped up with the row shift) or below it (it went round the pillar's
lower side, the zigzag lane). A sphere that bumps at every pass bumps.
Near contact the lattice stops resolving the gap: below ``lub_range`` lattice
units the normal lubrication force of a sphere on a plane,
6πμa²(1/h − 1/h_c)(R/(R + a)) for the pillar's radius R (the curvature factor of
docs/validation/near-wall.md), is added implicitly, and a hard inelastic
contact keeps the gap at least ``contact_gap`` (the resolved run's contact law,
as the one-way model has its own).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from fibersweep.flow.lattice import W
from fibersweep.geometry.array import PillarArray
from fibersweep.resolved.box import Box
from fibersweep.resolved.lattice import FluidSettings, Lattice
from fibersweep.resolved.particle import Body, BodyState
from fibersweep.resolved.run import Coupled

__all__ = ["CellSettings", "Decision", "empty_cell", "decide", "critical_diameter"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class CellSettings:
    """The array cell and how the sphere is run in it.

    Attributes
    ----------
    shift : float
        Row shift ε.
    dx : float
        Node spacing [µm].
    pillar, period, depth : float
        Circle diameter, period λx = λy and channel depth H [µm] (gap G = period − pillar).
    tau : float
        Relaxation time (ν = (τ − ½)/3).
    reynolds : float
        Particle Reynolds number Re_p = u_g a/ν that sets the flow's speed, u_g the
        midplane speed through the gap, (3/2)(λ/G) × the superficial velocity.
    start_gap : float
        Initial surface gap to the pillar's apex [lattice units].
    lub_range : float
        Gap below which the lubrication correction acts [lattice units].
    contact_gap : float
        Least surface gap: a hard, inelastic contact stops the sphere there [lattice units].
    passes : int
        Pillars passed before deciding.
    threads : int, optional
        Threads of the lattice kernels (None: the lattice's default,
        :data:`fibersweep.resolved.lattice.SERIAL_BELOW`); no effect on the result.
    cache_dir : str, optional
        Folder that keeps the solved empty cell between processes (an ``.npz`` per
        shift, dx, τ and geometry); None: kept in memory for this process only.
    """

    shift: float
    dx: float = 2.0
    pillar: float = 40.0
    period: float = 80.0
    depth: float = 40.0
    tau: float = 1.0
    reynolds: float = 0.1
    start_gap: float = 1.0
    lub_range: float = 2.0
    contact_gap: float = 1.0
    passes: int = 2
    threads: int | None = None
    cache_dir: str | None = None

    @property
    def array(self) -> PillarArray:
        return PillarArray(pillar_shape="circle", pillar_size=self.pillar, period_x=self.period,
                           period_y=self.period, shift=self.shift, depth=self.depth)  # fmt: skip


@dataclass(frozen=True)
class Decision:
    """Outcome of one sphere.

    Attributes
    ----------
    diameter : float
        Sphere diameter [µm].
    bumped : tuple of bool
        Per pass: above the pillar at its centre's x.
    offsets : tuple of float
        Per pass: the centre's height above that pillar's centre [µm].
    steps : int
    seconds : float
    reynolds : float
        Re_p of the run.
    min_gap : float
        Smallest surface gap to a pillar met [µm].
    """

    diameter: float
    bumped: tuple
    offsets: tuple
    steps: int
    seconds: float
    reynolds: float
    min_gap: float

    @property
    def bumps(self) -> bool:
        """True if the sphere bumped at every pass."""
        return all(self.bumped)


def _box(cs: CellSettings) -> tuple[Box, object, int]:
    arr = cs.array
    s = arr.check_lattice(cs.dx)
    shape = arr.shape.in_units(cs.dx)
    nx = int(round(cs.period / cs.dx))
    nz = int(round(cs.depth / cs.dx))
    if nz % 2:
        raise ValueError("the depth must be an even number of cells (mirror midplane)")
    x = np.arange(nx) + 0.5
    X, Y = np.meshgrid(x, x, indexing="ij")
    solid = shape.inside(X, Y, margin=1e-9)
    box = Box(nx, nx, nz // 2, periodic_y=True, shift=s, z_mode="symmetric", solid=solid,
              shape=shape)  # fmt: skip
    return box, shape, s


def _steady_empty(box: Box, fluid: FluidSettings, force, tol: float = 1e-6,
                  threads: int | None = None) -> Lattice:  # fmt: skip
    lat = Lattice(box, fluid, force=force, threads=threads)
    prev = None
    for _ in range(1000):
        for _ in range(100):
            lat.step()
        _, u = lat.velocity()
        m = u.reshape(3, -1).sum(axis=1)
        if prev is not None and np.abs(m - prev).max() < tol * np.abs(m).max():
            return lat
        prev = m
    raise RuntimeError("the empty cell did not converge")


_EMPTY: dict = {}


def empty_cell(cs: CellSettings, radius: float) -> tuple[Lattice, float]:
    """The developed empty cell for a sphere of ``radius`` lattice units at ``cs.reynolds``.

    Returns the lattice (populations scaled to the speed) and the gap speed u_g.
    Solved once per (shift, dx, tau) with a unit force pair, then rescaled.
    """
    box, _, _ = _box(cs)
    fluid = FluidSettings(tau=cs.tau)
    key = (cs.shift, cs.dx, cs.tau, cs.pillar, cs.period, cs.depth)
    path = None
    if cs.cache_dir is not None:
        path = Path(cs.cache_dir) / ("resolved-empty-" + "-".join(f"{v:g}" for v in key) + ".npz")
        if key not in _EMPTY and path.exists():
            with np.load(path) as z:
                _EMPTY[key] = (z["dev"], float(z["us"]), z["force"])
    if key not in _EMPTY:
        t0 = time.perf_counter()
        g = 1e-6
        lx = _steady_empty(box, fluid, (g, 0.0, 0.0), threads=cs.threads)
        ly = _steady_empty(box, fluid, (0.0, g, 0.0), threads=cs.threads)
        _, ux = lx.velocity()
        _, uy = ly.velocity()
        alpha = -float(ux[1].sum()) / float(uy[1].sum())
        dev = (lx.f - _rest(box)) + alpha * (ly.f - _rest(box))
        us = (float(ux[0].sum()) + alpha * float(uy[0].sum())) / box.nodes
        _EMPTY[key] = (dev, us, np.array([g, alpha * g, 0.0]))
        log.info("empty cell eps=%g dx=%g: lateral force ratio %.4f, %d + %d steps, %.0f s",
                 cs.shift, cs.dx, alpha, lx.steps, ly.steps, time.perf_counter() - t0)  # fmt: skip
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(".tmp.npz")
            np.savez(tmp, dev=dev, us=us, force=_EMPTY[key][2])
            tmp.replace(path)
    dev, us, force = _EMPTY[key]
    u_gap_per_us = 1.5 * cs.period / (cs.period - cs.pillar)
    target = cs.reynolds * fluid.nu / radius / u_gap_per_us  # superficial velocity
    c = target / us
    lat = Lattice(box, fluid, force=force * c, threads=cs.threads)
    lat.f[:] = _rest(box) + c * dev
    return lat, target * u_gap_per_us


def _rest(box: Box) -> np.ndarray:
    return np.repeat(W[:, None], box.nodes, axis=1)


def _nearest_pillar(shape, box: Box, x: np.ndarray, radius: float) -> tuple[float, np.ndarray]:
    """Surface gap of a sphere at ``x`` (unwrapped) to the nearest pillar image, and the normal."""
    best, bx, by, br = math.inf, 0.0, 0.0, 1.0
    x0, x1 = float(x[0]), float(x[1])
    for di in (-1, 0, 1):
        rows = math.floor(x0 / box.nx) + di
        cx = shape.cx + rows * box.nx
        base = shape.cy + rows * box.shift
        m0 = math.floor((x1 - base) / box.ny)
        for dj in (-1, 0, 1, 2):
            cy = base + (m0 + dj) * box.ny
            d0, d1 = x0 - cx, x1 - cy
            r = math.hypot(d0, d1)
            h = r - shape.radius - radius
            if h < best:
                best, bx, by, br = h, d0, d1, r
    return best, np.array([bx, by, 0.0]) / br


def _contact(cs: CellSettings, shape, box: Box, radius: float, fluid: FluidSettings, gaps: list):
    """External action (implicit normal lubrication) and hard contact (least gap) at pillars."""
    R, mu, hc, hmin = shape.radius, fluid.nu, cs.lub_range, cs.contact_gap

    def act(st: BodyState):
        h, n = _nearest_pillar(shape, box, st.x, radius)
        gaps.append(h)
        zero = np.zeros(3)
        if h >= hc:
            return zero, zero, None
        zeta = 6 * math.pi * mu * radius**2 * (1 / max(h, hmin) - 1 / hc) * R / (R + radius)
        return zero, zero, zeta * np.outer(n, n)

    def keep(st: BodyState) -> BodyState:
        h, n = _nearest_pillar(shape, box, st.x, radius)
        if h >= hmin:
            return st
        un = float(st.u @ n)
        u = st.u - min(un, 0.0) * n  # an inelastic stop: no velocity into the pillar
        return replace(st, x=st.x + (hmin - h) * n, u=u)

    return act, keep


def decide(cs: CellSettings, diameter: float, max_steps: int | None = None) -> Decision:
    """Run a sphere of ``diameter`` µm from a pillar's apex past ``cs.passes`` pillars."""
    t0 = time.perf_counter()
    radius = diameter / 2.0 / cs.dx
    lat, u_gap = empty_cell(cs, radius)
    box, shape, s = _box(cs)
    fluid = lat.fluid
    start = np.array([shape.cx, shape.cy + shape.radius + radius + cs.start_gap, box.nz])
    gaps: list = []
    act, keep = _contact(cs, shape, box, radius, fluid, gaps)
    run = Coupled(lat, Body(radius), BodyState(start), motion="planar", external=act,
                  constrain=keep)
    nx = box.nx
    if max_steps is None:
        max_steps = int(40 * cs.passes * nx / u_gap)
    xs, ys = [start[0]], [start[1]]
    steps = 0
    while steps < max_steps and xs[-1] < start[0] + cs.passes * nx + 1:
        for _ in range(20):
            run.step()
        steps += 20
        xs.append(run.state.x[0])
        ys.append(run.state.x[1])
        if steps % 5000 == 0:
            log.debug("D = %g µm, step %d: x %.1f y %.1f (lattice units), %.0f s", diameter,
                      steps, xs[-1], ys[-1], time.perf_counter() - t0)  # fmt: skip
    if xs[-1] < start[0] + cs.passes * nx:
        raise RuntimeError(f"sphere D = {diameter} µm did not pass {cs.passes} pillars "
                           f"in {steps} steps (trapped?)")  # fmt: skip
    bumped, offs = [], []
    for k in range(1, cs.passes + 1):
        xk = start[0] + k * nx
        yk = float(np.interp(xk, np.array(xs), np.array(ys)))
        off = yk - (shape.cy + k * s)
        offs.append(off * cs.dx)
        bumped.append(off > 0)
    secs = time.perf_counter() - t0
    out = Decision(diameter, tuple(bumped), tuple(offs), steps, secs,
                   u_gap * radius / fluid.nu, min(gaps) * cs.dx)  # fmt: skip
    log.info("D = %.3g µm: %s", diameter, out)
    return out


def critical_diameter(cs: CellSettings, lo: float, hi: float, tol: float = 0.25
                      ) -> tuple[float, float, list[Decision]]:  # fmt: skip
    """Bisection on D [µm] between a zigzagging ``lo`` and a bumping ``hi`` to width ``tol``.

    Returns (largest zigzag D, smallest bump D, all decisions).
    """
    done = [decide(cs, lo), decide(cs, hi)]
    if done[0].bumps or not done[1].bumps:
        raise ValueError(f"bracket does not straddle the transition: {done}")
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        d = decide(cs, mid)
        done.append(d)
        lo, hi = (lo, mid) if d.bumps else (mid, hi)
    return lo, hi, done


def with_reynolds(cs: CellSettings, factor: float) -> CellSettings:
    """The same settings at ``factor`` × the Reynolds number."""
    return replace(cs, reynolds=cs.reynolds * factor)
