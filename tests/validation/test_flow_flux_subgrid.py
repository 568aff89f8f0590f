"""Flux below the pillar with a sub-grid wall: integrated to the exact base line.

A flow u = s y (y_b − y) between the channel wall and the pillar base (zero
above it) carries s y_b³ / 6 below the base. The trapezoid rule through the
nodes, closed by a linear fall to zero at the wall, is exact up to its own
O(Δx²) error whatever fraction q of a cell separates the last node from the
base; closing it half a cell above the last node (the staircase rule) adds an
error that depends on q.
"""

from __future__ import annotations

import numpy as np

from fibersweep.flow.analysis import flux_below_pillar
from fibersweep.flow.field import FlowField
from fibersweep.units import Geometry

DX = 4.0


def _relative_error(q: float, kind: str) -> float:
    yb = (93 + 0.5 + q) * DX
    geom = Geometry(pillar_y_base=yb)

    def fn(X, Y):
        return np.where(Y < yb, Y * (yb - Y), 0.0), 0.0 * X

    field = FlowField.from_function(
        fn, geom, DX, with_pillar=True, meta={"settings": {"pillar_boundary": kind}}
    )
    return float(flux_below_pillar(field).mean() / (yb**3 / 6.0) - 1.0)


def test_flux_to_the_exact_base_line_does_not_depend_on_q():
    qs = [0.1, 0.3, 0.5, 0.7, 0.9]
    exact = [_relative_error(q, "interpolated") for q in qs]
    half = [_relative_error(q, "staircase") for q in qs]
    # measured: exact-wall closure -1.14e-4 .. -1.12e-4 (the trapezoid error,
    # (Δx / y_b)² sized); half-cell closure -0.9e-4 .. -2.3e-4
    assert max(abs(e) for e in exact) < 2e-4, exact
    assert np.ptp(exact) < 5e-6, exact
    assert np.ptp(half) > 1e-4, half
