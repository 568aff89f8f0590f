"""Where the pillars stand: the frame a fiber moves in (one pillar in its channel, or an array).

A pillar geometry is a *set of pillars*: one outline (the run's
:class:`~fibersweep.fiber.contact.pillar.PillarArrays`) and the translations at which
copies of it stand, with one background field
(:class:`~fibersweep.fiber.kernel.bundles.FlowArrays`) read at the beads. The
integrators never read the field or call the contact kernel themselves: they
ask the run's *frame* through two stages, resolved at compile time on the
frame's record type (as the effects' stages are, :mod:`fibersweep.fiber.kernel.hooks`):

``velocity(frame, flow, x, y, u)``
    Background velocity at the bead centres ``x, y`` (m,) [µm] into ``u`` (m, 2)
    [µm/s].
``contact(frame, pillar, x, y, fx, fy, st, dist)`` -> ``(n_pillars, cx, cy)``
    Contact forces on the beads (overwrites ``fx, fy`` [pN], stiffness ``st``
    [pN/µm], distance to the nearest pillar outline ``dist`` [µm]); returns the
    number of pillars touching (int) and the pillar-side point of the contact
    [µm] (NaN when none).

Two frames:

- :class:`Channel`, the single pillar between side walls: the field is the
  channel's (periodic along x), the pillar stands once. Its record has no
  fields and its stages are exactly the plain calls
  :func:`~fibersweep.flow.field.interpolate_ib` and
  :func:`~fibersweep.fiber.contact.pillar.pillar_forces`, so a single-pillar run is
  bit for bit what it was before frames existed, at the same speed.
- :class:`Lattice`, a tilted pillar array (:class:`fibersweep.geometry.array.PillarArray`):
  the fiber moves in unwrapped coordinates; the field is the unit cell padded
  with its periodic images (:meth:`fibersweep.flow.cell.CellField.extended`),
  beads are folded into the cell to read it; the contact force is summed over
  every pillar image within reach, each computed by the same contact kernel on
  the beads moved into that pillar's frame (two pillars at once when a fiber
  bridges a gap).

The integrators are compiled once per frame type (and set of effects); one
frame's code is not even compiled into the other's.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np
from numba.extending import overload

from fibersweep.fiber.contact.pillar import pillar_forces
from fibersweep.flow.field import interpolate_ib

__all__ = [
    "CHANNEL",
    "FRAMES",
    "Channel",
    "Lattice",
    "contact",
    "frame_contact",
    "frame_velocity",
    "lattice",
    "velocity",
]


class Channel(NamedTuple):
    """The single pillar in its channel (no fields: nothing to read, nothing to pay)."""


class Lattice(NamedTuple):
    """A tilted pillar array as the kernels read it (lengths in µm).

    Attributes
    ----------
    off : float
        Where cell node 0 sits in the padded field: ``pad`` × Δx.
    px, py : float
        Periods λx (along the flow) and λy (across).
    sy : float
        Row shift ε λy: row r + 1 stands this much higher than row r.
    bounds : ndarray, shape (4,)
        (x0, y0, x1, y1) of the cell's pillar (row 0, column 0).
    xs, ys, fxs, fys, sts, dists : ndarray, shape (n,)
        Scratch: folded or translated bead positions and one image's forces,
        stiffness and distances (a stage called on m ≤ n beads uses the first m).
    """

    off: float
    px: float
    py: float
    sy: float
    bounds: np.ndarray
    xs: np.ndarray
    ys: np.ndarray
    fxs: np.ndarray
    fys: np.ndarray
    sts: np.ndarray
    dists: np.ndarray


CHANNEL = Channel()
#: The frame record types (a contract test checks each implements both stages).
FRAMES = (Channel, Lattice)


def lattice(array, pad: int, dx: float, n: int) -> Lattice:
    """The frame of a pillar array whose padded cell field has ``pad`` nodes of margin.

    Parameters
    ----------
    array : fibersweep.geometry.array.PillarArray
    pad : int
        Nodes of periodic images on every side of the cell field.
    dx : float
        Node spacing [µm].
    n : int
        Beads of the fiber (the scratch size).
    """
    return Lattice(
        float(pad * dx),
        float(array.period_x),
        float(array.period_y),
        float(array.lateral_shift),
        np.array(array.shape.bounds, dtype=np.float64),
        *(np.zeros(n) for _ in range(6)),
    )


# Stubs: callable only inside Numba kernels, where they resolve per frame type.


def velocity(frame, flow, x, y, u):
    """Background velocity at beads (x, y) into ``u`` (m, 2)."""
    raise NotImplementedError("frame stage: call from a Numba kernel")


def contact(frame, pillar, x, y, fx, fy, st, dist):
    """Contact forces on beads (x, y): ``(n_pillars, cx, cy)``."""
    raise NotImplementedError("frame stage: call from a Numba kernel")


# ------------------------------------------------------------------ channel
def _channel_velocity(frame, flow, x, y, u):
    interpolate_ib(flow.ux, flow.uy, flow.dx, x, y, u)


def _channel_contact(frame, pillar, x, y, fx, fy, st, dist):
    hit, cx, cy = pillar_forces(pillar, x, y, fx, fy, st, dist)
    return np.int64(1) if hit else np.int64(0), cx, cy


# ------------------------------------------------------------------ lattice
def _lattice_velocity(frame, flow, x, y, u):
    m = x.shape[0]
    xs = frame.xs[:m]
    ys = frame.ys[:m]
    px = frame.px
    py = frame.py
    for i in range(m):
        r = math.floor(x[i] / px)
        yl = y[i] - r * frame.sy
        xs[i] = x[i] - r * px + frame.off
        ys[i] = yl - math.floor(yl / py) * py + frame.off
    interpolate_ib(flow.ux, flow.uy, flow.dx, xs, ys, u)


def _lattice_contact(frame, pillar, x, y, fx, fy, st, dist):
    m = x.shape[0]
    tx = frame.xs[:m]
    ty = frame.ys[:m]
    tfx = frame.fxs[:m]
    tfy = frame.fys[:m]
    tst = frame.sts[:m]
    tdist = frame.dists[:m]
    reach = pillar.r_cut
    b = frame.bounds
    px = frame.px
    py = frame.py
    x0 = x.min() - reach
    x1 = x.max() + reach
    y0 = y.min() - reach
    y1 = y.max() + reach
    for i in range(m):
        fx[i] = 0.0
        fy[i] = 0.0
        st[i] = 0.0
        dist[i] = 1e300
    count = np.int64(0)
    cx = math.nan
    cy = math.nan
    closest = 1e300
    for r in range(math.floor((x0 - b[2]) / px), math.floor((x1 - b[0]) / px) + 1):
        ox = r * px
        dy = r * frame.sy
        for c in range(math.floor((y0 - b[3] - dy) / py), math.floor((y1 - b[1] - dy) / py) + 1):
            oy = dy + c * py
            for i in range(m):
                tx[i] = x[i] - ox
                ty[i] = y[i] - oy
            hit, qx, qy = pillar_forces(pillar, tx, ty, tfx, tfy, tst, tdist)
            near = 1e300
            for i in range(m):
                fx[i] += tfx[i]
                fy[i] += tfy[i]
                st[i] += tst[i]
                near = min(near, tdist[i])
                if tdist[i] < dist[i]:
                    dist[i] = tdist[i]
            if hit:
                count += 1
                if near < closest:  # report the contact point of the closest pillar
                    closest = near
                    cx = qx + ox
                    cy = qy + oy
    return count, cx, cy


_VELOCITY = {Channel: _channel_velocity, Lattice: _lattice_velocity}
_CONTACT = {Channel: _channel_contact, Lattice: _lattice_contact}


def _impl(table: dict, frame, stage: str):
    cls = getattr(frame, "instance_class", None)
    if cls not in table:
        names = ", ".join(c.__name__ for c in table)
        raise TypeError(f"frame.{stage}: {frame} is not a frame record ({names})")
    return table[cls]


@overload(velocity)
def _ov_velocity(frame, flow, x, y, u):
    return _impl(_VELOCITY, frame, "velocity")


@overload(contact)
def _ov_contact(frame, pillar, x, y, fx, fy, st, dist):
    return _impl(_CONTACT, frame, "contact")


# ------------------------------------------------------------------ from Python
@nb.njit(cache=True)
def frame_velocity(frame, flow, x, y, u):
    """:func:`velocity` callable from Python (tests, plots): fills ``u`` (m, 2) [µm/s]."""
    velocity(frame, flow, x, y, u)


@nb.njit(cache=True)
def frame_contact(frame, pillar, x, y, fx, fy, st, dist):
    """:func:`contact` callable from Python: ``(n_pillars, cx, cy)``, fills the arrays."""
    return contact(frame, pillar, x, y, fx, fy, st, dist)
