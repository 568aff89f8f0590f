"""The ``flow.array`` section: a tilted pillar array whose unit cell is the flow domain.

With ``flow.array`` set, the flow of a config is the steady flow of one unit
cell of the array (:func:`fibersweep.flow.cell.solve_cell`), with shifted
periodic boundaries; every flow setting applies to it as to the channel but
``flow.geometry`` (the cell is the domain) and ``flow.patch`` (the cell is
solved whole), which :class:`~fibersweep.config.flow.FlowSettings` refuses
with their reasons. The checks here name the
field at fault (``FieldError``): pillars that overlap, a shift that is not a
whole number of lattice cells, a pillar wall too close to the cell's edge. The
gap against the fiber's diameter is checked with the fiber settings
(:func:`fibersweep.sweep.starts.check_starts`).
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from fibersweep.config.errors import FieldError, all_checks
from fibersweep.geometry import PILLAR_SHAPES, check_shape_name
from fibersweep.geometry.array import ArrayError, PillarArray

#: Cells between a sub-grid pillar wall and the edge of a periodic box: the wall's
#: link interpolation (3 upstream nodes) and the IB ghost stencil are built for one
#: pillar image (the flow's lattice reads it from here).
EDGE_CELLS = 4

__all__ = ["ArraySettings", "array_on_lattice", "check_array_flow"]


class ArraySettings(BaseModel):
    """The pillar array (:class:`fibersweep.geometry.array.PillarArray`), lengths in µm."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    pillar_shape: str = Field("triangle", description=f"one of {', '.join(PILLAR_SHAPES)}")
    pillar_size: float = Field(
        40.0, gt=0, description="h_obs [µm]: triangle height, circle diameter, square side"
    )
    pillar_rotation: float = Field(0.0, description="counter-clockwise rotation [deg]")
    pillar_vertices: tuple[tuple[float, float], ...] | None = Field(
        None, description="corners of a 'polygon' in units of pillar_size"
    )
    period_x: float = Field(80.0, gt=0, description="centre-to-centre period along the flow [µm]")
    period_y: float = Field(80.0, gt=0, description="centre-to-centre period across the flow [µm]")
    shift: float = Field(0.1, ge=0, lt=1, description="row shift epsilon (tilt atan epsilon)")
    depth: float = Field(40.0, gt=0, description="channel depth H [µm]")
    mean_flow: Literal["x", "force"] = Field(
        "x",
        description="x: a lateral body force keeps the mean flow along x (as a device's side "
        "walls do); force: body force along x only, the mean flow follows the cell's "
        "permeability",
    )

    def to_array(self) -> PillarArray:
        """The :class:`PillarArray` of these settings."""
        return PillarArray(**self.model_dump(exclude={"mean_flow"}))

    @field_validator("pillar_shape")
    @classmethod
    def _known_shape(cls, name: str) -> str:
        return check_shape_name(name)

    @model_validator(mode="after")
    def _valid(self) -> ArraySettings:
        """Pillars that do not overlap along or across the flow; a valid polygon."""
        try:
            self.to_array()
        except ArrayError as exc:
            raise FieldError(exc.field, str(exc)) from None
        except ValueError as exc:  # the shape's own checks (polygon vertices)
            raise FieldError("pillar_vertices", str(exc)) from None
        return self


def check_array_flow(array: ArraySettings, dx: float, boundary: str, symmetry: bool) -> None:
    """The unit cell's lattice: whole cells, enough depth nodes, the wall clear of the edges.

    Checked when the settings are, before any field is computed
    (:func:`fibersweep.flow.cell.solve_cell` relies on them). A length within
    :data:`~fibersweep.geometry.array.LATTICE_TOLERANCE` (1e-3 µm) of a whole number
    of cells counts as that number (:func:`array_on_lattice` gives the settings
    with it). Every problem is reported, each at its field.

    Raises
    ------
    FieldError or FieldErrors
        At ``array.<field>`` (a length or the shift not whole in cells) or ``dx``.
    """
    arr = array.to_array()
    checks: list = [
        lambda e=e: _raise(FieldError(("array", e.field), str(e))) for e in arr.lattice_problems(dx)
    ]

    def depth_nodes() -> None:
        nz = int(round(arr.depth / dx))
        if nz < 8 or (symmetry and nz % 2):
            raise FieldError(
                "dx",
                f"dx = {dx} µm gives {nz} nodes across the array's depth {arr.depth} µm; at "
                "least 8 (an even number with symmetry: true) are needed",
            )

    def edge_clear() -> None:
        x0, y0, x1, y1 = arr.shape.bounds
        edge = min(x0, y0, arr.period_x - x1, arr.period_y - y1) / dx
        if boundary != "staircase" and edge < EDGE_CELLS:
            raise FieldError(
                "dx",
                f"the pillar is {edge:.1f} cells from the unit cell's edge; the sub-grid wall "
                f"needs {EDGE_CELLS} (refine dx, widen the gaps, or pillar_boundary: staircase)",
            )

    all_checks(*checks, depth_nodes, edge_clear)


def array_on_lattice(array: ArraySettings, dx: float) -> ArraySettings:
    """``array`` with the lengths :func:`check_array_flow` took as whole numbers of cells
    set to them exactly (the same object when all are whole as written), so the flow's
    lattice and the fibers' array are the same and a config gives the same results
    however its values were rounded."""
    update = array.to_array().on_lattice(dx)
    return array.model_copy(update=update) if update else array


def _raise(exc: Exception) -> None:
    raise exc
