"""Exact wall distances of the lattice links that cross a full-depth wall (sub-grid geometry).

The pillar spans the whole channel depth, so whether a link leaves the fluid
and where it meets the wall depend only on its in-plane part: the link from
fluid node (i, j, k) along e = (e_x, e_y, e_z) meets the wall where the 2D ray
from the node centre along (e_x, e_y) does, at the same fraction q of the link
(0 < q ≤ 1, in units of the link length). :class:`Cuts` stores these fractions
for every link that enters the wall: links into a solid node, and links
between two fluid nodes that cut through a corner of the pillar (near sharp
corners such as the triangle's 60° vertices no node may lie inside for a cell or more; ignoring such
links would blunt the corners by an amount that depends on where they sit on
the lattice).

Two geometries are provided: any pillar shape of :mod:`fibersweep.geometry`
(the triangle, a circle, a square, a convex polygon: :func:`shape_cuts`) and
two plane walls normal to y (validation, :func:`slab_cuts`). Lattice
coordinates: node (i, j) sits at ((i + ½) Δx, (j + ½) Δx).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from fibersweep.flow.lattice import Grid
from fibersweep.flow.schemes import WALL_SCHEMES, get_wall_scheme
from fibersweep.geometry import ConvexPolygon, as_shape

__all__ = [
    "Cuts",
    "cuts_from_distance",
    "polygon_cuts",
    "shape_cuts",
    "slab_cuts",
    "pillar_cuts",
]

# The 8 in-plane directions (e_x, e_y) ≠ (0, 0) index q2[e_x + 1, e_y + 1].
_DIRS = [(ex, ey) for ex in (-1, 0, 1) for ey in (-1, 0, 1) if (ex, ey) != (0, 0)]


@dataclass(frozen=True)
class Cuts:
    """Wall fractions of the links from fluid nodes into solid nodes.

    Attributes
    ----------
    i, j : ndarray, shape (n,), int64
        Fluid nodes with at least one in-plane neighbour in the solid.
    q : ndarray, shape (n, 3, 3), float64
        ``q[m, e_x + 1, e_y + 1]``: fraction of the link from node m along
        (e_x, e_y) at which it meets the wall, in [0, 1]; NaN where the link
        does not enter the wall.
    scheme : str
        Interpolation used at these links: "trt" (default, exact for Poiseuille
        flow with TRT where the weights stay bounded) or "bfl" (linear
        Bouzidi–Firdaouss–Lallemand); see :func:`fibersweep.flow.ibb.ibb_coefficients`.
    """

    i: np.ndarray
    j: np.ndarray
    q: np.ndarray
    scheme: str = "trt"

    def lookup(self, nx: int, ny: int) -> np.ndarray:
        """Dense map (nx, ny) -> row of this table, −1 where the node has no cut link."""
        index = -np.ones((nx, ny), dtype=np.int64)
        index[self.i, self.j] = np.arange(self.i.size)
        return index

    @property
    def links(self) -> int:
        """Number of in-plane links cut by the wall."""
        return int(np.isfinite(self.q).sum())


def cuts_from_distance(
    solid: np.ndarray,
    distance: Callable[[np.ndarray, np.ndarray, int, int], np.ndarray],
    scheme: str = "trt",
) -> Cuts:
    """Tabulate the wall fraction of every in-plane link from a fluid node that enters the wall.

    Parameters
    ----------
    solid : ndarray, shape (nx, ny), bool
        Solid nodes; x is periodic, links leaving 0 ≤ j < ny are ignored (channel walls).
    distance : callable
        ``distance(x, y, e_x, e_y)`` with node-centre coordinates x, y in lattice
        units (arrays of equal shape): fraction q of the link to (x + e_x, y + e_y)
        at which it first enters the wall, NaN if it does not. Called for every
        link from a fluid node. With ``closed=True`` (asked for links into a
        solid node that do not enter the open wall region) the first point
        where the link touches the wall; NaN there means q = 1.
    scheme : str
        Stored in the result (:attr:`Cuts.scheme`).

    Returns
    -------
    Cuts

    Raises
    ------
    ValueError
        If a link into a solid node has no fraction in [0, 1] (the geometry and
        ``solid`` disagree).
    """
    nx, ny = solid.shape
    fi, fj = np.nonzero(~solid)
    found: dict[tuple[int, int], np.ndarray] = {}
    near = np.zeros(fi.size, dtype=bool)
    for ex, ey in _DIRS:
        ii = (fi + ex) % nx
        jj = fj + ey
        inside = (jj >= 0) & (jj < ny)
        into_solid = inside.copy()
        into_solid[inside] = solid[ii[inside], jj[inside]]
        with np.errstate(invalid="ignore"):
            t = np.asarray(distance(fi + 0.5, fj + 0.5, ex, ey), dtype=np.float64)
        # a link into a solid node on the outline may only touch the wall (run
        # along an edge, or meet it at its end): q is where it first touches
        touch = into_solid & np.isnan(t)
        if touch.any():
            t[touch] = distance(fi[touch] + 0.5, fj[touch] + 0.5, ex, ey, closed=True)
        t[touch & np.isnan(t)] = 1.0
        bad = into_solid & ~((t >= -1e-12) & (t <= 1.0 + 1e-12))
        if bad.any():
            raise ValueError(
                f"{int(bad.sum())} links along ({ex}, {ey}) end in a solid node but "
                "meet the wall outside the link"
            )
        t[~inside | ~((t >= -1e-12) & (t <= 1.0 + 1e-12))] = np.nan
        near |= np.isfinite(t)
        found[(ex, ey)] = t
    i, j = fi[near], fj[near]
    q = np.full((i.size, 3, 3), np.nan)
    for ex, ey in _DIRS:
        q[:, ex + 1, ey + 1] = np.clip(found[(ex, ey)][near], 0.0, 1.0)
    return Cuts(i=i.astype(np.int64), j=j.astype(np.int64), q=q, scheme=scheme)


def shape_cuts(grid: Grid, shape, scheme: str = "trt") -> Cuts:
    """Cuts of the links into a pillar shape given in µm (:mod:`fibersweep.geometry`).

    A segment enters a convex shape at most once; q is where it does
    (:meth:`link_entry`: Cyrus–Beck clipping for a polygon, the quadratic's
    root for a circle), exact up to rounding. ``grid.solid`` should be the
    closed shape (``make_grid(..., closed=True)``) so that no fluid node lies
    on the outline (q = 0).
    """
    lattice_shape = as_shape(shape).in_units(grid.dx)  # lattice units, node i at i + ½
    return cuts_from_distance(grid.solid, lattice_shape.link_entry, scheme)


def polygon_cuts(grid: Grid, vertices: np.ndarray, scheme: str = "trt") -> Cuts:
    """Cuts of the links into a convex polygon given in µm (counter-clockwise vertices)."""
    return shape_cuts(grid, ConvexPolygon(np.asarray(vertices, dtype=np.float64)), scheme)


#: Link interpolation of each sub-grid wall scheme (from :data:`WALL_SCHEMES`).
PILLAR_SCHEMES = {n: w.links for n, w in WALL_SCHEMES.items() if w.links is not None}


def pillar_cuts(grid: Grid, shape, kind: str) -> Cuts | None:
    """Cuts of the pillar for the wall scheme ``kind``; None for a staircase wall.

    ``shape``: a :mod:`fibersweep.geometry` shape or convex polygon vertices (n, 2) [µm].
    ``kind``: a name of :data:`fibersweep.flow.schemes.WALL_SCHEMES` (unknown: ValueError
    listing the valid ones).
    """
    scheme = get_wall_scheme(kind)
    if scheme.links is None:
        return None
    return shape_cuts(grid, shape, scheme.links)


def slab_cuts(grid: Grid, y_low: float, y_high: float, scheme: str = "trt") -> Cuts:
    """Cuts of two plane walls y = y_low and y = y_high (lattice units, y of node j is j + ½).

    ``grid.solid`` must be the nodes outside y_low < y < y_high (validation).
    """

    def distance(
        x: np.ndarray, y: np.ndarray, ex: int, ey: int, closed: bool = False
    ) -> np.ndarray:
        if ey == 0:
            return np.full_like(x, np.nan)
        t = ((y_low if ey < 0 else y_high) - y) / ey
        return np.where((t >= 0.0) & (t <= 1.0), t, np.nan)

    return cuts_from_distance(grid.solid, distance, scheme)
