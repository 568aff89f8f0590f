"""Validated settings of the flow problem: geometry, fluid and LBM solver."""

from __future__ import annotations

import math
from typing import Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationInfo,
    field_validator,
    model_serializer,
    model_validator,
)

from fibersweep.config.array import ArraySettings, array_on_lattice, check_array_flow
from fibersweep.config.errors import FieldError, all_checks
from fibersweep.geometry import PILLAR_SHAPES, ConvexPolygon, Geometry, check_shape_name
from fibersweep.geometry.array import LATTICE_TOLERANCE, on_lattice, whole_cells
from fibersweep.units import Fluid

__all__ = [
    "ArraySettings",
    "GeometrySettings",
    "FluidSettings",
    "FlowSettings",
    "PatchSettings",
    "MIN_DEPTH_NODES",
    "FLOAT32_MIN_TOLERANCE",
]

MIN_DEPTH_NODES = 8
#: Flow settings that cannot apply to an array's unit cell, and why.
_NOT_FOR_ARRAYS = {
    "geometry": "the array's unit cell is the flow domain (flow.geometry is the single "
    "pillar's channel)",
    "patch": "a patch nests a finer grid round one pillar in a channel's solution, and the "
    "unit cell is solved whole: refine flow.dx instead",
}
# float32 populations carry rounding noise of about one float32 epsilon (6e-8) of the
# field: the relative change per check levels off there (measured 7e-8 past the pillar,
# docs/precision.md), so a smaller tolerance may never be met
FLOAT32_MIN_TOLERANCE = 1e-7


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class GeometrySettings(_Strict):
    """Channel and pillar in µm (see :class:`fibersweep.units.Geometry`)."""

    width: float = Field(800.0, gt=0, description="channel width W_ch (y) [µm]")
    depth: float = Field(40.0, gt=0, description="channel depth H_ch (z) [µm]")
    length: float = Field(2400.0, gt=0, description="periodic channel length L_ch (x) [µm]")
    pillar_height: float = Field(
        75.0,
        gt=0,
        description=(
            "pillar size h_obs [µm]: triangle height, circle diameter, square side, "
            "unit of polygon vertices"
        ),
    )
    pillar_x: float | None = Field(
        None, description="x of the pillar centroid (triangle: base centre) [µm]; default L_ch/2"
    )
    pillar_y_base: float | None = Field(
        None,
        description=(
            "y of the pillar's lowest point, the base line [µm]; default: centroid on the "
            "centreline (W_ch/2 - h_obs/3 for the triangle)"
        ),
    )
    pillar_shape: str = Field(
        "triangle",
        description=f"pillar outline: {', '.join(PILLAR_SHAPES)} (docs/shapes.md)",
    )
    pillar_rotation: float = Field(
        0.0, description="counter-clockwise rotation of the pillar about its centroid [deg]"
    )
    pillar_vertices: tuple[tuple[float, float], ...] | None = Field(
        None,
        description="corners of a convex 'polygon' pillar, [x, y] in units of h_obs (any origin)",
    )

    @field_validator("pillar_shape")
    @classmethod
    def _known_shape(cls, name: str) -> str:
        return check_shape_name(name)

    @field_validator("pillar_rotation")
    @classmethod
    def _finite_rotation(cls, deg: float) -> float:
        if not math.isfinite(deg):
            raise ValueError("pillar_rotation must be a finite angle in degrees")
        return deg

    @field_validator("pillar_vertices")
    @classmethod
    def _convex(cls, verts: tuple | None) -> tuple | None:
        if verts is not None:
            ConvexPolygon.from_vertices(verts)  # ValueError says what is wrong
        return verts

    @model_validator(mode="after")
    def _pillar_fits(self) -> GeometrySettings:
        """The pillar lies inside the channel."""
        geo = self.to_geometry()
        if not geo.fits():  # building the shape checks that vertices go with 'polygon' only
            x0, y0, x1, y1 = geo.shape.bounds
            raise ValueError(
                f"pillar does not fit in the channel: its {self.pillar_shape} spans "
                f"x in [{x0:.2f}, {x1:.2f}], y in [{y0:.2f}, {y1:.2f}] and must lie inside "
                f"x in (0, {self.length}), y in (0, {self.width})"
            )
        return self

    def to_geometry(self) -> Geometry:
        return Geometry(**self.model_dump())


