"""Exact wall distances of the lattice links that cross a full-depth wall (sub-grid geometry).

The pillar spans the whole channel depth, so whether a link leaves the fluid
and where it meets the wall depend only on its in-plane part: the link from
fluid node (i, j, k) along e = (e_x, e_y, e_z) meets the wall where the 2D ray
from the node centre along (e_x, e_y) does, at the same fraction q of the link
(0 ≤ q < 1, in units of the link length). :class:`Cuts` stores these fractions
for every fluid node next to a solid node and every in-plane direction.

Two geometries are provided: a convex polygon (the triangular pillar,
:func:`polygon_cuts`) and two plane walls normal to y (validation,
:func:`slab_cuts`). Lattice coordinates: node (i, j) sits at ((i + ½) Δx, (j + ½) Δx).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from fibersweep.flow.lattice import Grid

__all__ = ["Cuts", "cuts_from_distance", "polygon_cuts", "slab_cuts", "pillar_cuts"]

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
        (e_x, e_y) at which it meets the wall, in [0, 1); NaN where that
        neighbour is fluid (no wall on the link).
    """

    i: np.ndarray
    j: np.ndarray
    q: np.ndarray

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
    solid: np.ndarray, distance: Callable[[np.ndarray, np.ndarray, int, int], np.ndarray]
) -> Cuts:
    """Tabulate the wall fraction of every fluid→solid in-plane link.

    Parameters
    ----------
    solid : ndarray, shape (nx, ny), bool
        Solid nodes; x is periodic, links leaving 0 ≤ j < ny are ignored (channel walls).
    distance : callable
        ``distance(x, y, e_x, e_y)`` with node-centre coordinates x, y in lattice
        units (arrays of equal shape): fraction q of the link to (x + e_x, y + e_y)
        at which it first meets the wall. Called only for links whose end is solid.

    Returns
    -------
    Cuts

    Raises
    ------
    ValueError
        If a returned fraction lies outside [0, 1] (the geometry and ``solid`` disagree).
    """
    nx, ny = solid.shape
    fi, fj = np.nonzero(~solid)
    found: dict[tuple[int, int], np.ndarray] = {}
    near = np.zeros(fi.size, dtype=bool)
    for ex, ey in _DIRS:
        ii = (fi + ex) % nx
        jj = fj + ey
        hit = (jj >= 0) & (jj < ny)
        hit[hit] = solid[ii[hit], jj[hit]]
        near |= hit
        found[(ex, ey)] = hit
    i, j = fi[near], fj[near]
    q = np.full((i.size, 3, 3), np.nan)
    for ex, ey in _DIRS:
        hit = found[(ex, ey)][near]
        if not hit.any():
            continue
        t = np.asarray(distance(i[hit] + 0.5, j[hit] + 0.5, ex, ey), dtype=np.float64)
        if t.size and (t.min() < -1e-12 or t.max() > 1.0 + 1e-12):
            raise ValueError(
                f"wall fraction outside [0, 1] along ({ex}, {ey}): {t.min():.3g} .. {t.max():.3g}"
            )
        q[hit, ex + 1, ey + 1] = np.clip(t, 0.0, 1.0)
    return Cuts(i=i.astype(np.int64), j=j.astype(np.int64), q=q)


def _polygon_entry(vertices: np.ndarray) -> Callable:
    """Entry fraction of the segment (x, y) → (x + e_x, y + e_y) into a convex CCW polygon."""

    def distance(x: np.ndarray, y: np.ndarray, ex: int, ey: int) -> np.ndarray:
        t_in = np.zeros_like(x)
        for k in range(len(vertices)):
            ax, ay = vertices[k]
            bx, by = vertices[(k + 1) % len(vertices)]
            # inside ⇔ cross > 0 for every edge; along the segment cross = c + t s
            c = (bx - ax) * (y - ay) - (by - ay) * (x - ax)
            s = (bx - ax) * ey - (by - ay) * ex
            with np.errstate(divide="ignore", invalid="ignore"):
                t = np.where(s > 0.0, -c / s, 0.0)
            t_in = np.maximum(t_in, t)
        return t_in

    return distance


def polygon_cuts(grid: Grid, vertices: np.ndarray) -> Cuts:
    """Cuts of the links into a convex polygon given in µm (counter-clockwise vertices).

    The end node of a cut link lies strictly inside the polygon and its start
    node does not, so the segment enters the polygon once: q is the largest
    entry parameter over the edges (Cyrus–Beck clipping), exact up to rounding.
    """
    verts = np.asarray(vertices, dtype=np.float64) / grid.dx  # lattice units, node i at i + ½
    return cuts_from_distance(grid.solid, _polygon_entry(verts))


def pillar_cuts(grid: Grid, vertices: np.ndarray, kind: str) -> Cuts | None:
    """Cuts of the pillar for ``kind`` "interpolated", None for "staircase" (half-way links)."""
    if kind == "staircase":
        return None
    if kind != "interpolated":
        raise ValueError(f"unknown pillar boundary {kind!r}; valid: interpolated, staircase")
    return polygon_cuts(grid, vertices)


def slab_cuts(grid: Grid, y_low: float, y_high: float) -> Cuts:
    """Cuts of two plane walls y = y_low and y = y_high (lattice units, y of node j is j + ½).

    ``grid.solid`` must be the nodes outside y_low < y < y_high (validation).
    """

    def distance(x: np.ndarray, y: np.ndarray, ex: int, ey: int) -> np.ndarray:
        wall = y_low if ey < 0 else y_high
        return (wall - y) / ey if ey else np.full_like(x, np.nan)

    return cuts_from_distance(grid.solid, distance)
