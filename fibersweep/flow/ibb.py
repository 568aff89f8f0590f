"""Interpolated bounce-back at sub-grid walls, as small per-link tables.

For a fluid node x whose link along e_p meets the wall at the fraction q of
the link (:mod:`fibersweep.flow.cuts`), the population that comes back,
f_p̄(x, t + 1) with p̄ = opp(p), is a linear combination of post-collision
values along the link. Two schemes:

- "bfl" (Bouzidi, Firdaouss & Lallemand 2001):
  q < 1/2: 2q f*_p(x) + (1 − 2q) f*_p(x − e_p); q ≥ 1/2: f*_p(x)/2q + (1 − 1/2q) f*_p̄(x).
- "trt" (default): a member of the same linear family chosen with the TRT
  steady-state analysis (exact steady solutions of TRT for parabolic
  profiles, Ginzburg & d'Humières) so that plane Poiseuille flow is exact
  at every q and every viscosity: for q ≥ 1/2 the exact linear member (weights
  in [0, 1]); for q < 1/2 Ginzburg's central linear interpolation (CLI) plus a
  curvature correction built from the second difference of f*_p − f*_p̄ at x,
  x − e_p, x − 2e_p (:func:`parabolic_correction`); exact linear members
  there need weights of 5 or more and were unstable.

BFL leaves a Poiseuille wall error (1/2 − q)((1/2 + q)/2 + Λ+) ∂²e⁻ (q < 1/2),
(q − 1/2)((q + 1/2)/2 − Λ+) ∂²e⁻ (q ≥ 1/2), which depends on the viscosity
and the wall position; the validation tests show the difference.

At q = 1/2 both reduce to half-way bounce-back. f*_p(x − e_p) is read where
the lattice kernel itself finds the population p arriving at x (a plain
neighbour, the half-way bounce-back of a channel wall, or the mirror image
across the free-slip midplane), so the scheme composes with the other
boundaries. The curvature correction is used only on in-plane links (e_z = 0)
and where x − e_p, x − 2e_p, x − 3e_p are all fluid nodes (else plain CLI), so
that the half-depth solve with its free-slip top equals the full-depth one. If x − e_p were solid
(not possible for one convex pillar, but checked) the link falls back to
half-way bounce-back.

Each link is a row (dst, src[6], coef[6]): ``flat[dst] = Σ coef · flat[src]``,
flat indices into the whole population array (slot × plane + cell); the rows
are applied by :func:`fibersweep.flow.kernels.apply_interpolated`. For the AA
pattern (:mod:`fibersweep.flow.kernels_aa`) the same links give two tables:

- ``before`` (after the even step, which leaves f*_r(y) in slot r̄ of every
  node y): the value is stored in the slot across the wall from which the
  odd step gathers p̄ for x;
- ``after`` (after the odd step, which pushed f*_r(y) into slot r of y + e_r,
  in particular f*_p(x) into that slot across the wall and f*_p(x − e_p) into
  slot p of x): the value goes to slot p̄ of x, which the next even step reads.

For the two-array pull kernel one table stores the value in the solid slot x pulls from.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from fibersweep.flow.cuts import Cuts
from fibersweep.flow.lattice import OPP, E, Grid, Q, table_cells

__all__ = [
    "LinkTable",
    "bfl_coefficients",
    "family_coefficients",
    "ibb_coefficients",
    "parabolic_correction",
    "aa_interpolated",
    "pull_interpolated",
]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class LinkTable:
    """Rows ``g.flat[dst] = Σ_k coef[:, k] g.flat[src[:, k]]`` (flat over the whole array).

    Attributes
    ----------
    dst : ndarray, shape (n,), int64
    src : ndarray, shape (n, 6), int64
        Where f*_p(x), f*_p̄(x), f*_p(x − e_p), f*_p̄(x − e_p), f*_p(x − 2e_p),
        f*_p̄(x − 2e_p) of each link are stored.
    coef : ndarray, shape (n, 6), float64
        Interpolation weights plus the curvature correction
        (:func:`parabolic_correction`); they sum to 1 per row, so they apply to
        the shifted g = f − w too.
    q : ndarray, shape (n,), float64
        Wall fraction of each link (for diagnostics).
    """

    dst: np.ndarray
    src: np.ndarray
    coef: np.ndarray
    q: np.ndarray


def bfl_coefficients(q: np.ndarray, has_upstream: np.ndarray | None = None) -> np.ndarray:
    """Linear BFL weights on (f*_p(x), f*_p̄(x), f*_p(x − e_p)), shape (n, 3).

    Parameters
    ----------
    q : ndarray, shape (n,)
        Wall fraction of each link, 0 ≤ q ≤ 1.
    has_upstream : ndarray, shape (n,), bool, optional
        False where x − e_p is not fluid: such links with q < 1/2 fall back to
        half-way bounce-back (weights (1, 0, 0)).
    """
    q = np.asarray(q, dtype=np.float64)
    c = np.zeros((q.size, 3))
    low = q < 0.5
    c[low, 0] = 2.0 * q[low]
    c[low, 2] = 1.0 - 2.0 * q[low]
    c[~low, 0] = 0.5 / q[~low]
    c[~low, 1] = 1.0 - 0.5 / q[~low]
    return _fallback(c, q, has_upstream)


def _fallback(c: np.ndarray, q: np.ndarray, has_upstream: np.ndarray | None) -> np.ndarray:
    if has_upstream is not None:
        bad = ~np.asarray(has_upstream, dtype=bool) & (np.abs(c[:, 2]) > 0)
        c[bad] = (1.0, 0.0, 0.0)
    return c


def family_coefficients(q: np.ndarray, rho: np.ndarray) -> np.ndarray:
    """Weights of the linear three-point scheme with wall at q and parameter ρ.

    The schemes f_p̄ = α f*_p(x) + β f*_p(x − e_p) + γ f*_p̄(x) that conserve
    rest populations and are exact for linear profiles with the wall at q
    form a one-parameter family: β = (ρ − 1)/(ρ + 1), σ = 2/((ρ + 1) q),
    α = σ/2 − β, γ = 1 − σ/2. BFL (q < 1/2) is ρ = (1 − q)/q, BFL (q ≥ 1/2)
    ρ = 1 (β = 0), Ginzburg's central linear interpolation ρ = 1/(2q).
    """
    q = np.asarray(q, dtype=np.float64)
    rho = np.asarray(rho, dtype=np.float64)
    beta = (rho - 1.0) / (rho + 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        sigma = 2.0 / ((rho + 1.0) * q)
    return np.column_stack([0.5 * sigma - beta, beta, 1.0 - 0.5 * sigma])[:, [0, 2, 1]]


def ibb_coefficients(
    q: np.ndarray,
    lam_plus: float,
    lam: float,
    has_upstream: np.ndarray | None = None,
    scheme: str = "bfl",
) -> np.ndarray:
    """Weights on (f*_p(x), f*_p̄(x), f*_p(x − e_p)), shape (n, 3), for ``scheme``.

    "bfl": linear BFL. "trt": the member of :func:`family_coefficients`
    that is exact for Poiseuille flow with TRT (steady-state analysis: the
    scheme puts the wall of a parabolic profile at q when
    ρ = X/(q Λ+), X = q²/2 − 2Λ/3 + Λ+/2, Λ = Λ+ Λ−). ρ is limited to at
    least 1/(2q), Ginzburg's central linear interpolation (CLI): members with
    smaller ρ have larger weights and were unstable in tests (q = 0.1 diverged
    with γ = −1). With Λ = 3/16 the exact member satisfies the limit exactly
    for q ≥ 1/2, so this is CLI for q < 1/2 (Poiseuille wall error
    (1/8 − q²/2) ∂²_q e⁻, independent of the viscosity, removed by
    :func:`parabolic_correction`) and exact for q ≥ 1/2.
    """
    q = np.asarray(q, dtype=np.float64)
    if scheme == "bfl":
        return bfl_coefficients(q, has_upstream)
    if scheme != "trt":
        raise ValueError(f"unknown interpolation scheme {scheme!r}")
    x = 0.5 * q * q - 2.0 * lam / 3.0 + 0.5 * lam_plus
    qs = np.maximum(q, 1e-12)
    rho = x / (qs * lam_plus)
    rho = np.maximum(rho, 1.0 / (2.0 * qs))
    c = family_coefficients(qs, rho)
    return _fallback(c, q, has_upstream)


def parabolic_correction(q: np.ndarray, scheme: str) -> np.ndarray:
    """Weight κ of the curvature correction κ (D(x) − 2 D(x − e_p) + D(x − 2e_p)), D = f*_p − f*_p̄.

    For the "trt" scheme at q < 1/2 (CLI) the steady-state analysis leaves a
    wall error (1/8 − q²/2) ∂²e⁻_p; adding −(1 − 2q)/2 ∂²e⁻_p to the returned
    population removes it (Poiseuille flow then exact at every q). Along the
    link D(t) = 2 e⁻_p(t) + const in the bulk, so ∂²e⁻_p = (D(0) − 2D(−1) + D(−2))/2
    and κ = −(1 − 2q)/4. Zero elsewhere ("bfl", and q ≥ 1/2 where "trt" is exact).
    """
    q = np.asarray(q, dtype=np.float64)
    if scheme != "trt":
        return np.zeros_like(q)
    return np.where(q < 0.5, -(1.0 - 2.0 * q) / 4.0, 0.0)


class _Flat:
    """Flat indices into a padded population array (slot, z, y, interior x)."""

    def __init__(self, grid: Grid):
        self.nx, self.ny = grid.nx, grid.ny
        self.nyp, self.nxp = grid.ny + 2, grid.nx + 2
        self.plane = (grid.nz + 2) * self.nyp * self.nxp

    def __call__(self, slot, z, y, x_padded) -> np.ndarray:
        return slot * self.plane + (z * self.nyp + y) * self.nxp + x_padded


def _candidates(grid: Grid, cuts: Cuts, table: np.ndarray, wrap: bool):
    """Yield, per layer k and direction q, cut nodes whose ``table`` source of q is across the wall.

    That source is a solid node, or a fluid node beyond a link that cuts a
    corner of the pillar: its slot is then read only by this node in this
    step, so it can carry the interpolated value as a solid slot does.
    Yields (k, q, m, loc, di, dj): m indexes ``cuts``, loc = (slot, z, y,
    x_padded) of that source (x wrapped into the interior if ``wrap``), (di, dj)
    its in-plane offset.
    """
    for k in range(grid.nz):
        rows = k * grid.ny + cuts.j
        for q in range(1, Q):
            loc, ii, jj = _location(table, rows, q, cuts.i, grid, wrap)
            di = (ii - cuts.i + 1) % grid.nx - 1
            dj = jj - cuts.j
            hit = (np.abs(di) <= 1) & (np.abs(dj) <= 1) & ((di != 0) | (dj != 0))
            hit[hit] = np.isfinite(cuts.q[np.flatnonzero(hit), di[hit] + 1, dj[hit] + 1])
            if not hit.any():
                continue
            loc = tuple(c[hit] for c in loc)
            yield k, q, np.flatnonzero(hit), loc, di[hit], dj[hit]


def _location(table: np.ndarray, rows, q, i, grid: Grid, wrap: bool):
    """(slot, z, y, x_padded) of ``table`` entry q for cells i of ``rows``; interior x, y.

    ``wrap``: an AA table, whose kernel wraps x itself (x_padded in the interior);
    otherwise a pull table, read through the ghost columns (x_padded as it is).
    """
    if wrap:
        return table_cells(grid, table, rows, q, i)
    slot, zs, ys, xo = (table[rows, q, c] for c in range(4))
    ii, jj, _ = grid.wrap(i + xo - 1, ys - 1)  # the node the ghost column repeats
    return (slot, zs, ys, i + xo), ii, jj


def _fluid(grid: Grid, ii: np.ndarray, jj: np.ndarray) -> np.ndarray:
    ok = (jj >= 0) & (jj < grid.ny)
    ok[ok] = ~grid.solid[ii[ok], jj[ok]]
    return ok


def _chain(grid: Grid, flat: _Flat, i, j, k: int, p: int, steps: int):
    """Cells x − s e_p, s = 1..steps, of nodes (i, j, k): (all interior fluid, flat cells)."""
    ex, ey, ez = (int(v) for v in E[p])
    # in-plane links only: a chain along e_z would leave the solved half-depth
    # near the free-slip top, and using it only where it does not would make the
    # half-depth and full-depth solves differ
    ok = np.full(i.size, ez == 0)
    cells = []
    for n in range(1, steps + 1):
        ii, jj, _ = grid.wrap(i - n * ex, j - n * ey)
        kk = k - n * ez
        ok &= (kk >= 0) & (kk < grid.nz) & _fluid(grid, ii, jj)
        cells.append(flat(0, kk + 1, np.clip(jj, -1, grid.ny) + 1, ii + 1))
    return ok, cells


def _with_correction(src3, coef3, extra, kappa, ok, q, p):
    """Append the curvature-correction columns (f*_p̄(x−c), f*_p(x−2c), f*_p̄(x−2c)).

    ``extra``: their flat indices; the correction also weights f*_p(x), f*_p̄(x)
    and f*_p(x − c) (columns 0–2). Where ``ok`` is False it is left out.
    """
    kappa = np.where(ok, kappa, 0.0)
    coef = np.zeros((q.size, 6))
    coef[:, :3] = coef3
    coef[:, 0] += kappa
    coef[:, 1] -= kappa
    coef[:, 2] -= 2.0 * kappa
    coef[:, 3] = 2.0 * kappa
    coef[:, 4] = kappa
    coef[:, 5] = -kappa
    src = np.empty((q.size, 6), dtype=np.int64)
    src[:, :3] = src3
    for n, col in enumerate(extra):
        src[:, 3 + n] = np.where(ok, col, src3[:, 0])  # unused where not ok (weight 0)
    return src, coef


def _table(parts: list) -> LinkTable:
    if not parts:
        return LinkTable(
            np.zeros(0, np.int64), np.zeros((0, 6), np.int64), np.zeros((0, 6)), np.zeros(0)
        )
    dst, src, coef, q = (np.concatenate([p[n] for p in parts]) for n in range(4))
    return LinkTable(dst.astype(np.int64), src.astype(np.int64), coef, q)


def _wall_q(cuts: Cuts, m: np.ndarray, di: np.ndarray, dj: np.ndarray) -> np.ndarray:
    q = cuts.q[m, di + 1, dj + 1]
    if not np.all(np.isfinite(q)):
        raise ValueError("a cut link has no wall fraction: cuts and grid disagree")
    return q


def _coefficients(cuts: Cuts, q, up, omega_p: float, omega_m: float) -> np.ndarray:
    lam_p, lam_m = 1.0 / omega_p - 0.5, 1.0 / omega_m - 0.5
    return ibb_coefficients(q, lam_p, lam_p * lam_m, up, cuts.scheme)


def aa_interpolated(
    grid: Grid,
    cuts: Cuts,
    gather: np.ndarray,
    scatter: np.ndarray,
    omega_p: float,
    omega_m: float,
) -> tuple[LinkTable, LinkTable]:
    """The ``before`` and ``after`` tables of the AA pattern (see the module docstring).

    Parameters
    ----------
    grid : Grid
    cuts : Cuts
        Wall fractions of ``grid.solid``'s links.
    gather, scatter : ndarray, shape (nz * ny, 19, 5), int64
        From :func:`fibersweep.flow.lattice.aa_tables`.
    omega_p, omega_m : float
        TRT relaxation rates (the "trt" weights depend on them).
    """
    flat = _Flat(grid)
    before, after = [], []
    fallback = 0
    for k, q, m, loc, di, dj in _candidates(grid, cuts, gather, wrap=True):
        p = OPP[q]  # the link x → wall is along e_p; p̄ = q comes back
        i, j = cuts.i[m], cuts.j[m]
        rows = k * grid.ny + j
        x_cell = flat(0, k + 1, j + 1, i + 1)
        solid_slot = flat(*loc)
        wq = _wall_q(cuts, m, di, dj)
        up_loc, ui, uj = _location(gather, rows, p, i, grid, wrap=True)
        up = _fluid(grid, ui, uj)
        fallback += int((~up & (wq < 0.5)).sum())
        coef = _coefficients(cuts, wq, up, omega_p, omega_m)
        kappa = parabolic_correction(wq, cuts.scheme)
        ok, (c1, c2, c3) = _chain(grid, flat, i, j, k, p, 3)
        P, Qb = p * flat.plane, q * flat.plane
        # after the even step: f*_p(y) in slot p̄ = q of y, f*_p̄(y) in slot p of y
        src_b = np.column_stack([Qb + x_cell, P + x_cell, flat(*up_loc)])
        src_b, coef_b = _with_correction(src_b, coef, (P + c1, Qb + c2, P + c2), kappa, ok, wq, p)
        before.append((solid_slot, src_b, coef_b, wq))
        pushed_p, _, _ = _location(scatter, rows, p, i, grid, wrap=True)
        if not np.array_equal(flat(*pushed_p), solid_slot):
            raise AssertionError("AA tables: the odd step must push f*_p(x) into the slot it read")
        pushed_q, _, _ = _location(scatter, rows, q, i, grid, wrap=True)
        # after the odd step: f*_p(x) in the solid slot, f*_p̄(x) where x pushed it,
        # f*_p(x − e_p) arrived in slot p of x; the result goes to slot p̄ of x
        # (f*_p(y) was pushed to slot p of y + e_p, f*_p̄(y) to slot p̄ of y − e_p)
        src_a = np.column_stack([solid_slot, flat(*pushed_q), P + x_cell])
        src_a, coef_a = _with_correction(src_a, coef, (Qb + c2, P + c1, Qb + c3), kappa, ok, wq, p)
        after.append((Qb + x_cell, src_a, coef_a, wq))
    if fallback:
        log.info("interpolated bounce-back: %d links fall back to half-way", fallback)
    return _table(before), _table(after)


def pull_interpolated(
    grid: Grid, cuts: Cuts, sources: np.ndarray, omega_p: float, omega_m: float
) -> LinkTable:
    """Table for the two-array pull kernel: values stored in the solid slots that fluid pulls.

    Parameters
    ----------
    grid : Grid
    cuts : Cuts
    sources : ndarray, shape (nz * ny, 19, 4), int64
        From :func:`fibersweep.flow.lattice.pull_sources`; the kernel writes
        post-collision f*_q(x) into slot q of x and fills the periodic ghost columns.
    omega_p, omega_m : float
        TRT relaxation rates.
    """
    flat = _Flat(grid)
    parts = []
    for k, q, m, loc, di, dj in _candidates(grid, cuts, sources, wrap=False):
        p = OPP[q]
        i, j = cuts.i[m], cuts.j[m]
        rows = k * grid.ny + j
        x_cell = flat(0, k + 1, j + 1, i + 1)
        wq = _wall_q(cuts, m, di, dj)
        up_loc, ui, uj = _location(sources, rows, p, i, grid, wrap=False)
        up = _fluid(grid, ui, uj)
        P, Qb = p * flat.plane, q * flat.plane
        # post-collision f*_r(y) is stored in slot r of y
        src = np.column_stack([P + x_cell, Qb + x_cell, flat(*up_loc)])
        ok, (c1, c2, _) = _chain(grid, flat, i, j, k, p, 3)
        src, coef = _with_correction(
            src,
            _coefficients(cuts, wq, up, omega_p, omega_m),
            (Qb + c1, P + c2, Qb + c2),
            parabolic_correction(wq, cuts.scheme),
            ok,
            wq,
            p,
        )
        parts.append((flat(*loc), src, coef, wq))
    return _table(parts)
