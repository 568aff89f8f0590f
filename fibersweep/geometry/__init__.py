"""Exact pillar geometry: one small frozen shape object per outline.

A shape (:class:`ConvexPolygon` or :class:`Circle`, coordinates in µm or, after
:meth:`in_units`, in lattice units) answers every geometric question the
solver, the contact model, the analysis and the plots ask of the pillar:
inside-test, signed distance, the fraction q at which a lattice link enters
the wall, the nearest outline point with its outward normal, the outline as a
polygon and the bounding box. :mod:`fibersweep.geometry.pillars` builds the
named shapes (triangle, circle, square, polygon) at a size, rotation and
placement; :class:`Geometry` (:mod:`fibersweep.geometry.channel`) is the channel
with one pillar, :mod:`fibersweep.geometry.array` the tilted pillar array.
"""

from fibersweep.geometry.channel import Geometry
from fibersweep.geometry.circle import Circle
from fibersweep.geometry.pillars import PILLAR_SHAPES, check_shape_name, pillar_shape
from fibersweep.geometry.polygon import ENTRY_MIN, ConvexPolygon

Shape = ConvexPolygon | Circle

__all__ = [
    "ENTRY_MIN",
    "Circle",
    "ConvexPolygon",
    "Geometry",
    "PILLAR_SHAPES",
    "Shape",
    "as_shape",
    "check_shape_name",
    "pillar_shape",
]


def as_shape(outline) -> Shape:
    """A shape as it stands, or a convex CCW polygon from an (n, 2) vertex array."""
    if isinstance(outline, ConvexPolygon | Circle):
        return outline
    return ConvexPolygon.from_vertices(outline)
