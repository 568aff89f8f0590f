"""The named pillar shapes, sized by h_obs, rotated and placed in the channel.

Every shape is built from a template of size h = h_obs whose centroid has
x = 0 and whose lowest point has y = 0:

- ``triangle``: equilateral, height h (side l_obs = 2h/√3), base parallel to x,
  apex towards +y (the model's pillar);
- ``circle``: diameter h;
- ``square``: side h, sides parallel to the axes;
- ``polygon``: any convex polygon, vertices given in units of h (any origin,
  any orientation).

The template is rotated counter-clockwise by ``rotation`` degrees about its
centroid, then moved so that the centroid has x = ``x`` and the lowest point
y = ``y_base`` (the base line from which lateral positions are quoted, y/h_obs).
"""

from __future__ import annotations

import difflib
import math

import numpy as np

from fibersweep.geometry.circle import Circle
from fibersweep.geometry.polygon import ConvexPolygon

__all__ = ["PILLAR_SHAPES", "check_shape_name", "pillar_shape", "template", "unit_width"]

PILLAR_SHAPES = ("triangle", "circle", "square", "polygon")


def check_shape_name(name: str) -> str:
    """``name`` if it is a registered shape, else ValueError listing the valid ones."""
    if name in PILLAR_SHAPES:
        return name
    close = difflib.get_close_matches(str(name), PILLAR_SHAPES, n=1, cutoff=0.5)
    hint = f"did you mean '{close[0]}'? " if close else ""
    raise ValueError(
        f"unknown pillar shape {name!r}; {hint}valid shapes: {', '.join(PILLAR_SHAPES)}"
    )


def _polygon_template(vertices, size: float) -> ConvexPolygon:
    if vertices is None:
        raise ValueError("pillar_vertices: pillar_shape 'polygon' needs its vertices")
    poly = ConvexPolygon.from_vertices(np.asarray(vertices, dtype=np.float64) * size)
    cx, _ = poly.centroid
    return poly.moved(-cx, -poly.bounds[1])


def template(name: str, size: float, vertices=None) -> ConvexPolygon | Circle:
    """The unrotated shape of size ``size`` [µm], centroid at x = 0, lowest point at y = 0."""
    check_shape_name(name)
    if name != "polygon" and vertices is not None:
        raise ValueError(
            f"pillar_vertices: only used with pillar_shape 'polygon' (here {name!r}); remove it"
        )
    if name == "triangle":
        half = 2.0 * size / math.sqrt(3.0) / 2.0
        return ConvexPolygon(np.array([[-half, 0.0], [half, 0.0], [0.0, size]]))
    if name == "circle":
        return Circle(0.0, size / 2.0, size / 2.0)
    if name == "square":
        s = size / 2.0
        return ConvexPolygon(np.array([[-s, 0.0], [s, 0.0], [s, size], [-s, size]]))
    return _polygon_template(vertices, size)


def unit_width(name: str, size: float, vertices=None) -> float:
    """Width in x of the unrotated shape, l_obs [µm] (the unit of fiber lengths)."""
    if name == "triangle":
        return 2.0 * size / math.sqrt(3.0)
    b = template(name, size, vertices).bounds
    return b[2] - b[0]


def _oriented(name: str, size: float, rotation: float, vertices) -> ConvexPolygon | Circle:
    """Template rotated about its centroid, lowest point back at y = 0."""
    shape = template(name, size, vertices)
    if rotation % 360.0 == 0.0:
        return shape
    shape = shape.rotated(rotation, shape.centroid)
    return shape.moved(-shape.centroid[0], -shape.bounds[1])


def centroid_height(name: str, size: float, rotation: float = 0.0, vertices=None) -> float:
    """Height of the centroid above the lowest point of the rotated shape [µm]."""
    if name == "triangle" and rotation % 360.0 == 0.0:
        return size / 3.0
    return _oriented(name, size, rotation, vertices).centroid[1]


def pillar_shape(
    name: str,
    size: float,
    x: float,
    y_base: float,
    rotation: float = 0.0,
    vertices=None,
) -> ConvexPolygon | Circle:
    """The pillar in the channel [µm].

    Parameters
    ----------
    name : str
        One of :data:`PILLAR_SHAPES`.
    size : float
        h_obs [µm]: triangle height, circle diameter, square side, polygon scale.
    x : float
        x of the centroid [µm] (the base centre of the unrotated triangle).
    y_base : float
        y of the lowest point [µm] (the base line of the unrotated triangle).
    rotation : float
        Counter-clockwise rotation about the centroid [deg].
    vertices : array_like, shape (n, 2), optional
        Polygon corners in units of ``size`` (``polygon`` only).

    Raises
    ------
    ValueError
        Unknown name (the valid ones listed), or bad polygon vertices.
    """
    shape = _oriented(name, size, rotation, vertices)
    if isinstance(shape, Circle):
        return Circle(x + shape.cx, y_base + shape.cy, shape.radius)
    # x + t and y_base + t, in this order: the default triangle's vertices come out
    # bit for bit as they always have (x − l/2, y_base), (x + l/2, y_base), (x, y_base + h)
    v = shape.vertices
    return ConvexPolygon(np.column_stack([x + v[:, 0], y_base + v[:, 1]]))
