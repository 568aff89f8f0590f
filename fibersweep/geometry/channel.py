"""The channel and its pillar: one single-pillar geometry, all lengths in µm.

The flow solver, the fiber's contact and the plots read the pillar through
:attr:`Geometry.shape` (:mod:`fibersweep.geometry`); a pillar array's unit cell
is one of these (:attr:`fibersweep.geometry.array.PillarArray.cell_geometry`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from fibersweep.geometry.circle import Circle
from fibersweep.geometry.pillars import centroid_height, pillar_shape, unit_width
from fibersweep.geometry.polygon import ConvexPolygon

__all__ = ["Geometry"]


@dataclass(frozen=True)
class Geometry:
    """Channel and pillar, all lengths in µm.

    The channel spans x ∈ [0, length) (periodic), y ∈ [0, width], z ∈ [0, depth].
    The pillar spans the full depth; its outline is :attr:`shape`
    (:mod:`fibersweep.geometry`). By default it is the model's equilateral
    triangle: base parallel to x, apex pointing to +y.

    Parameters
    ----------
    width, depth, length : float
        Channel width W_ch (y), depth H_ch (z) and periodic length L_ch (x) [µm].
    pillar_height : float
        Size h_obs of the pillar [µm]: the triangle's height (base to apex), the
        circle's diameter, the square's side, the scale of polygon vertices.
    pillar_x : float or None
        x of the pillar's centroid (the base centre of the unrotated triangle)
        [µm]; None means L_ch / 2.
    pillar_y_base : float or None
        y of the pillar's lowest point, the base line [µm]; None means the
        model's decision: centroid on the centreline (W_ch/2 − h_obs/3 for the triangle).
    pillar_shape : str
        ``triangle``, ``circle``, ``square`` or ``polygon``
        (:data:`fibersweep.geometry.PILLAR_SHAPES`).
    pillar_rotation : float
        Counter-clockwise rotation about the centroid [deg].
    pillar_vertices : tuple of (x, y) or None
        Corners of a ``polygon`` in units of h_obs (any origin).
    """

    width: float = 800.0
    depth: float = 40.0
    length: float = 2400.0
    pillar_height: float = 75.0
    pillar_x: float | None = None
    pillar_y_base: float | None = None
    pillar_shape: str = "triangle"
    pillar_rotation: float = 0.0
    pillar_vertices: tuple[tuple[float, float], ...] | None = None

    def __post_init__(self) -> None:
        if self.pillar_vertices is not None:
            verts = tuple((float(x), float(y)) for x, y in self.pillar_vertices)
            object.__setattr__(self, "pillar_vertices", verts)

    @property
    def pillar_base_length(self) -> float:
        """l_obs [µm], the unit of fiber lengths: the unrotated pillar's width in x.

        The triangle's side 2 h_obs / √3; the circle's diameter and the square's side h_obs.
        """
        return unit_width(self.pillar_shape, self.pillar_height, self.pillar_vertices)

    @property
    def base_center(self) -> tuple[float, float]:
        """(x of the centroid, y of the base line) [µm]; the base centre of the triangle."""
        x = self.length / 2.0 if self.pillar_x is None else self.pillar_x
        if self.pillar_y_base is None:
            rise = centroid_height(
                self.pillar_shape, self.pillar_height, self.pillar_rotation, self.pillar_vertices
            )
            yb = self.width / 2.0 - rise
        else:
            yb = self.pillar_y_base
        return float(x), float(yb)

    @cached_property
    def shape(self) -> ConvexPolygon | Circle:
        """The pillar's outline in the channel [µm] (:mod:`fibersweep.geometry`)."""
        xc, yb = self.base_center
        return pillar_shape(
            self.pillar_shape,
            self.pillar_height,
            xc,
            yb,
            self.pillar_rotation,
            self.pillar_vertices,
        )

    @property
    def vertices(self) -> np.ndarray:
        """Polygon pillar corners (n, 2), CCW [µm]; the triangle's: base-left, base-right, apex.

        Raises
        ------
        ValueError
            For a circle (use :attr:`shape`).
        """
        if not isinstance(self.shape, ConvexPolygon):
            raise ValueError(f"a {self.pillar_shape} pillar has no vertices; use Geometry.shape")
        return self.shape.vertices

    @property
    def centroid(self) -> tuple[float, float]:
        """(x, y) of the pillar centroid [µm]."""
        if self.pillar_shape == "triangle" and self.pillar_rotation % 360.0 == 0.0:
            xc, yb = self.base_center
            return xc, yb + self.pillar_height / 3.0
        return self.shape.centroid

    @property
    def top(self) -> float:
        """Highest y of the pillar [µm] (the apex of the triangle)."""
        return self.shape.bounds[3]

    @property
    def x_far(self) -> float:
        """x [µm] farthest from the pillar along the periodic channel (half a period away)."""
        return (self.base_center[0] + self.length / 2.0) % self.length

    def y_from_base(self, y_over_h: float) -> float:
        """Absolute y [µm] of a lateral position quoted as y/h_obs from the base line."""
        return self.base_center[1] + y_over_h * self.pillar_height

    def y_over_h(self, y: np.ndarray | float) -> np.ndarray | float:
        """Lateral position(s) y [µm] quoted as y/h_obs from the base line."""
        return (np.asarray(y) - self.base_center[1]) / self.pillar_height

    def inside_pillar(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Boolean mask of points strictly inside the pillar.

        Parameters
        ----------
        x, y : ndarray
            Coordinates [µm], any broadcastable shapes.
        """
        return self.shape.inside(x, y)

    def fits(self) -> bool:
        """True if the pillar lies strictly inside the channel."""
        x0, y0, x1, y1 = self.shape.bounds
        return bool(x0 > 0.0 and x1 < self.length and y0 > 0.0 and y1 < self.width)
