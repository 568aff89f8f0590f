"""Time steppers: the two-array pull kernel and the in-place AA kernel behind one interface."""

from __future__ import annotations

import numpy as np

from fibersweep.flow import kernels, kernels_aa
from fibersweep.flow.cuts import Cuts
from fibersweep.flow.ibb import LinkTable, aa_interpolated, pull_interpolated
from fibersweep.flow.lattice import (
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


class PullStepper:
    """Fused pull-stream-collide between two arrays (228 B per cell update).

    ``cuts`` None: the pillar is a staircase of cells bounced back half-way;
    otherwise interpolated bounce-back at the wall fractions ``cuts``.
    ``dtype``: storage (and collision) precision of the populations, float32 or float64.
    """

    step_multiple = 1

    def __init__(
        self, grid: Grid, u0, rho0, grad, fx: float, omega_p: float, omega_m: float,
        cuts: Cuts | None = None, dtype: np.dtype | type = np.float32,
    ):  # fmt: skip
        self.fx, self.omega_p, self.omega_m = fx, omega_p, omega_m
        self.links, self.solid_cells = boundary_links(grid)
        self.sources = pull_sources(grid)
        self.table = (
            None if cuts is None else pull_interpolated(grid, cuts, self.sources, omega_p, omega_m)
        )
        self.buf = np.zeros(0 if cuts is None else self.table.dst.size)
        self.e = tuple(np.ascontiguousarray(E[:, k]) for k in range(3))
        self.g = np.zeros(grid.padded_shape, dtype=_storage(dtype))
        self.gn = np.zeros_like(self.g)
        kernels.init_populations(self.g, u0, rho0, grad, omega_p, True, W, *self.e)
        kernels.fill_periodic(self.g)
        self._fill(self.g)

    def _fill(self, g: np.ndarray) -> None:
        if self.table is None:
            kernels.fill_pillar(g, self.solid_cells, self.links)
        else:
            _apply(g, self.table, self.buf, self.solid_cells)

    def advance(self, n: int) -> None:
        """n steps."""
        for _ in range(n):
            kernels.stream_collide(
                self.g, self.gn, self.sources, self.fx, self.omega_p, self.omega_m
            )
            self._fill(self.gn)
            self.g, self.gn = self.gn, self.g

    def moments(self, out: np.ndarray) -> None:
        """(δρ, ux, uy, uz) of the state the next step collides, shape (4, nz, ny, nx)."""
        kernels.moments(self.g, self.sources, self.fx, *self.e, out)


class AAStepper:
    """In-place AA pattern on one array (152 B per cell update); steps come in pairs.

    ``cuts`` and ``dtype`` as for :class:`PullStepper`.
    """

    step_multiple = 2

    def __init__(
        self, grid: Grid, u0, rho0, grad, fx: float, omega_p: float, omega_m: float,
        cuts: Cuts | None = None, dtype: np.dtype | type = np.float32,
    ):  # fmt: skip
        self.fx, self.omega_p, self.omega_m = fx, omega_p, omega_m
        self.gather, self.scatter = aa_tables(grid)
        self.before, self.after, self.solid_cells = aa_links(grid, self.gather, self.scatter)
        self.tables = None
        if cuts is not None:
            self.tables = aa_interpolated(grid, cuts, self.gather, self.scatter, omega_p, omega_m)
            self.buf = np.zeros(self.tables[0].dst.size)
        self.no_cells = np.zeros(0, dtype=np.int64)
        self.opp = np.ascontiguousarray(OPP)
        self.e = tuple(np.ascontiguousarray(E[:, k]) for k in range(3))
        # after an odd step (and initially) slot q of a node holds the population
        # arriving there: the moments are local, read through an identity table
        ident = np.zeros((grid.nz * grid.ny, Q, 4), dtype=np.int64)
        k, j = np.divmod(np.arange(grid.nz * grid.ny), grid.ny)
        ident[:, :, 0] = np.arange(Q)[None, :]
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
            kernels_aa.aa_even(self.g, self.opp, self.fx, self.omega_p, self.omega_m)
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
        kernels.moments(self.g, self.local, self.fx, *self.e, out)


STEPPERS = {"pull": PullStepper, "aa": AAStepper}


def make_stepper(
    name: str, *args, cuts: Cuts | None = None, dtype: np.dtype | type = np.float32
) -> PullStepper | AAStepper:
    """The stepper called ``name`` ("aa" or "pull"); unknown names fail listing the valid ones.

    ``cuts``: wall fractions for interpolated bounce-back (None: staircase pillar).
    ``dtype``: population precision, float32 (default) or float64.
    """
    try:
        cls = STEPPERS[name]
    except KeyError:
        raise ValueError(f"unknown LBM kernel {name!r}; valid: {sorted(STEPPERS)}") from None
    return cls(*args, cuts=cuts, dtype=dtype)
