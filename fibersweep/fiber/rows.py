"""Fibers through many rows of a pillar array: the periodic frame and the rigid integrator.

The fiber lives in unwrapped lab coordinates (x along the flow, y across,
[µm]); the array (:class:`fibersweep.geometry.array.PillarArray`) is the unit
cell repeated at (r λx, r ε λy + c λy). Two model-agnostic pieces give any
integrator what it needs from the array, for bead positions (bx, by):

- :func:`cell_velocity`: background velocity, each bead folded into the cell
  and interpolated with the channel's IB kernel
  (:func:`fibersweep.flow.field.interpolate_ib`) in the cell field padded
  with its periodic images (:meth:`fibersweep.flow.cell.CellField.extended`);
- :func:`image_forces`: contact forces summed over every pillar image within
  reach of the fiber (two or more at once when it bridges a gap), each
  computed by the channel's contact kernel
  (:func:`fibersweep.fiber.contact.pillar_forces`, rough or smooth, any
  shape) on the beads translated into that pillar's frame.

:func:`integrate_rows` is the rigid model (the body-frame rigid multiblob
mobility of :mod:`fibersweep.fiber.mobility`, explicit midpoint steps bounded
as in :mod:`fibersweep.fiber.rigid`). A bead-spring integrator needs only the
two functions above in place of the channel's interpolation and contact.

Record columns (:data:`COLS`): t [s], xc, yc [µm], th [rad], contact (0/1),
pillars in contact (count), speed of the centre [µm/s].
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np

from fibersweep.fiber.contact import PillarArrays, pillar_forces
from fibersweep.fiber.mobility import body_velocity
from fibersweep.flow.field import interpolate_ib

__all__ = [
    "COLS",
    "DONE",
    "TRAPPED",
    "TIMEOUT",
    "FULL",
    "CellArrays",
    "RowParams",
    "cell_velocity",
    "image_forces",
    "integrate_rows",
    "run_rows",
    "work",
]

COLS = ("t", "xc", "yc", "th", "contact", "n_pillars", "speed")
NCOLS = len(COLS)
DONE, TRAPPED, TIMEOUT, FULL, FAILED = 0, 1, 2, 3, 4


class CellArrays(NamedTuple):
    """The array as the kernels read it.

    ``ux, uy``: the cell field padded by ``pad`` nodes (µm/s); ``dx`` [µm];
    ``px, py, sy``: λx, λy and the row shift ε λy [µm]; ``bounds``: (x0, y0,
    x1, y1) of the cell's pillar [µm].
    """

    ux: np.ndarray
    uy: np.ndarray
    dx: float
    pad: int
    px: float
    py: float
    sy: float
    bounds: np.ndarray


class RowParams(NamedTuple):
    """Stepping and stopping [µm, s, µm/s]."""

    max_disp: float
    contact_disp: float
    dt_max: float
    t_max: float
    x_end: float
    trap_speed: float
    trap_time: float


@nb.njit(cache=True)
def cell_velocity(cell, bx, by, fxl, fyl, u):
    """Background velocity at beads (bx, by) [µm] of the unwrapped array, into ``u`` (n, 2).

    ``fxl, fyl``: scratch (n,) for the folded positions.
    """
    n = bx.shape[0]
    off = cell.pad * cell.dx
    for i in range(n):
        r = math.floor(bx[i] / cell.px)
        yl = by[i] - r * cell.sy
        fxl[i] = bx[i] - r * cell.px + off
        fyl[i] = yl - math.floor(yl / cell.py) * cell.py + off
    interpolate_ib(cell.ux, cell.uy, cell.dx, fxl, fyl, u)


@nb.njit(cache=True)
def image_forces(cell, pillar, bx, by, fx, fy, st, dist, tx, ty, tfx, tfy, tst, tdist):
    """Contact forces of every pillar image within reach, summed (overwrites fx, fy, st, dist).

    Returns
    -------
    (any_contact, n_pillars) : (bool, int)
        Whether any force acts, and on how many distinct pillars.
    """
    n = bx.shape[0]
    reach = pillar.r_cut
    x0 = bx.min() - reach
    x1 = bx.max() + reach
    y0 = by.min() - reach
    y1 = by.max() + reach
    b = cell.bounds
    for i in range(n):
        fx[i] = 0.0
        fy[i] = 0.0
        st[i] = 0.0
        dist[i] = 1e300
    any_c = False
    count = 0
    for r in range(math.floor((x0 - b[2]) / cell.px), math.floor((x1 - b[0]) / cell.px) + 1):
        ox = r * cell.px
        dy = r * cell.sy
        for c in range(math.floor((y0 - b[3] - dy) / cell.py),
                       math.floor((y1 - b[1] - dy) / cell.py) + 1):  # fmt: skip
            oy = dy + c * cell.py
            for i in range(n):
                tx[i] = bx[i] - ox
                ty[i] = by[i] - oy
            hit, _, _ = pillar_forces(pillar, tx, ty, tfx, tfy, tst, tdist)
            if hit:
                any_c = True
                count += 1
            for i in range(n):
                fx[i] += tfx[i]
                fy[i] += tfy[i]
                st[i] += tst[i]
                if tdist[i] < dist[i]:
                    dist[i] = tdist[i]
    return any_c, count


@nb.njit(cache=True)
def _velocity(cell, pillar, s, pm, nm, w, xc, yc, th):
    """Rigid-body velocity at (xc, yc, th): (vx, vy, om, contact, n_pillars, min_dist, stiff)."""
    bx, by, u, fx, fy, st, dist, tx, ty, tfx, tfy, tst, tdist = w
    n = s.shape[0]
    c = math.cos(th)
    sn = math.sin(th)
    for i in range(n):
        bx[i] = xc + s[i] * c
        by[i] = yc + s[i] * sn
    cell_velocity(cell, bx, by, tx, ty, u)
    any_c, count = image_forces(cell, pillar, bx, by, fx, fy, st, dist, tx, ty, tfx, tfy, tst,
                                tdist)  # fmt: skip
    vbx, vby, om = body_velocity(c, sn, s, pm, nm, u.reshape(2 * n), fx, fy, any_c)
    md = 1e300
    stiff = 0.0
    for i in range(n):
        md = min(md, dist[i])
        stiff += st[i]
    return c * vbx - sn * vby, sn * vbx + c * vby, om, any_c, count, md, stiff


@nb.njit(cache=True)
def _implicit(cell, pillar, s, pm, nm, w, xc, yc, th, vx, vy, om, dt, half):
    """(I − dt J) Δ = dt f, J by forward differences: the new (xc, yc, th)."""
    h = 1e-3
    f0 = np.array([vx, vy, om])
    a = np.empty((3, 3))
    for k in range(3):
        dq = np.zeros(3)
        dq[k] = h if k < 2 else h / max(half, 1e-9)
        f = _velocity(cell, pillar, s, pm, nm, w, xc + dq[0], yc + dq[1], th + dq[2])
        fk = np.array([f[0], f[1], f[2]])
        for j in range(3):
            a[j, k] = (1.0 if j == k else 0.0) - dt * (fk[j] - f0[j]) / dq[k]
    d = np.linalg.solve(a, np.array([dt * vx, dt * vy, dt * om]))
    return xc + d[0], yc + d[1], th + d[2]


@nb.njit(cache=True)
def integrate_rows(state, cell, pillar, s, pm, nm, tip_m, p, w, rec):
    """Advance a rigid fiber through the array until done, trapped, timed out or ``rec`` is full.

    Parameters
    ----------
    state : ndarray, shape (5,)
        [t, xc, yc, th, stopped_since] (updated in place; NaN when not stopped).
    cell : CellArrays
    pillar : PillarArrays
        The cell's pillar (row 0, column 0).
    s, pm, nm, tip_m :
        Bead offsets and body-frame mobility (:func:`fibersweep.fiber.mobility.body_mobility`).
    p : RowParams
    w : tuple of 13 scratch arrays (n,) / (n, 2)
    rec : ndarray, shape (cap, NCOLS)

    Returns
    -------
    (rows, code)
    """
    t, xc, yc, th, since = state[0], state[1], state[2], state[3], state[4]
    half = 0.5 * (s[s.shape[0] - 1] - s[0])
    rows = 0
    code = FULL
    while rows < rec.shape[0]:
        vx, vy, om, any_c, count, md, stiff = _velocity(cell, pillar, s, pm, nm, w, xc, yc, th)
        speed = math.sqrt(vx * vx + vy * vy)
        r = rec[rows]
        r[0] = t
        r[1] = xc
        r[2] = yc
        r[3] = th
        r[4] = 1.0 if any_c else 0.0
        r[5] = count
        r[6] = speed
        rows += 1
        if not (math.isfinite(vx) and math.isfinite(vy) and math.isfinite(om)):
            code = FAILED
            break
        if xc >= p.x_end:
            code = DONE
            break
        if any_c and speed < p.trap_speed:
            if not math.isfinite(since):
                since = t
            elif t - since >= p.trap_time:
                code = TRAPPED
                break
        else:
            since = math.nan
        if t >= p.t_max:
            code = TIMEOUT
            break
        if math.isfinite(since):
            # stopped in contact: a linearly implicit Euler step (3x3 finite-difference
            # Jacobian), accepted only if the fiber is still stopped, as in fiber.rigid
            dti = max(min(p.max_disp / (speed + 1e-12), since + p.trap_time - t), 1e-9)
            xi, yi, ti = _implicit(cell, pillar, s, pm, nm, w, xc, yc, th, vx, vy, om, dti, half)
            f = _velocity(cell, pillar, s, pm, nm, w, xi, yi, ti)
            if f[3] and math.sqrt(f[0] * f[0] + f[1] * f[1]) < p.trap_speed:
                xc, yc, th, t = xi, yi, ti, t + dti
                continue
        disp = min(p.max_disp, max(p.contact_disp, 0.5 * (md - pillar.r_cut)))
        dt = min(disp / (speed + abs(om) * half + 1e-12), p.dt_max)
        if stiff > 0.0:
            dt = min(dt, 0.5 / (tip_m * stiff))
        vx2, vy2, om2, _, _, _, _ = _velocity(
            cell, pillar, s, pm, nm, w, xc + 0.5 * dt * vx, yc + 0.5 * dt * vy, th + 0.5 * dt * om
        )
        xc += dt * vx2
        yc += dt * vy2
        th += dt * om2
        t += dt
    state[0] = t
    state[1] = xc
    state[2] = yc
    state[3] = th
    state[4] = since
    return rows, code


def work(n: int) -> tuple:
    """Scratch arrays of :func:`integrate_rows` for n beads."""
    z = [np.zeros(n) for _ in range(12)]
    return (z[0], z[1], np.zeros((n, 2)), *z[2:12])


def run_rows(cell: CellArrays, pillar: PillarArrays, body, p: RowParams, x0: float, y0: float,
             th0: float, chunk: int = 20_000) -> tuple[np.ndarray, int]:  # fmt: skip
    """Integrate one rigid run from centre (x0, y0) [µm], angle th0 [rad].

    ``body``: a :class:`fibersweep.fiber.mobility.BodyMobility`.
    Returns the record (rows, NCOLS) and the stop code.
    """
    state = np.array([0.0, x0, y0, th0, math.nan])
    w = work(body.n)
    parts = []
    while True:
        rec = np.empty((chunk, NCOLS))
        rows, code = integrate_rows(state, cell, pillar, body.offsets, body.P, body.N,
                                    body.tip_mobility, p, w, rec)  # fmt: skip
        parts.append(rec[:rows])
        if code != FULL:
            return np.concatenate(parts), int(code)
