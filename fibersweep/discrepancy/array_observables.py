"""The pillar-array observables of the workflow's registry (:mod:`.observables`).

A fiber measured through a pillar array is compared by what a sorting experiment
reports per fiber (the measured-table columns of :mod:`.array_schema`):

- ``fraction``: the displacement fraction f (1 displaced every row, 0 zigzag),
  the ``fraction`` column of an array sweep's runs; undefined (NaN) for a trapped
  fiber. Its noise: f is read from the lateral displacement over the rows crossed,
  f = Δy / (rows ε λy); a 1 µm error at each end (√2 µm in Δy) over the shipped
  config's 20 rows of ε λy = 8 µm is an error of about 0.009 in f; the default 0.01
  rounds it up.
- ``trapped``: whether the fiber stopped on a pillar (no noise: it is seen).
- ``mode``: zigzag, displacement, wrap-and-jump or mixed
  (:data:`fibersweep.analysis.modes.MODES` but trapped), when the fibers were imaged
  (no noise); undefined for a trapped fiber, which ``trapped`` counts.
- ``bend``: 1 - the smallest end-to-end distance over the contour length
  (``RunResult.min_end_to_end``), for flexible fibers; NaN for a rigid model.
  Its noise: 0.01, a 1 % error of an end-to-end distance read from an image.

Each entry has ``geometry='array'``: a channel run scores none of these, an array
run none of the channel's (:func:`fibersweep.discrepancy.observables.scored`).
"""

from __future__ import annotations

import math

from fibersweep.analysis.modes import MODES
from fibersweep.discrepancy.observable_types import NoiseLaw, Observable
from fibersweep.fiber.result import RunResult

__all__ = ["ARRAY_OBSERVABLES", "is_array_result"]


def is_array_result(r: RunResult) -> bool:
    """Whether a run went through a pillar array (it has a mode)."""
    return getattr(r, "mode", None) is not None


def _fraction(r: RunResult) -> float:
    return math.nan if r.mode == "trapped" else float(r.fraction)


def _bend(r: RunResult) -> float:
    e = float(r.min_end_to_end)
    return 1.0 - e if math.isfinite(e) else math.nan


#: The array observables, in table and report order.
ARRAY_OBSERVABLES: tuple[Observable, ...] = (
    Observable(
        "fraction",
        "continuous",
        "-",
        "displacement fraction f (1 displaced every row, 0 zigzag)",
        extract=_fraction,
        defined=("not_trapped",),
        required=True,
        noise=NoiseLaw("additive", 0.01),
        bounds=(-1.0, 2.0),
        unit_hint="fraction is the mean shift per row over the row shift ε period_y (1: displaced)",
        measures=("wasserstein",),
        geometry="array",
    ),
    Observable(
        "trapped",
        "binary",
        "",
        "whether the fiber stopped on a pillar",
        extract=lambda r: r.mode == "trapped",
        required=True,
        categories=("free", "trapped"),
        geometry="array",
    ),
    Observable(
        "mode",
        "class",
        "",
        "transport mode through the rows",
        extract=lambda r: r.mode,
        # trapped is its own observable: a trapped fiber's mode is undefined, so that
        # trapping enters the tests and the fit once
        defined=("not_trapped",),
        categories=tuple(m for m in MODES if m != "trapped"),
        geometry="array",
    ),
    Observable(
        "bend",
        "continuous",
        "-",
        "largest bending: 1 - smallest end-to-end distance / contour length",
        extract=_bend,
        strict=False,
        noise=NoiseLaw("reflected", 0.01),
        bounds=(0.0, 1.0),
        unit_hint="bend is 1 - end-to-end distance / contour length (0: straight)",
        geometry="array",
    ),
)
