"""Numba kernels of the D3Q19 solver: fused pull-stream-collide and boundary fills.

All kernels work on the padded, shifted population array ``g[q, z, y, x]``
(``g = f - w``, float32 by default, float64 with ``flow.precision: float64``)
described in :mod:`fibersweep.flow.lattice`, take arrays and floats only, and
are wrapped by :mod:`fibersweep.flow.solver`. The collision computes in the
storage precision (Numba compiles one specialisation per dtype); the moments
used for convergence checks and results are summed in float64.

Collision (TRT; BGK is ω+ = ω-), second-order equilibrium, Guo forcing with a
body force density ``fx`` along x and the half-force velocity shift:

    g_q* = g_q - ω+ (g+_q - e+_q) - ω- (g-_q - e-_q) + (1 - ω+/2) S+_q + (1 - ω-/2) S-_q

with S_q = w_q [3 (e_q - u)·F + 9 (e_q·u)(e_q·F)] split in its even (S+) and
odd (S-) parts in e_q.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from numba.extending import overload
from numba.np.numpy_support import as_dtype

__all__ = [
    "stream_collide",
    "fill_pillar",
    "apply_interpolated",
    "fill_periodic",
    "moments",
    "init_populations",
]


def as_dtype_of(x, arr):  # pragma: no cover - replaced by the overload in jitted code
    """``x`` cast to the element type of ``arr`` (usable inside Numba kernels only)."""
    raise NotImplementedError("as_dtype_of is only callable from Numba-compiled code")


@overload(as_dtype_of, inline="always")
def _as_dtype_of(x, arr):
    cast = arr.dtype

    def impl(x, arr):
        return cast(x)

    return impl


def lattice_weights(arr):  # pragma: no cover - replaced by the overload in jitted code
    """(w0, w1, w2) as compile-time constants of the element type of ``arr`` (jitted code only)."""
    raise NotImplementedError("lattice_weights is only callable from Numba-compiled code")


@overload(lattice_weights, inline="always")
def _lattice_weights(arr):
    kind = as_dtype(arr.dtype).type
    w0, w1, w2 = kind(1.0 / 3.0), kind(1.0 / 18.0), kind(1.0 / 36.0)  # frozen into the code

    def impl(arr):
        return w0, w1, w2

    return impl


@nb.njit(inline="always")
def block_constants(g, fx, omega_p, omega_m):
    """Collision constants in the element type of ``g`` (float32 or float64).

    Returns (F, F/2, ω+, ω−, 1 − ω+/2, 1 − ω−/2, w0, w1, w2): the kernels then
    compute entirely in the storage precision and specialise on it.
    """
    w0, w1, w2 = lattice_weights(g)
    return (
        as_dtype_of(fx, g),
        as_dtype_of(0.5 * fx, g),
        as_dtype_of(omega_p, g),
        as_dtype_of(omega_m, g),
        as_dtype_of(1.0 - 0.5 * omega_p, g),
        as_dtype_of(1.0 - 0.5 * omega_m, g),
        w0,
        w1,
        w2,
    )


@nb.njit(inline="always", fastmath=True)
def _pair(gi, gj, w, eu, ef, d, rho, usq15, uf3, wp, wm, sp, sm):
    """TRT update of one opposite pair (q, opp q); eu = e_q·u, ef = e_q·F.

    The float32 literals are exact (0.5, 3, 4.5, 9), so they promote without
    rounding when the populations are float64.
    """
    gp = np.float32(0.5) * (gi + gj)
    gm = np.float32(0.5) * (gi - gj)
    ep = w * (d + rho * (np.float32(4.5) * eu * eu - usq15))
    em = w * rho * np.float32(3.0) * eu
    srcp = w * (np.float32(9.0) * eu * ef - uf3)
    srcm = w * np.float32(3.0) * ef
    a = wp * (gp - ep) - sp * srcp
    b = wm * (gm - em) - sm * srcm
    return gi - a - b, gj - a + b


CHUNK = 128  # x-cells per block: 19 x 128 float32 = 9.7 kB stays in L1 (float64: 19.5 kB)


@nb.njit(inline="always", fastmath=True)
def _collide_block(b, n, F, half_f, wp, wm, sp, sm, w0, w1, w2):
    """Collide the first ``n`` cells of a (19, CHUNK) block in place.

    TRT (BGK if wp == wm), second-order equilibrium, Guo forcing ``F`` along x;
    ``half_f`` = F/2 is the half-force velocity shift, ``sp``/``sm`` = 1 − ω±/2,
    ``w0``/``w1``/``w2`` the lattice weights; all scalars in the block's dtype
    (:func:`block_constants`).
    """
    one = as_dtype_of(1.0, b)
    zero = as_dtype_of(0.0, b)
    for i in range(n):
        f0 = b[0, i]
        f1 = b[1, i]
        f2 = b[2, i]
        f3 = b[3, i]
        f4 = b[4, i]
        f5 = b[5, i]
        f6 = b[6, i]
        f7 = b[7, i]
        f8 = b[8, i]
        f9 = b[9, i]
        f10 = b[10, i]
        f11 = b[11, i]
        f12 = b[12, i]
        f13 = b[13, i]
        f14 = b[14, i]
        f15 = b[15, i]
        f16 = b[16, i]
        f17 = b[17, i]
        f18 = b[18, i]
        d = (
            f0 + f1 + f2 + f3 + f4 + f5 + f6 + f7 + f8 + f9
            + f10 + f11 + f12 + f13 + f14 + f15 + f16 + f17 + f18
        )  # fmt: skip
        rho = one + d
        inv = one / rho
        jx = f1 - f2 + f7 - f8 + f9 - f10 + f11 - f12 + f13 - f14
        jy = f3 - f4 + f7 - f8 - f9 + f10 + f15 - f16 + f17 - f18
        jz = f5 - f6 + f11 - f12 - f13 + f14 + f15 - f16 - f17 + f18
        ux = (jx + half_f) * inv
        uy = jy * inv
        uz = jz * inv
        usq15 = np.float32(1.5) * (ux * ux + uy * uy + uz * uz)
        uf3 = np.float32(3.0) * ux * F
        e0 = w0 * (d - rho * usq15)  # rest population: even part only
        b[0, i] = f0 - wp * (f0 - e0) - sp * w0 * uf3  # S_0 = -w_0 3 u.F
        b[1, i], b[2, i] = _pair(f1, f2, w1, ux, F, d, rho, usq15, uf3, wp, wm, sp, sm)
        b[3, i], b[4, i] = _pair(f3, f4, w1, uy, zero, d, rho, usq15, uf3, wp, wm, sp, sm)
        b[5, i], b[6, i] = _pair(f5, f6, w1, uz, zero, d, rho, usq15, uf3, wp, wm, sp, sm)
        b[7, i], b[8, i] = _pair(f7, f8, w2, ux + uy, F, d, rho, usq15, uf3, wp, wm, sp, sm)
        b[9, i], b[10, i] = _pair(f9, f10, w2, ux - uy, F, d, rho, usq15, uf3, wp, wm, sp, sm)
        b[11, i], b[12, i] = _pair(f11, f12, w2, ux + uz, F, d, rho, usq15, uf3, wp, wm, sp, sm)
        b[13, i], b[14, i] = _pair(f13, f14, w2, ux - uz, F, d, rho, usq15, uf3, wp, wm, sp, sm)
        b[15, i], b[16, i] = _pair(f15, f16, w2, uy + uz, zero, d, rho, usq15, uf3, wp, wm, sp, sm)
        b[17, i], b[18, i] = _pair(f17, f18, w2, uy - uz, zero, d, rho, usq15, uf3, wp, wm, sp, sm)


@nb.njit(cache=True, parallel=True, fastmath=True)
def stream_collide(
    g: np.ndarray,
    gn: np.ndarray,
    sources: np.ndarray,
    slots: np.ndarray,
    fx: float,
    omega_p: float,
    omega_m: float,
) -> None:
    """One fused pull-stream + collide step over the interior, g -> gn.

    Each row (z, y) is processed in blocks of ``CHUNK`` cells: the 19 pulled
    source segments are copied into a local block, collided in place and
    copied out. The block has compile-time strides, so LLVM can prove the
    in-place collision free of aliasing and vectorise it (it cannot with 38
    row pointers into the same arrays). Walls are resolved per row through
    ``sources``; the pillar through values stored in its cells
    (:func:`fill_pillar`); periodic x through ghost columns written here.

    Parameters
    ----------
    g, gn : ndarray, shape (19, nz + 2, ny + 2, nx + 2), float32 or float64
        Post-collision populations of the last step and the output.
    sources : ndarray, shape (nz * ny, 19, 4), int64
        Per row r = z * ny + y and population q: (q_src, z_src, y_src, x_off) in
        padded coordinates; population q of interior cell i is
        ``g[q_src, z_src, y_src, x_off + i]`` (see :func:`fibersweep.flow.lattice.pull_sources`).
    slots : ndarray, shape (19,), int64
        Slot of ``gn`` that the collided population q is written to: the identity,
        or with the force along y the turned frame (:data:`fibersweep.flow.lattice.FRAMES`,
        ``sources`` then permuted alike).
    fx : float
        Body force density along x [lattice units].
    omega_p, omega_m : float
        Relaxation rates of the even and odd moments (equal for BGK).
    """
    nx = g.shape[3] - 2
    ny = g.shape[2] - 2
    nrows = sources.shape[0]
    F, half_f, wp, wm, sp, sm, w0, w1, w2 = block_constants(g, fx, omega_p, omega_m)
    for r in nb.prange(nrows):
        z = r // ny + 1
        y = r - (z - 1) * ny + 1
        b = np.empty((19, CHUNK), dtype=g.dtype)
        for c0 in range(0, nx, CHUNK):
            # unsigned indices: numba then emits no negative-index wraparound
            # test, which would otherwise block vectorisation
            n = np.uint64(min(CHUNK, nx - c0))
            for q in range(19):
                src = g[sources[r, q, 0], sources[r, q, 1], sources[r, q, 2]]
                off = np.uint64(sources[r, q, 3] + c0)
                bq = b[q]
                for i in range(n):
                    bq[i] = src[off + i]
            _collide_block(b, n, F, half_f, wp, wm, sp, sm, w0, w1, w2)
            o = np.uint64(1 + c0)
            for q in range(19):
                dst = gn[slots[q], z, y]
                bq = b[q]
                for i in range(n):
                    dst[o + i] = bq[i]
        for q in range(19):  # periodic ghost columns of this row
            gn[q, z, y, 0] = gn[q, z, y, nx]
            gn[q, z, y, nx + 1] = gn[q, z, y, 1]


@nb.njit(cache=True)
def fill_pillar(g: np.ndarray, solid_cells: np.ndarray, links: np.ndarray) -> None:
    """Reset pillar cells to rest, then store bounce-back values where fluid pulls them.

    Parameters
    ----------
    g : ndarray, shape (19, nz + 2, ny + 2, nx + 2), float32 or float64
        Populations just written by :func:`stream_collide`.
    solid_cells : ndarray, shape (m,), int64
        Flat indices (in one padded plane) of pillar cells.
    links : ndarray, shape (n, 4), int64
        Rows (q, dst, q_src, src) from :func:`fibersweep.flow.lattice.boundary_links`.
    """
    plane = g.shape[1] * g.shape[2] * g.shape[3]
    flat = g.reshape(g.shape[0] * plane)
    for q in range(g.shape[0]):
        for c in range(solid_cells.shape[0]):
            flat[q * plane + solid_cells[c]] = 0.0
    for n in range(links.shape[0]):
        flat[links[n, 0] * plane + links[n, 1]] = flat[links[n, 2] * plane + links[n, 3]]


@nb.njit(cache=True)
def apply_interpolated(
    g: np.ndarray,
    dst: np.ndarray,
    src: np.ndarray,
    coef: np.ndarray,
    buf: np.ndarray,
    reset_cells: np.ndarray,
) -> None:
    """Interpolated bounce-back rows, then zero the solid cells, then store.

    All values are computed first (sources may be solid slots that the reset
    clears, destinations may be solid slots that it must not clear), so the
    order of the rows does not matter.

    Parameters
    ----------
    g : ndarray, shape (19, nz + 2, ny + 2, nx + 2), float32 or float64
    dst : ndarray, shape (n,), int64
        Flat indices into the whole of ``g`` (slot × plane + cell).
    src : ndarray, shape (n, k), int64
        Flat indices of the interpolated populations.
    coef : ndarray, shape (n, k), float64
        Their weights (:class:`fibersweep.flow.ibb.LinkTable`).
    buf : ndarray, shape (n,), float64
        Scratch space.
    reset_cells : ndarray, shape (m,), int64
        Flat indices (one padded plane) zeroed in every slot.
    """
    plane = g.shape[1] * g.shape[2] * g.shape[3]
    flat = g.reshape(g.shape[0] * plane)
    for n in range(dst.shape[0]):
        acc = 0.0
        for k in range(src.shape[1]):
            acc += coef[n, k] * flat[src[n, k]]
        buf[n] = acc
    for q in range(g.shape[0]):
        for c in range(reset_cells.shape[0]):
            flat[q * plane + reset_cells[c]] = 0.0
    for n in range(dst.shape[0]):
        flat[dst[n]] = buf[n]


@nb.njit(cache=True, parallel=True)
def fill_periodic(g: np.ndarray, shift: int) -> None:
    """Copy the x ghost columns from the interior columns they repeat.

    With a row shift s (a box periodic in y, :attr:`fibersweep.flow.lattice.Grid.shift`)
    the ghost of node (−1, j) is node (nx − 1, j + s) and that of (nx, j) is
    (0, j − s); with s = 0 each row is periodic on its own.
    """
    nyp, nxp = g.shape[2], g.shape[3]
    ny = nyp - 2
    for q in nb.prange(g.shape[0]):
        for z in range(g.shape[1]):
            for y in range(nyp):
                low, high = y, y
                if shift != 0 and 0 < y < nyp - 1:
                    low = (y - 1 + shift) % ny + 1
                    high = (y - 1 - shift) % ny + 1
                g[q, z, y, 0] = g[q, z, low, nxp - 2]
                g[q, z, y, nxp - 1] = g[q, z, high, 1]


@nb.njit(cache=True, parallel=True)
def moments(
    g: np.ndarray, sources: np.ndarray, fx: float, ex: np.ndarray, ey: np.ndarray, ez: np.ndarray,
    out: np.ndarray,
) -> None:  # fmt: skip
    """Density deviation and velocity (with the half-force shift) of every interior node.

    The moments are those of the populations the next step pulls (its
    pre-collision state), exactly as :func:`stream_collide` computes them.

    Parameters
    ----------
    g : ndarray, shape (19, nz + 2, ny + 2, nx + 2), float32 or float64
    sources : ndarray, shape (nz * ny, 19, 4), int64
        Pull table of :func:`stream_collide`.
    ex, ey, ez : ndarray, shape (19,), int64
        Lattice velocities.
    out : ndarray, shape (4, nz, ny, nx), float64
        Written with (δρ, ux, uy, uz).
    """
    nx = g.shape[3] - 2
    ny = g.shape[2] - 2
    for r in nb.prange(sources.shape[0]):
        z = r // ny
        y = r - z * ny
        for x in range(nx):
            d = 0.0
            jx = 0.0
            jy = 0.0
            jz = 0.0
            for q in range(19):
                s = sources[r, q]
                f = np.float64(g[s[0], s[1], s[2], s[3] + x])
                d += f
                jx += f * ex[q]
                jy += f * ey[q]
                jz += f * ez[q]
            rho = 1.0 + d
            out[0, z, y, x] = d
            out[1, z, y, x] = (jx + 0.5 * fx) / rho
            out[2, z, y, x] = jy / rho
            out[3, z, y, x] = jz / rho


@nb.njit(cache=True, parallel=True)
def init_populations(
    g: np.ndarray,
    u: np.ndarray,
    drho: np.ndarray,
    grad: np.ndarray,
    omega_p: float,
    post_collision: bool,
    w: np.ndarray,
    ex: np.ndarray,
    ey: np.ndarray,
    ez: np.ndarray,
) -> None:
    """Set interior populations to the state of a given flow (after or before a collision).

    Equilibrium of (ρ = 1 + δρ, u) plus the Chapman-Enskog non-equilibrium part
    f¹_q = −3 τ w_q ρ Q_q:∇u (Q = e e − c_s² I): after a collision
    g_q = f^eq_q − w_q + (1 − ω+) f¹_q, before it f^eq_q − w_q + f¹_q. Without f¹ the
    whole shear stress as a pressure pulse that takes hundreds of steps to damp.

    Parameters
    ----------
    g : ndarray, shape (19, nz + 2, ny + 2, nx + 2), float32 or float64
    u : ndarray, shape (3, nz, ny, nx), float64
        Lattice velocity.
    drho : ndarray, shape (nz, ny, nx), float64
        Density deviation δρ.
    grad : ndarray, shape (3, 3, nz, ny, nx), float64
        grad[a, b] = ∂_a u_b.
    omega_p : float
        Relaxation rate of the even moments (τ = 1/ω+).
    post_collision : bool
        True: the state a collision leaves (two-array pull kernel stores these);
        False: the state before a collision, f^eq + f¹ (the AA kernel's even step
        starts from it).
    w : ndarray, shape (19,), float64
        Lattice weights.
    ex, ey, ez : ndarray, shape (19,), int64
        Lattice velocities.
    """
    nz, ny, nx = g.shape[1] - 2, g.shape[2] - 2, g.shape[3] - 2
    tau = 1.0 / omega_p
    keep = 1.0 - omega_p if post_collision else 1.0
    for r in nb.prange(nz * ny):
        z = r // ny
        y = r - z * ny
        for x in range(nx):
            ux = u[0, z, y, x]
            uy = u[1, z, y, x]
            uz = u[2, z, y, x]
            d = drho[z, y, x]
            rho = 1.0 + d
            usq = ux * ux + uy * uy + uz * uz
            div = grad[0, 0, z, y, x] + grad[1, 1, z, y, x] + grad[2, 2, z, y, x]
            for q in range(19):
                e0, e1, e2 = ex[q], ey[q], ez[q]
                eu = e0 * ux + e1 * uy + e2 * uz
                # Q:∇u = e_a e_b ∂_a u_b − c_s² ∇·u
                qs = (
                    e0
                    * (
                        e0 * grad[0, 0, z, y, x]
                        + e1 * grad[0, 1, z, y, x]
                        + e2 * grad[0, 2, z, y, x]
                    )
                    + e1
                    * (
                        e0 * grad[1, 0, z, y, x]
                        + e1 * grad[1, 1, z, y, x]
                        + e2 * grad[1, 2, z, y, x]
                    )
                    + e2
                    * (
                        e0 * grad[2, 0, z, y, x]
                        + e1 * grad[2, 1, z, y, x]
                        + e2 * grad[2, 2, z, y, x]
                    )
                    - div / 3.0
                )
                feq = w[q] * (d + rho * (3.0 * eu + 4.5 * eu * eu - 1.5 * usq))
                fneq = -3.0 * tau * w[q] * rho * qs
                g[q, z + 1, y + 1, x + 1] = feq + keep * fneq
