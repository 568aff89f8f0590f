"""Time steppers: the two-array pull kernel and the in-place AA kernel behind one interface.

Both step any :class:`~fibersweep.flow.lattice.Grid`: the channel (walls in y,
periodic x) or the unit cell of a pillar array (periodic y, shifted periodic
x), with the body force along x or, through the turned frame of the kernels
(:data:`fibersweep.flow.lattice.FRAMES`), along y.
"""

from __future__ import annotations

import numpy as np

from fibersweep.flow import kernels, kernels_aa
from fibersweep.flow.cuts import Cuts
from fibersweep.flow.ibb import LinkTable, aa_interpolated, pull_interpolated
from fibersweep.flow.lattice import (
    FRAMES,
    OPP,
    E,
    Grid,
    Q,
    W,
    aa_links,
    aa_tables,
    boundary_links,
    pull_sources,
)

__all__ = ["STEPPERS", "PRECISIONS", "PullStepper", "AAStepper", "make_stepper"]


PRECISIONS = ("float32", "float64")


def _storage(dtype: np.dtype | type) -> np.dtype:
    """``dtype`` checked to be one of ``PRECISIONS``."""
    dt = np.dtype(dtype)
    if dt.name not in PRECISIONS:
        raise ValueError(f"unknown population precision {dt.name!r}; valid: {list(PRECISIONS)}")
    return dt


def _apply(g: np.ndarray, table: LinkTable, buf: np.ndarray, reset: np.ndarray) -> None:
    kernels.apply_interpolated(g, table.dst, table.src, table.coef, buf, reset)


class _Stepper:
    """What both steppers share: the force's frame and the moments in the box's frame.

    ``axis``: direction of the body force ``fx``, 0 (x) or 1 (y).
    """

    step_multiple = 1

    def _frame(self, axis: int) -> np.ndarray:
        if axis not in (0, 1):
            raise ValueError(f"the body force acts along x (0) or y (1), got axis {axis!r}")
        self.axis = axis
        self.e = tuple(np.ascontiguousarray(E[:, k]) for k in range(3))
        return FRAMES[axis]

    def _moments(self, table: np.ndarray, out: np.ndarray) -> None:
        """(δρ, ux, uy, uz) through ``table`` (rows in the kernels' frame), in the box's frame."""
        kernels.moments(self.g, table, self.fx, *self.e, out)
        if self.axis:  # the kernels' (x, y) is the box's (y, −x)
            ux = out[2].copy()
            out[2] = out[1]
            out[1] = -ux


class PullStepper(_Stepper):
    """Fused pull-stream-collide between two arrays (228 B per cell update).

    ``cuts`` None: the pillar is a staircase of cells bounced back half-way;
    otherwise interpolated bounce-back at the wall fractions ``cuts``.
    ``dtype``: storage (and collision) precision of the populations, float32 or float64.
    With shifted x faces the ghost columns are filled after the pillar, so the
    pillar must stay clear of the x faces (a unit cell's pillar does: it is
    centred, and a sub-grid wall keeps :data:`~fibersweep.flow.lattice.EDGE_CELLS`).
    """

    def __init__(
        self, grid: Grid, u0, rho0, grad, fx: float, omega_p: float, omega_m: float,
        cuts: Cuts | None = None, dtype: np.dtype | type = np.float32, axis: int = 0,
    ):  # fmt: skip
        self.fx, self.omega_p, self.omega_m, self.shift = fx, omega_p, omega_m, grid.shift
        if grid.shift and (grid.solid[0].any() or grid.solid[-1].any()):
            raise ValueError("the pull stepper needs the pillar clear of shifted x faces")
        frame = self._frame(axis)
        self.links, self.solid_cells = boundary_links(grid)
        self.sources = pull_sources(grid)
        self.table = (
            None if cuts is None else pull_interpolated(grid, cuts, self.sources, omega_p, omega_m)
        )
        self.pull = np.ascontiguousarray(self.sources[:, frame])  # rows in the kernels' frame
        self.slots = frame
        self.buf = np.zeros(0 if cuts is None else self.table.dst.size)
        self.g = np.zeros(grid.padded_shape, dtype=_storage(dtype))
        self.gn = np.zeros_like(self.g)
        kernels.init_populations(self.g, u0, rho0, grad, omega_p, True, W, *self.e)
        kernels.fill_periodic(self.g, self.shift)
        self._fill(self.g)

    def _fill(self, g: np.ndarray) -> None:
        if self.table is None:
            kernels.fill_pillar(g, self.solid_cells, self.links)
        else:
            _apply(g, self.table, self.buf, self.solid_cells)
        if self.shift:  # the kernel copied each row's own ends: take the shifted rows'
            kernels.fill_periodic(g, self.shift)

    def advance(self, n: int) -> None:
        """n steps."""
        for _ in range(n):
            kernels.stream_collide(
                self.g, self.gn, self.pull, self.slots, self.fx, self.omega_p, self.omega_m
            )
            self._fill(self.gn)
            self.g, self.gn = self.gn, self.g

    def moments(self, out: np.ndarray) -> None:
        """(δρ, ux, uy, uz) of the state the next step collides, shape (4, nz, ny, nx)."""
        self._moments(self.pull, out)


