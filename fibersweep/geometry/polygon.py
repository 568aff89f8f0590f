"""A convex polygon (counter-clockwise vertices) as a pillar shape."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ConvexPolygon", "ENTRY_MIN"]

ENTRY_MIN = 1e-9  # a segment must run this far (in link lengths) inside to cut the wall


@dataclass(frozen=True, eq=False)
class ConvexPolygon:
    """Convex polygon with counter-clockwise vertices.

    Attributes
    ----------
    vertices : ndarray, shape (n, 2), float64
        Corners, counter-clockwise, n ≥ 3 (µm, or lattice units after :meth:`in_units`).
    """

    vertices: np.ndarray

    @classmethod
    def from_vertices(cls, vertices) -> ConvexPolygon:
        """Checked constructor: at least 3 corners, strictly convex; made counter-clockwise.

        Raises
        ------
        ValueError
            Fewer than 3 vertices, repeated or collinear corners, or a non-convex outline.
        """
        v = np.array(vertices, dtype=np.float64)
        if v.ndim != 2 or v.shape[1] != 2 or v.shape[0] < 3:
            raise ValueError(f"a polygon needs at least 3 (x, y) vertices, got shape {v.shape}")
        if not np.all(np.isfinite(v)):
            raise ValueError("polygon vertices must be finite")
        d = np.roll(v, -1, axis=0) - v  # edge k: v[k] -> v[k + 1]
        dn = np.roll(d, -1, axis=0)
        cross = d[:, 0] * dn[:, 1] - d[:, 1] * dn[:, 0]
        dot = (d * dn).sum(axis=1)
        scale = float(np.max(np.abs(v - v.mean(axis=0)))) ** 2
        if np.any(np.abs(cross) <= 1e-12 * scale):
            raise ValueError(
                "polygon vertices must be distinct corners (no repeated or collinear ones)"
            )
        # convex and simple: every turn of one sign, and the turns add up to one full turn
        turning = float(np.arctan2(cross, dot).sum())
        if not (np.all(cross > 0) or np.all(cross < 0)) or abs(abs(turning) - 2 * np.pi) > 1e-6:
            raise ValueError("the polygon must be convex, its vertices in order around it")
        if cross[0] < 0:
            v = v[::-1].copy()
        return cls(np.ascontiguousarray(v))

    # ------------------------------------------------------------------ edges
    def _edges(self):
        v = self.vertices
        for k in range(len(v)):
            ax, ay = v[k]
            bx, by = v[(k + 1) % len(v)]
            yield ax, ay, bx, by

    # ------------------------------------------------------------- queries
    def inside(self, x, y, margin: float = 0.0) -> np.ndarray:
        """Points strictly inside (margin 0), or within ``margin`` of the outline too.

        Parameters
        ----------
        x, y : array_like
            Coordinates, broadcastable.
        margin : float
            Points whose distance to every edge line is > −margin count as inside.
        """
        x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        if margin == 0.0:
            inside = np.ones(np.broadcast(x, y).shape, dtype=bool)
            for ax, ay, bx, by in self._edges():
                # CCW vertices: interior is on the left of every edge.
                inside &= (bx - ax) * (y - ay) - (by - ay) * (x - ax) > 0.0
            return inside
        return self.edge_distance(x, y) > -margin

    def edge_distance(self, x, y) -> np.ndarray:
        """Smallest signed distance to the edge lines, > 0 inside (a bound, exact inside)."""
        out = np.full(np.broadcast(np.asarray(x), np.asarray(y)).shape, np.inf)
        for ax, ay, bx, by in self._edges():
            cross = (bx - ax) * (y - ay) - (by - ay) * (x - ax)
            out = np.minimum(out, cross / np.hypot(bx - ax, by - ay))
        return out

    def nearest(self, x, y) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Nearest outline point, outward normal there and signed distance (negative inside).

        Parameters
        ----------
        x, y : array_like, shape (m,)

        Returns
        -------
        points : ndarray, shape (m, 2)
        normals : ndarray, shape (m, 2)
            Unit outward normal of the outline at the nearest point (at a corner
            seen from outside: the direction from the corner to the point).
        distance : ndarray, shape (m,)
        """
        x = np.atleast_1d(np.asarray(x, dtype=np.float64))
        y = np.atleast_1d(np.asarray(y, dtype=np.float64))
        best = np.full(x.shape, np.inf)
        pts = np.zeros((x.size, 2))
        nrm = np.zeros((x.size, 2))
        for ax, ay, bx, by in self._edges():
            dx, dy = bx - ax, by - ay
            t = np.clip(((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy), 0.0, 1.0)
            px, py = ax + t * dx, ay + t * dy
            dist = np.hypot(x - px, y - py)
            better = dist < best
            best = np.where(better, dist, best)
            pts[better, 0] = px[better]
            pts[better, 1] = py[better]
            ln = np.hypot(dx, dy)
            nrm[better] = (dy / ln, -dx / ln)  # outward for CCW
        inside = self.inside(x, y)
        outside_corner = ~inside & (best > 0)
        rel = np.column_stack([x - pts[:, 0], y - pts[:, 1]])
        nrm[outside_corner] = rel[outside_corner] / best[outside_corner, None]
        return pts, nrm, np.where(inside, -best, best)

    def signed_distance(self, x, y) -> np.ndarray:
        """Euclidean distance to the outline, negative inside."""
        shape = np.broadcast(np.asarray(x), np.asarray(y)).shape
        xb, yb = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
        return self.nearest(xb.ravel(), yb.ravel())[2].reshape(shape)

    def link_entry(self, x, y, ex: float, ey: float, closed: bool = False) -> np.ndarray:
        """Fraction t of the segment (x, y) → (x + e_x, y + e_y) where it enters the polygon.

        Cyrus–Beck clipping against the open half-planes of the edges; NaN if the
        clipped part is shorter than ``ENTRY_MIN`` (the segment misses the polygon,
        touches a vertex or runs along an edge). ``closed``: against the closed
        polygon (a touching segment counts).
        """
        x = np.asarray(x, dtype=np.float64)
        y = np.asarray(y, dtype=np.float64)
        t_in = np.zeros_like(x)
        t_out = np.ones_like(x)
        for ax, ay, bx, by in self._edges():
            # inside ⇔ cross > 0 for every edge; along the segment cross = c + t s
            c = (bx - ax) * (y - ay) - (by - ay) * (x - ax)
            s = (bx - ax) * ey - (by - ay) * ex
            with np.errstate(divide="ignore", invalid="ignore"):
                t = -c / s
            t_in = np.where(s > 0.0, np.maximum(t_in, t), t_in)
            t_out = np.where(s < 0.0, np.minimum(t_out, t), t_out)
            edge = -1e-12 if closed else 0.0
            t_out = np.where((s == 0.0) & (c <= edge), -1.0, t_out)  # parallel, outside
        length = t_out - t_in
        return np.where(length >= -1e-12 if closed else length > ENTRY_MIN, t_in, np.nan)

    def span_at(self, x) -> tuple[np.ndarray, np.ndarray]:
        """Lowest and highest y of the polygon on the vertical line(s) ``x`` (NaN off it).

        On a horizontal edge the value is that edge's y exactly.
        """
        x = np.atleast_1d(np.asarray(x, dtype=np.float64))
        lo = np.full(x.shape, np.inf)
        hi = np.full(x.shape, -np.inf)
        for ax, ay, bx, by in self._edges():
            if ax == bx:
                on = x == ax
                lo = np.where(on, np.minimum(lo, min(ay, by)), lo)
                hi = np.where(on, np.maximum(hi, max(ay, by)), hi)
                continue
            t = (x - ax) / (bx - ax)
            on = (t >= 0.0) & (t <= 1.0)
            yy = ay + t * (by - ay)
            lo = np.where(on, np.minimum(lo, yy), lo)
            hi = np.where(on, np.maximum(hi, yy), hi)
        miss = ~np.isfinite(lo)
        return np.where(miss, np.nan, lo), np.where(miss, np.nan, hi)

    # ------------------------------------------------------------ description
    def outline(self, n: int | None = None) -> np.ndarray:
        """The outline as polygon vertices, shape (k, 2) (``n`` is ignored: exact already)."""
        return self.vertices.copy()

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(x_min, y_min, x_max, y_max)."""
        lo, hi = self.vertices.min(axis=0), self.vertices.max(axis=0)
        return float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])

    @property
    def centroid(self) -> tuple[float, float]:
        """Area centroid (the vertex mean for a triangle)."""
        v = self.vertices
        if len(v) == 3:
            c = v.mean(axis=0)
            return float(c[0]), float(c[1])
        w = np.roll(v, -1, axis=0)
        cr = v[:, 0] * w[:, 1] - w[:, 0] * v[:, 1]
        area = cr.sum() / 2.0
        cx = ((v[:, 0] + w[:, 0]) * cr).sum() / (6.0 * area)
        cy = ((v[:, 1] + w[:, 1]) * cr).sum() / (6.0 * area)
        return float(cx), float(cy)

    @property
    def area(self) -> float:
        v = self.vertices
        w = np.roll(v, -1, axis=0)
        return float((v[:, 0] * w[:, 1] - w[:, 0] * v[:, 1]).sum() / 2.0)

    def in_units(self, dx: float) -> ConvexPolygon:
        """The same polygon with coordinates divided by ``dx`` (µm → lattice units)."""
        return ConvexPolygon(self.vertices / dx)

    def moved(self, shift_x: float, shift_y: float) -> ConvexPolygon:
        return ConvexPolygon(self.vertices + np.array([shift_x, shift_y]))

    def rotated(self, degrees: float, about: tuple[float, float]) -> ConvexPolygon:
        """Rotated counter-clockwise by ``degrees`` about the point ``about``."""
        a = np.radians(degrees)
        c, s = np.cos(a), np.sin(a)
        r = self.vertices - np.asarray(about)
        out = np.column_stack([c * r[:, 0] - s * r[:, 1], s * r[:, 0] + c * r[:, 1]])
        return ConvexPolygon(out + np.asarray(about))