class FluidSettings(_Strict):
    """Fluid properties (docs/model.md)."""

    viscosity: float = Field(0.340, gt=0, description="dynamic viscosity [Pa s]")
    density: float = Field(1190.0, gt=0, description="density [kg/m^3]")
    u_center: float = Field(600.0, gt=0, description="midplane centreline speed far away [µm/s]")

    def to_fluid(self) -> Fluid:
        return Fluid(**self.model_dump())


class PatchSettings(_Strict):
    """A finer grid around the pillar nested in the channel's solution (docs/fidelity.md)."""

    dx: float = Field(gt=0, description="lattice spacing of the patch [µm]; dx / patch.dx whole")
    margin: float = Field(
        160.0,
        gt=0,
        description=(
            "distance from the pillar's bounding box to the patch edge [µm], rounded up to "
            "whole channel cells (default from the patch-size study in docs/fidelity.md)"
        ),
    )


class FlowSettings(_Strict):
    """Everything that changes the steady field (all of it enters the cache key)."""

    geometry: GeometrySettings = GeometrySettings()
    array: ArraySettings | None = Field(
        None,
        description=(
            "a tilted pillar array (docs/arrays.md): the flow is then its unit cell with "
            "shifted periodic boundaries, and geometry and patch are not used; None: the "
            "single pillar in a channel"
        ),
    )
    fluid: FluidSettings = FluidSettings()
    dx: float = Field(4.0, gt=0, description="lattice spacing [µm]")
    collision: Literal["trt", "bgk"] = Field("trt", description="collision operator")
    magic: float = Field(3.0 / 16.0, gt=0, description="TRT magic parameter Lambda")
    tau: float | None = Field(
        None, gt=0.5, description="relaxation time; None lets the solver choose a fast one"
    )
    tolerance: float = Field(1e-6, gt=0, lt=1, description="relative change per check to stop")
    check_every: int = Field(100, ge=1, description="steps between convergence checks")
    max_steps: int = Field(200_000, ge=1, description="hard limit on LBM steps")
    pillar_boundary: Literal["staircase", "interpolated", "bfl"] = Field(
        "interpolated",
        description=(
            "pillar wall: interpolated bounce-back at the exact sub-grid wall (default; "
            "second order, 2.5x less sensitive to where the pillar sits on the grid: "
            "docs/fidelity.md), the staircase of lattice cells bounced back half-way "
            "(first order, kept for comparison), or plain linear "
            "Bouzidi-Firdaouss-Lallemand ('bfl')"
        ),
    )
    symmetry: bool = Field(True, description="solve half the depth with a free-slip midplane")
    keep_3d: bool = Field(False, description="keep the full 3D field in the cache")
    precision: Literal["float32", "float64"] = Field(
        "float32",
        description=(
            "storage and collision precision of the populations: float32 (default, "
            "stored as the deviation f - w from rest, 76 B per cell) or float64 (the "
            "reference, twice the memory and memory traffic: docs/precision.md)"
        ),
    )
    patch: PatchSettings | None = Field(
        None,
        description=(
            "a finer grid around the pillar, nested in this channel solution; the field is "
            "then stored at patch.dx (docs/fidelity.md, 'Fine patch'); None: one grid"
        ),
    )

    @field_validator("dx")
    @classmethod
    def _resolution(cls, dx: float, info: ValidationInfo) -> float:
        geom = info.data.get("geometry")
        if info.data.get("array") is not None:
            return dx  # the unit cell's lattice is checked with the array (_array_cell)
        if geom is None or dx <= 0:  # geometry invalid (reported on its own) or dx <= 0
            return dx
        nz = geom.depth / dx
        if nz < MIN_DEPTH_NODES - 1e-9:
            raise ValueError(
                f"dx = {dx} µm leaves {nz:g} nodes across the depth "
                f"{geom.depth} µm; at least {MIN_DEPTH_NODES} are needed"
            )
        for name in ("width", "depth", "length"):
            if whole_cells(getattr(geom, name), dx) is None:
                raise ValueError(
                    f"geometry.{name} = {getattr(geom, name)} µm is not a whole "
                    f"number of dx = {dx} µm (within {LATTICE_TOLERANCE:g} µm)"
                )
        return dx

    @field_validator("symmetry")
    @classmethod
    def _even_depth(cls, symmetry: bool, info: ValidationInfo) -> bool:
        geom, dx = info.data.get("geometry"), info.data.get("dx")
        if info.data.get("array") is not None:
            return symmetry  # checked with the array (_array_cell)
        if symmetry and geom is not None and dx is not None and round(geom.depth / dx) % 2:
            raise ValueError(
                "symmetry: true needs an even number of nodes across the depth "
                f"(depth/dx = {geom.depth / dx:g}); use symmetry: false or another dx"
            )
        return symmetry

    @property
    def field_dx(self) -> float:
        """Spacing of the stored midplane field [µm]: ``patch.dx`` with a patch, else ``dx``."""
        return self.dx if self.patch is None else self.patch.dx

    @model_serializer(mode="wrap")
    def _without_array(self, handler: Any) -> dict[str, Any]:
        """``array`` is written only when set: a channel's dump, key and manifest stay as before."""
        data = handler(self)
        if isinstance(data, dict) and data.get("array") is None:
            data.pop("array", None)
        return data

    @model_validator(mode="after")
    def _checks(self) -> FlowSettings:
        """The array's cell, the patch's grid and the tolerance, all checked (each failure
        at its field); then the lengths taken as whole numbers of cells are set to them
        (:meth:`_on_lattice`)."""
        all_checks(self._array_cell, self._patch_grid, self._reachable_tolerance)
        self._on_lattice()
        return self

    def _on_lattice(self) -> None:
        """Lengths accepted within :data:`~fibersweep.geometry.array.LATTICE_TOLERANCE` of
        a whole number of cells become that number exactly (a value whole as written keeps
        its bits), so the solver's lattice, the fibers' geometry, the cache key and the
        run ids all use one value. Set during validation (the model is frozen after)."""
        if self.array is not None:
            snapped = array_on_lattice(self.array, self.dx)
            if snapped is not self.array:
                object.__setattr__(self, "array", snapped)
            return
        geo = self.geometry
        update = {n: on_lattice(getattr(geo, n), self.dx) for n in ("width", "depth", "length")}
        update = {n: v for n, v in update.items() if v != getattr(geo, n)}
        if update:
            object.__setattr__(self, "geometry", geo.model_copy(update=update))
        if self.patch is not None:
            k = round(self.dx / self.patch.dx)
            if abs(self.dx / self.patch.dx - k) > 1e-9:
                patch = self.patch.model_copy(update={"dx": self.dx / k})
                object.__setattr__(self, "patch", patch)

    def _array_cell(self) -> None:
        """With ``array``: the settings that cannot apply to a unit cell are refused away
        from their defaults, with the reason, and the lattice must fit the cell
        (:func:`check_array_flow`)."""
        if self.array is None:
            return
        for name, why in _NOT_FOR_ARRAYS.items():
            if getattr(self, name) != type(self).model_fields[name].default:
                raise FieldError(name, f"not used with flow.array: {why}; leave flow.{name} out")
        check_array_flow(self.array, self.dx, self.pillar_boundary, self.symmetry)

    def _patch_grid(self) -> None:
        """A patch divides dx a whole number of times (2 or more) and the depth into whole
        (even with symmetry) nodes, within 1e-3 µm; no keep_3d with a patch."""
        if self.patch is None:
            return
        if self.keep_3d:
            raise ValueError("keep_3d: true is not available with a patch (patch: null)")
        k = whole_cells(self.dx, self.patch.dx)
        if k is None or k < 2:
            raise ValueError(
                f"patch.dx = {self.patch.dx} µm must divide dx = {self.dx} µm a whole number "
                f"of times (2 or more, within {LATTICE_TOLERANCE:g} µm)"
            )
        n = whole_cells(self.geometry.depth, self.dx / k)
        if n is None or (self.symmetry and n % 2):
            raise ValueError(
                f"patch.dx = {self.patch.dx} µm must give a whole (even with symmetry) "
                f"number of nodes across the depth {self.geometry.depth} µm"
            )

    def _reachable_tolerance(self) -> None:
        """float32 populations cannot resolve a tolerance below 1e-7."""
        if self.precision == "float32" and self.tolerance < FLOAT32_MIN_TOLERANCE:
            raise ValueError(
                f"tolerance = {self.tolerance:g} is below what float32 populations can "
                f"resolve (the relative change per check levels off near 7e-8); use a "
                f"tolerance >= {FLOAT32_MIN_TOLERANCE:g} or precision: float64"
            )
