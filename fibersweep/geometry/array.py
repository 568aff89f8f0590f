"""A tilted pillar array: the single-pillar cell repeated on a shifted lattice.

One model for both geometries
-----------------------------
A pillar geometry is a *set of pillars*: one outline (any registered shape,
:mod:`fibersweep.geometry.pillars`) and the translations at which it stands.

- The single pillar in a channel (:class:`fibersweep.geometry.channel.Geometry`) is the set
  with one member, bounded by side walls at y = 0 and y = W_ch.
- An array is the same outline at every lattice point
  ``(r λx, r ε λy + c λy)`` for rows r and columns c (integers): each row is
  shifted across the flow by ε times the lateral period, so the array is tilted
  by atan ε to the flow.

The unit cell of the array *is* a single-pillar :class:`~fibersweep.geometry.channel.Geometry`
(``length = λx``, ``width = λy``, pillar centred in the cell); the array adds
its periodic images. Everything that solves or reads a cell (the flow solver,
the contact kernel, plots) therefore uses the same shape objects, caches and
kernels as the single pillar; :meth:`PillarArray.images` gives the members of
the set near a point.

Lengths in µm. Row r holds the pillar whose centroid is at
``x = (r + ½) λx``, ``y = (r ε + c + ½) λy``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from fibersweep.geometry.channel import Geometry
from fibersweep.geometry.pillars import unit_width

__all__ = ["LATTICE_TOLERANCE", "PillarArray", "ArrayError", "on_lattice", "whole_cells"]

#: A length within this of a whole number of lattice cells counts as that whole number
#: [µm] (e.g. ε λy = 0.0909 × 44 µm = 3.9996 µm is 4 µm, one cell of dx = 4 µm): values
#: written with a few digits (1/11 as 0.0909) are accepted, and replaced by the whole
#: number (:func:`on_lattice`) so the flow and the fibers use the same, reproducible
#: lattice. 1e-3 µm is far below any resolved length (a cell is 0.25 µm or more).
LATTICE_TOLERANCE = 1e-3


def whole_cells(length: float, dx: float) -> int | None:
    """``length / dx`` rounded when ``length`` is within :data:`LATTICE_TOLERANCE` of that
    many cells [µm], else None."""
    n = round(length / dx)
    return int(n) if abs(length - n * dx) <= LATTICE_TOLERANCE else None


def on_lattice(length: float, dx: float, exact: float = 1e-9) -> float:
    """``length`` [µm] as the whole number of cells of ``dx`` it is taken as.

    Within ``exact`` cells of it (a whole number up to float rounding) the value is
    kept as written, so a config that was already whole keeps its bits (the same
    cache key and run ids); farther (but within :data:`LATTICE_TOLERANCE`): that
    number of cells times ``dx``. Call it on a length :func:`whole_cells` accepted.
    """
    n = round(length / dx)
    return length if abs(length / dx - n) <= exact else float(n * dx)


class ArrayError(ValueError):
    """A bad array setting; ``field`` names the setting (for the config error)."""

    def __init__(self, field: str, message: str):
        super().__init__(message)
        self.field = field


@dataclass(frozen=True)
class PillarArray:
    """A tilted periodic lattice of identical full-depth pillars.

    Parameters
    ----------
    pillar_shape : str
        A registered shape (triangle, circle, square, polygon).
    pillar_size : float
        h_obs of the shape [µm] (triangle height, circle diameter, square side).
    period_x, period_y : float
        Centre-to-centre period along (λx) and across (λy) the flow [µm].
    shift : float
        Row shift ε: row r + 1 stands ε λy higher than row r (tilt atan ε).
    depth : float
        Channel depth H [µm].
    pillar_rotation : float
        Counter-clockwise rotation of the pillar about its centroid [deg].
    pillar_vertices : tuple of (x, y) or None
        Corners of a ``polygon`` pillar in units of ``pillar_size``.
    """

    pillar_shape: str = "triangle"
    pillar_size: float = 40.0
    period_x: float = 80.0
    period_y: float = 80.0
    shift: float = 0.1
    depth: float = 40.0
    pillar_rotation: float = 0.0
    pillar_vertices: tuple[tuple[float, float], ...] | None = None

    def __post_init__(self) -> None:
        for name in ("pillar_size", "period_x", "period_y", "depth"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ArrayError(name, f"{name} must be a positive length in µm, got {v!r}")
        if not (math.isfinite(self.shift) and 0.0 <= self.shift < 1.0):
            raise ArrayError(
                "shift",
                f"shift = {self.shift!r}: the row shift ε must lie in [0, 1) (a shift of a "
                "whole period or more is the same array as its fractional part)",
            )
        x0, y0, x1, y1 = self.cell_geometry.shape.bounds
        if x1 - x0 >= self.period_x:
            raise ArrayError(
                "period_x",
                f"pillars overlap along the flow: the {self.pillar_shape} is "
                f"{x1 - x0:.3g} µm long and period_x = {self.period_x:g} µm",
            )
        if y1 - y0 >= self.period_y:
            raise ArrayError(
                "period_y",
                f"pillars overlap across the flow: the {self.pillar_shape} is "
                f"{y1 - y0:.3g} µm wide and period_y = {self.period_y:g} µm",
            )

    # ------------------------------------------------------------ the cell
    @cached_property
    def cell_geometry(self) -> Geometry:
        """The unit cell as a single-pillar Geometry: λx × λy, the pillar's bounding box centred.

        Centring the box (not the centroid) leaves the widest margin between the
        pillar and the cell's edges on every side.
        """
        probe = Geometry(
            width=self.period_y, depth=self.depth, length=self.period_x,
            pillar_height=self.pillar_size, pillar_x=0.0, pillar_y_base=0.0,
            pillar_shape=self.pillar_shape, pillar_rotation=self.pillar_rotation,
            pillar_vertices=self.pillar_vertices,
        )  # fmt: skip
        x0, y0, x1, y1 = probe.shape.bounds  # centroid at x = 0, lowest point at y = 0
        return Geometry(
            width=self.period_y,
            depth=self.depth,
            length=self.period_x,
            pillar_height=self.pillar_size,
            pillar_x=0.5 * self.period_x - 0.5 * (x0 + x1),
            pillar_y_base=0.5 * (self.period_y - (y1 - y0)),
            pillar_shape=self.pillar_shape,
            pillar_rotation=self.pillar_rotation,
            pillar_vertices=self.pillar_vertices,
        )

    @property
    def shape(self):
        """The pillar of row 0, column 0 [µm] (in the cell)."""
        return self.cell_geometry.shape

    @property
    def gap(self) -> float:
        """Lateral gap G between neighbouring pillars of a row [µm]: λy minus the pillar's width."""
        _, y0, _, y1 = self.shape.bounds
        return self.period_y - (y1 - y0)

    @property
    def row_gap(self) -> float:
        """Gap along the flow between consecutive rows [µm] (λx minus the pillar's length)."""
        x0, _, x1, _ = self.shape.bounds
        return self.period_x - (x1 - x0)

    @property
    def lateral_shift(self) -> float:
        """ε λy [µm]: how far each row stands above the previous one."""
        return self.shift * self.period_y

    @property
    def tilt_deg(self) -> float:
        """Array tilt atan ε [deg] (the migration angle of the displacement mode)."""
        return math.degrees(math.atan2(self.lateral_shift, self.period_x))

    @property
    def unit_length(self) -> float:
        """l_obs of the pillar [µm] (the width in x of the unrotated shape)."""
        return unit_width(self.pillar_shape, self.pillar_size, self.pillar_vertices)

    # ------------------------------------------------------------ checks
    def check_fiber(self, bead_radius: float) -> None:
        """ArrayError naming ``period_y`` if a fiber of this bead radius cannot pass a gap."""
        if self.gap <= 2.0 * bead_radius:
            raise ArrayError(
                "period_y",
                f"the gap between pillars, {self.gap:.3g} µm, is not wider than the fiber's "
                f"diameter 2a = {2.0 * bead_radius:g} µm: widen period_y or shrink pillar_size",
            )

    def lattice_problems(self, dx: float) -> list[ArrayError]:
        """What keeps the array off a lattice of spacing ``dx``: each period, the depth
        and the row shift ε λy must be whole numbers of cells (within
        :data:`LATTICE_TOLERANCE`); one :class:`ArrayError` per setting at fault."""
        out = []
        for name in ("period_x", "period_y", "depth"):
            if whole_cells(getattr(self, name), dx) is None:
                out.append(ArrayError(name, f"{name} = {getattr(self, name)} µm is not a whole "
                                      f"number of dx = {dx} µm (within {LATTICE_TOLERANCE:g} "
                                      "µm)"))  # fmt: skip
        if whole_cells(self.lateral_shift, dx) is None:
            k = max(round(self.lateral_shift / dx), 1)
            out.append(
                ArrayError(
                    "shift",
                    f"the row shift ε λy = {self.shift:g} × {self.period_y:g} µm = "
                    f"{self.lateral_shift:.6g} µm is not a whole number of lattice cells "
                    f"(dx = {dx:g} µm, within {LATTICE_TOLERANCE:g} µm): the unit cell's "
                    f"shifted periodic boundary needs a whole number; choose ε λy = k dx, "
                    f"e.g. shift = {k * dx / self.period_y:.6g}",
                )
            )
        return out

    def check_lattice(self, dx: float) -> int:
        """Row shift in lattice cells; ArrayError naming ``shift`` unless it is whole.

        The shifted periodic boundary copies whole lattice columns, so ε λy must
        be a whole number of cells Δx (no interpolation across the boundary); so
        must the periods and the depth. A length within :data:`LATTICE_TOLERANCE`
        (1e-3 µm) of a whole number of cells counts as that number
        (:meth:`on_lattice` gives the array with the whole numbers).
        """
        problems = self.lattice_problems(dx)
        if problems:
            raise problems[0]
        return int(round(self.lateral_shift / dx))

    def on_lattice(self, dx: float) -> dict[str, float]:
        """The settings that :meth:`check_lattice` took as whole numbers of cells and
        that are not written so, with their whole values: periods and depth ``n dx``,
        the shift ``k dx / λy`` ({} when every one is whole as written, up to float
        rounding). Call it on an array that passed :meth:`check_lattice`."""
        out: dict[str, float] = {}
        for name in ("period_x", "period_y", "depth"):
            v = on_lattice(getattr(self, name), dx)
            if v != getattr(self, name):
                out[name] = v
        period_y = out.get("period_y", self.period_y)
        k = round(self.lateral_shift / dx)
        # the shift was accepted within 1e-6 cells before the tolerance: kept as written
        if abs(self.lateral_shift / dx - k) > 1e-6 or "period_y" in out:
            shift = k * dx / period_y
            if shift != self.shift:
                out["shift"] = shift
        return out

    # ------------------------------------------------------------ lattice
    def centre(self, row: int, col: int) -> tuple[float, float]:
        """Centroid of pillar (row, col) [µm]."""
        cx, cy = self.shape.centroid
        return (cx + row * self.period_x, cy + (row * self.shift + col) * self.period_y)

    def offset(self, row: int, col: int) -> tuple[float, float]:
        """Translation from pillar (0, 0) to pillar (row, col) [µm]."""
        return (row * self.period_x, (row * self.shift + col) * self.period_y)

    def row_of(self, x: np.ndarray | float) -> np.ndarray | int:
        """Row whose cell holds x [µm]: floor(x / λx)."""
        return np.floor(np.asarray(x) / self.period_x).astype(np.int64)

    def column_of(self, x, y) -> np.ndarray | int:
        """Column of the cell holding (x, y) [µm] within its row."""
        r = self.row_of(x)
        return np.floor((np.asarray(y) - r * self.lateral_shift) / self.period_y).astype(np.int64)

    def to_cell(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """Position (x, y) [µm] folded into the unit cell [0, λx) × [0, λy)."""
        r = self.row_of(x)
        xl = np.asarray(x) - r * self.period_x
        yl = np.mod(np.asarray(y) - r * self.lateral_shift, self.period_y)
        return xl, yl

    def images(self, x0: float, y0: float, x1: float, y1: float, reach: float) -> list:
        """Pillars (row, col, shape) whose outline may come within ``reach`` of a box [µm]."""
        bx0, by0, bx1, by1 = self.shape.bounds
        out = []
        r0 = math.floor((x0 - reach - bx1) / self.period_x)
        r1 = math.floor((x1 + reach - bx0) / self.period_x)
        for r in range(r0, r1 + 1):
            dy = r * self.lateral_shift
            c0 = math.floor((y0 - reach - by1 - dy) / self.period_y)
            c1 = math.floor((y1 + reach - by0 - dy) / self.period_y)
            for c in range(c0, c1 + 1):
                ox, oy = self.offset(r, c)
                out.append((r, c, self.shape.moved(ox, oy)))
        return out

    def block_shapes(self, rows: int) -> list:
        """Pillars of a block of ``rows`` rows, one column wide, folded into y ∈ [0, λy) [µm].

        The shapes of the explicit block used to check the unit cell (a pillar
        that straddles y = 0 or λy appears with both of its images).
        """
        out = []
        for r in range(rows):
            oy = math.fmod(r * self.lateral_shift, self.period_y)
            for c in (-1, 0, 1):
                s = self.shape.moved(r * self.period_x, oy + c * self.period_y)
                b = s.bounds
                if b[3] > 0.0 and b[1] < self.period_y:
                    out.append(s)
        return out

    def describe(self) -> dict:
        """Derived quantities a report prints [µm, deg]."""
        return {
            "gap": self.gap,
            "row_gap": self.row_gap,
            "lateral_shift": self.lateral_shift,
            "tilt_deg": self.tilt_deg,
            "rows_per_period": (1.0 / self.shift) if self.shift > 0 else math.inf,
        }