class AAStepper(_Stepper):
    """In-place AA pattern on one array (152 B per cell update); steps come in pairs.

    ``cuts``, ``dtype`` and ``axis`` as for :class:`PullStepper`.
    """

    step_multiple = 2

    def __init__(
        self, grid: Grid, u0, rho0, grad, fx: float, omega_p: float, omega_m: float,
        cuts: Cuts | None = None, dtype: np.dtype | type = np.float32, axis: int = 0,
    ):  # fmt: skip
        self.fx, self.omega_p, self.omega_m = fx, omega_p, omega_m
        frame = self._frame(axis)
        gather, scatter = aa_tables(grid)
        self.before, self.after, self.solid_cells = aa_links(grid, gather, scatter)
        self.tables = None
        if cuts is not None:
            self.tables = aa_interpolated(grid, cuts, gather, scatter, omega_p, omega_m)
            self.buf = np.zeros(self.tables[0].dst.size)
        # the kernels collide population q of their frame: slot frame[q] of the box
        self.gather = np.ascontiguousarray(gather[:, frame])
        self.scatter = np.ascontiguousarray(scatter[:, frame])
        self.reads, self.writes = frame, np.ascontiguousarray(OPP[frame])
        self.no_cells = np.zeros(0, dtype=np.int64)
        # after an odd step (and initially) slot q of a node holds the population
        # arriving there: the moments are local, read through an identity table
        ident = np.zeros((grid.nz * grid.ny, Q, 4), dtype=np.int64)
        k, j = np.divmod(np.arange(grid.nz * grid.ny), grid.ny)
        ident[:, :, 0] = frame[None, :]
        ident[:, :, 1] = (k + 1)[:, None]
        ident[:, :, 2] = (j + 1)[:, None]
        ident[:, :, 3] = 1
        self.local = ident
        self.g = np.zeros(grid.padded_shape, dtype=_storage(dtype))
        kernels.init_populations(self.g, u0, rho0, grad, omega_p, False, W, *self.e)

    def advance(self, n: int) -> None:
        """n steps (n even)."""
        if n % 2:
            raise ValueError(f"the AA stepper advances in pairs of steps, got {n}")
        for _ in range(n // 2):
            kernels_aa.aa_even(self.g, self.reads, self.writes, self.fx, self.omega_p, self.omega_m)
            if self.tables is None:
                kernels_aa.apply_links(self.g, self.before, self.no_cells)
            else:
                _apply(self.g, self.tables[0], self.buf, self.no_cells)
            kernels_aa.aa_odd(
                self.g, self.gather, self.scatter, self.fx, self.omega_p, self.omega_m
            )
            if self.tables is None:
                kernels_aa.apply_links(self.g, self.after, self.solid_cells)
            else:
                _apply(self.g, self.tables[1], self.buf, self.solid_cells)

    def moments(self, out: np.ndarray) -> None:
        """(δρ, ux, uy, uz) of the state the next (even) step collides."""
        self._moments(self.local, out)


STEPPERS = {"pull": PullStepper, "aa": AAStepper}


def make_stepper(
    name: str, *args, cuts: Cuts | None = None, dtype: np.dtype | type = np.float32,
    axis: int = 0,
) -> PullStepper | AAStepper:  # fmt: skip
    """The stepper called ``name`` ("aa" or "pull"); unknown names fail listing the valid ones.

    ``args``: (grid, u0, rho0, grad, fx, omega_p, omega_m).
    ``cuts``: wall fractions for interpolated bounce-back (None: staircase pillar).
    ``dtype``: population precision, float32 (default) or float64.
    ``axis``: direction of the body force, 0 (x, default) or 1 (y).
    """
    try:
        cls = STEPPERS[name]
    except KeyError:
        raise ValueError(f"unknown LBM kernel {name!r}; valid: {sorted(STEPPERS)}") from None
    return cls(*args, cuts=cuts, dtype=dtype, axis=axis)
