"""Validated settings of the flow problem: geometry, fluid and LBM solver."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator, model_validator

from fibersweep.units import Fluid, Geometry

__all__ = ["GeometrySettings", "FluidSettings", "FlowSettings", "MIN_DEPTH_NODES"]

MIN_DEPTH_NODES = 8


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class GeometrySettings(_Strict):
    """Channel and pillar in µm (see :class:`fibersweep.units.Geometry`)."""

    width: float = Field(800.0, gt=0, description="channel width W_ch (y) [µm]")
    depth: float = Field(40.0, gt=0, description="channel depth H_ch (z) [µm]")
    length: float = Field(2400.0, gt=0, description="periodic channel length L_ch (x) [µm]")
    pillar_height: float = Field(75.0, gt=0, description="triangle height h_obs [µm]")
    pillar_x: float | None = Field(None, description="x of the base centre [µm]; default L_ch/2")
    pillar_y_base: float | None = Field(
        None, description="y of the base line [µm]; default W_ch/2 - h_obs/3 (centroid centred)"
    )

    @model_validator(mode="after")
    def _pillar_fits(self) -> GeometrySettings:
        if not self.to_geometry().fits():
            raise ValueError(
                "pillar does not fit in the channel: its vertices "
                f"{self.to_geometry().vertices.round(2).tolist()} must lie inside "
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


class FlowSettings(_Strict):
    """Everything that changes the steady field (all of it enters the cache key)."""

    geometry: GeometrySettings = GeometrySettings()
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

    @field_validator("dx")
    @classmethod
    def _resolution(cls, dx: float, info: ValidationInfo) -> float:
        geom = info.data.get("geometry")
        if geom is None or dx <= 0:  # geometry invalid (reported on its own) or dx <= 0
            return dx
        nz = geom.depth / dx
        if nz < MIN_DEPTH_NODES - 1e-9:
            raise ValueError(
                f"dx = {dx} µm leaves {nz:g} nodes across the depth "
                f"{geom.depth} µm; at least {MIN_DEPTH_NODES} are needed"
            )
        for name in ("width", "depth", "length"):
            n = getattr(geom, name) / dx
            if abs(n - round(n)) > 1e-9:
                raise ValueError(
                    f"geometry.{name} = {getattr(geom, name)} µm is not a whole "
                    f"number of dx = {dx} µm"
                )
        return dx

    @field_validator("symmetry")
    @classmethod
    def _even_depth(cls, symmetry: bool, info: ValidationInfo) -> bool:
        geom, dx = info.data.get("geometry"), info.data.get("dx")
        if symmetry and geom is not None and dx is not None and round(geom.depth / dx) % 2:
            raise ValueError(
                "symmetry: true needs an even number of nodes across the depth "
                f"(depth/dx = {geom.depth / dx:g}); use symmetry: false or another dx"
            )
        return symmetry
