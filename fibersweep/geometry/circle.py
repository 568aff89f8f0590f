"""A circle as a pillar shape."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fibersweep.geometry.polygon import ENTRY_MIN

__all__ = ["Circle"]

OUTLINE_POINTS = 256  # corners of the polygon drawn for a circle


@dataclass(frozen=True)
class Circle:
    """Circle of centre (cx, cy) and radius r (µm, or lattice units after :meth:`in_units`)."""

    cx: float
    cy: float
    radius: float

    def __post_init__(self) -> None:
        if not (self.radius > 0 and math.isfinite(self.radius)):
            raise ValueError(f"circle radius must be positive and finite, got {self.radius}")

    def signed_distance(self, x, y) -> np.ndarray:
        """Euclidean distance to the circle, negative inside."""
        return (
            np.hypot(np.asarray(x, float) - self.cx, np.asarray(y, float) - self.cy) - self.radius
        )

    def inside(self, x, y, margin: float = 0.0) -> np.ndarray:
        """Points strictly inside (margin 0), or within ``margin`` outside the circle too."""
        return self.signed_distance(x, y) < margin if margin else self.signed_distance(x, y) < 0.0

    def nearest(self, x, y) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Nearest points on the circle (m, 2), outward normals (m, 2), signed distances (m,).

        At the centre itself the normal is taken along +x.
        """
        x = np.atleast_1d(np.asarray(x, dtype=np.float64))
        y = np.atleast_1d(np.asarray(y, dtype=np.float64))
        rx, ry = x - self.cx, y - self.cy
        r = np.hypot(rx, ry)
        safe = np.where(r > 0, r, 1.0)
        nx = np.where(r > 0, rx / safe, 1.0)
        ny = np.where(r > 0, ry / safe, 0.0)
        pts = np.column_stack([self.cx + self.radius * nx, self.cy + self.radius * ny])
        return pts, np.column_stack([nx, ny]), r - self.radius

    def link_entry(self, x, y, ex: float, ey: float, closed: bool = False) -> np.ndarray:
        """Fraction t of the segment (x, y) → (x + e_x, y + e_y) where it enters the disc.

        Roots of |d + t e|² = r² (d = start − centre), the stable quadratic
        formula; NaN if the part inside is shorter than ``ENTRY_MIN`` (misses or
        grazes). ``closed``: a grazing segment (tangent) counts.
        """
        x = np.asarray(x, dtype=np.float64)
        y = np.asarray(y, dtype=np.float64)
        dx, dy = x - self.cx, y - self.cy
        a = float(ex * ex + ey * ey)
        b = 2.0 * (dx * ex + dy * ey)
        c = dx * dx + dy * dy - self.radius * self.radius
        disc = b * b - 4.0 * a * c
        tol = 1e-12 * max(1.0, self.radius * self.radius) * a if closed else 0.0
        root = np.sqrt(np.maximum(disc, 0.0))
        qq = -0.5 * (b + np.where(b >= 0, root, -root))
        with np.errstate(divide="ignore", invalid="ignore"):
            t1, t2 = qq / a, np.where(qq != 0, c / qq, 0.0)
        t_lo, t_hi = np.minimum(t1, t2), np.maximum(t1, t2)
        t_in = np.maximum(t_lo, 0.0)
        t_out = np.minimum(t_hi, 1.0)
        length = t_out - t_in
        hit = (disc >= -tol) & (length >= -1e-12 if closed else length > ENTRY_MIN)
        return np.where(hit, t_in, np.nan)

    def span_at(self, x) -> tuple[np.ndarray, np.ndarray]:
        """Lowest and highest y of the disc on the vertical line(s) ``x`` (NaN off it)."""
        x = np.atleast_1d(np.asarray(x, dtype=np.float64))
        h2 = self.radius * self.radius - (x - self.cx) ** 2
        half = np.where(h2 >= 0, np.sqrt(np.maximum(h2, 0.0)), np.nan)
        return self.cy - half, self.cy + half

    def outline(self, n: int | None = None) -> np.ndarray:
        """``n`` (default 256) points on the circle, counter-clockwise, shape (n, 2)."""
        a = np.linspace(0.0, 2.0 * np.pi, n or OUTLINE_POINTS, endpoint=False)
        return np.column_stack(
            [self.cx + self.radius * np.cos(a), self.cy + self.radius * np.sin(a)]
        )

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(x_min, y_min, x_max, y_max)."""
        r = self.radius
        return self.cx - r, self.cy - r, self.cx + r, self.cy + r

    @property
    def centroid(self) -> tuple[float, float]:
        return float(self.cx), float(self.cy)

    @property
    def area(self) -> float:
        return math.pi * self.radius**2

    def in_units(self, dx: float) -> Circle:
        """The same circle with lengths divided by ``dx`` (µm → lattice units)."""
        return Circle(self.cx / dx, self.cy / dx, self.radius / dx)

    def moved(self, shift_x: float, shift_y: float) -> Circle:
        return Circle(self.cx + shift_x, self.cy + shift_y, self.radius)

    def rotated(self, degrees: float, about: tuple[float, float]) -> Circle:
        """Rotated counter-clockwise by ``degrees`` about ``about`` (moves only the centre)."""
        a = math.radians(degrees)
        rx, ry = self.cx - about[0], self.cy - about[1]
        return Circle(
            about[0] + math.cos(a) * rx - math.sin(a) * ry,
            about[1] + math.sin(a) * rx + math.cos(a) * ry,
            self.radius,
        )
