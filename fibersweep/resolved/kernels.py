"""Numba kernels of the resolved lattice: TRT collision, streaming, moving interpolated bounce-back.

Arrays and floats only; the checked entry points are in
:mod:`fibersweep.resolved.lattice`. Populations are unshifted ``f[q, n]``
(float64, n the flat node of :mod:`fibersweep.resolved.box`); ``flags[n]`` is 0
for fluid, 1 for a static solid (pillar) and 2 for a node inside the particle.

Particle boundary (Bouzidi, Firdaouss & Lallemand 2001 linear interpolation, as
Lallemand & Luo 2003 for moving walls): a fluid node x whose neighbour
x − e_q lies inside the particle gets, with t the fraction of the link at
which the surface lies and u_w the surface's velocity there,

    t < ½:  f_q(x) = 2t f*_q̄(x) + (1 − 2t) f*_q̄(x + e_q) + 6 w_q e_q·u_w
    t ≥ ½:  f_q(x) = f*_q̄(x)/(2t) + (1 − 1/(2t)) f*_q(x) + 6 w_q e_q·u_w/(2t)

(q̄ = opp q; f* post-collision). The link gives the particle the momentum
f*_q̄ e_q̄ − f_q e_q, corrected for the wall's motion as Wen et al. (2014).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from fibersweep.flow.lattice import OPP, E, W

__all__ = ["collide", "stream", "static_links", "particle_links", "refill", "moments"]

_E = np.ascontiguousarray(E.astype(np.int64))
_EF = np.ascontiguousarray(E.astype(np.float64))
_OPP = np.ascontiguousarray(OPP.astype(np.int64))
_W = np.ascontiguousarray(W.astype(np.float64))
_REACH = 1.415  # > √2, the longest D3Q19 link


@nb.njit(cache=True, parallel=True, fastmath=True)
def collide(f, flags, force, omega_p, omega_m):
    """TRT collision with Guo forcing, in place on the fluid nodes (flags == 0).

    ``force``: (3,) body force density [lattice units]; ω± the even/odd rates.
    """
    N = f.shape[1]
    fx, fy, fz = force[0], force[1], force[2]
    sp = 1.0 - 0.5 * omega_p
    sm = 1.0 - 0.5 * omega_m
    nblk = (N + 255) // 256
    for b in nb.prange(nblk):
        feq = np.empty(19)
        src = np.empty(19)
        for n in range(b * 256, min(N, b * 256 + 256)):
            if flags[n] != 0:
                continue
            rho = 0.0
            jx = 0.0
            jy = 0.0
            jz = 0.0
            for q in range(19):
                v = f[q, n]
                rho += v
                jx += v * _EF[q, 0]
                jy += v * _EF[q, 1]
                jz += v * _EF[q, 2]
            ux = (jx + 0.5 * fx) / rho
            uy = (jy + 0.5 * fy) / rho
            uz = (jz + 0.5 * fz) / rho
            usq = 1.5 * (ux * ux + uy * uy + uz * uz)
            uf = ux * fx + uy * fy + uz * fz
            for q in range(19):
                eu = _EF[q, 0] * ux + _EF[q, 1] * uy + _EF[q, 2] * uz
                ef = _EF[q, 0] * fx + _EF[q, 1] * fy + _EF[q, 2] * fz
                feq[q] = _W[q] * rho * (1.0 + 3.0 * eu + 4.5 * eu * eu - usq)
                src[q] = _W[q] * (3.0 * (ef - uf) + 9.0 * eu * ef)
            f[0, n] = f[0, n] - omega_p * (f[0, n] - feq[0]) + sp * src[0]
            for q in range(1, 19, 2):
                o = q + 1
                gp = 0.5 * (f[q, n] + f[o, n])
                gm = 0.5 * (f[q, n] - f[o, n])
                ep = 0.5 * (feq[q] + feq[o])
                em = 0.5 * (feq[q] - feq[o])
                s_p = 0.5 * (src[q] + src[o])
                s_m = 0.5 * (src[q] - src[o])
                a = omega_p * (gp - ep) - sp * s_p
                c = omega_m * (gm - em) - sm * s_m
                f[q, n] = f[q, n] - a - c
                f[o, n] = f[o, n] - a + c


@nb.njit(cache=True, parallel=True, fastmath=True)
def stream(f, fn, src, flags, wall_velocity):
    """Pull streaming f → fn on the fluid nodes through the table ``src`` (19, N).

    Negative entries bounce back half-way: −1 a static wall, −2 / −3 the bottom
    / top z wall moving with ``wall_velocity[0]`` / ``[1]`` (Ladd's term 6 w e·u_w).
    """
    N = f.shape[1]
    flat = f.ravel()
    nblk = (N + 255) // 256
    for b in nb.prange(nblk):
        for n in range(b * 256, min(N, b * 256 + 256)):
            if flags[n] != 0:
                continue
            for q in range(19):
                s = src[q, n]
                if s >= 0:
                    fn[q, n] = flat[s]
                else:
                    v = f[_OPP[q], n]
                    if s <= -2:
                        w = -2 - s
                        eu = (_EF[q, 0] * wall_velocity[w, 0] + _EF[q, 1] * wall_velocity[w, 1]
                              + _EF[q, 2] * wall_velocity[w, 2])  # fmt: skip
                        v += 6.0 * _W[q] * eu
                    fn[q, n] = v


@nb.njit(cache=True)
def static_links(f, fn, flags, node, qs, ts, beyond):
    """Interpolated bounce-back on a resting wall for the links (node, q, t, beyond).

    A link whose node beyond is not fluid now (a body covers it) falls back to
    half-way bounce-back.
    """
    for m in range(node.shape[0]):
        n = node[m]
        q = qs[m]
        o = _OPP[q]
        t = ts[m]
        if t < 0.5:
            nb2 = beyond[m]
            if nb2 >= 0 and flags[nb2] == 0:
                fn[q, n] = 2.0 * t * f[o, n] + (1.0 - 2.0 * t) * f[o, nb2]
            else:
                fn[q, n] = f[o, n]
        else:
            fn[q, n] = f[o, n] / (2.0 * t) + (1.0 - 0.5 / t) * f[q, n]


@nb.njit(inline="always")
def _sdf(x, y, z, cx, cy, cz, px, py, pz, ell, a):
    """Signed distance to a capsule (segment centre c, unit axis p, half-length ell, radius a)."""
    dx, dy, dz = x - cx, y - cy, z - cz
    s = dx * px + dy * py + dz * pz
    if s > ell:
        s = ell
    elif s < -ell:
        s = -ell
    rx, ry, rz = dx - s * px, dy - s * py, dz - s * pz
    return np.sqrt(rx * rx + ry * ry + rz * rz) - a


@nb.njit(inline="always")
def _node(i, j, k, nx, ny, nz, shift, periodic_y, z_periodic):
    """Flat node of lattice position (i, j, k), −1 outside the box (beyond a wall)."""
    rows = i // nx
    i = i - rows * nx
    j = j - rows * shift
    if periodic_y:
        j = j % ny
    elif j < 0 or j >= ny:
        return -1
    if z_periodic:
        k = k % nz
    elif k < 0 or k >= nz:
        return -1
    return (k * ny + j) * nx + i


@nb.njit(cache=True)
def particle_links(f, fn, flags, dims, body, out):
    """Moving interpolated bounce-back on the particle's links; its force and torque.

    Parameters
    ----------
    f, fn : ndarray, shape (19, N)
        Post-collision populations of the step and the streamed ones (fixed here).
    flags : ndarray, shape (N,), int8
    dims : ndarray, (nx, ny, nz, shift, periodic_y, z_periodic, symmetric_top), int64
    body : ndarray, shape (14,)
        Centre (3), unit axis (3), half-length, radius, velocity (3), angular velocity (3),
        all in lattice units; the centre unwrapped (it may lie outside the box).
    out : ndarray, shape (43,)
        Set to the force (3), torque about the centre (3), the number of links, and
        the 6 × 6 matrix Z (row-major) of the part of (force, torque) that the
        links' wall-velocity term makes linear in the body's (U, Ω): that part is
        −Z (U, Ω), each link adding c J Jᵀ with J = (e_q, r × e_q) and
        c = 6 w_q (t < ½) or 6 w_q/(2t) (Ladd & Verberg's implicit update uses it).
    """
    nx, ny, nz, shift = dims[0], dims[1], dims[2], dims[3]
    py_, zp, sym = dims[4] != 0, dims[5] != 0, dims[6] != 0
    cx, cy, cz = body[0], body[1], body[2]
    px, py, pz, ell, a = body[3], body[4], body[5], body[6], body[7]
    ux, uy, uz, wx, wy, wz = body[8], body[9], body[10], body[11], body[12], body[13]
    ext = ell + a + 2.0
    lo = np.array([cx - ext, cy - ext, cz - ext])
    hi = np.array([cx + ext, cy + ext, cz + ext])
    for c in range(43):
        out[c] = 0.0
    jv = np.empty(6)
    for kk in range(int(np.floor(lo[2])), int(np.ceil(hi[2])) + 1):
        if sym and kk >= nz:
            continue
        for jj in range(int(np.floor(lo[1])), int(np.ceil(hi[1])) + 1):
            for ii in range(int(np.floor(lo[0])), int(np.ceil(hi[0])) + 1):
                n = _node(ii, jj, kk, nx, ny, nz, shift, py_, zp)
                if n < 0 or flags[n] != 0:
                    continue
                x, y, z = ii + 0.5, jj + 0.5, kk + 0.5
                # the distance is 1-Lipschitz and a link at most √2 long: no link from here
                if _sdf(x, y, z, cx, cy, cz, px, py, pz, ell, a) > _REACH:
                    continue
                for q in range(1, 19):
                    ex, ey, ez = _EF[q, 0], _EF[q, 1], _EF[q, 2]
                    if _sdf(x - ex, y - ey, z - ez, cx, cy, cz, px, py, pz, ell, a) >= 0.0:
                        continue
                    if ell == 0.0:  # a sphere: the link's entry |x − t e − c| = a, exactly
                        dx_, dy_, dz_ = x - cx, y - cy, z - cz
                        de = dx_ * ex + dy_ * ey + dz_ * ez
                        ee = ex * ex + ey * ey + ez * ez
                        disc = de * de - ee * (dx_ * dx_ + dy_ * dy_ + dz_ * dz_ - a * a)
                        t = (de - np.sqrt(max(disc, 0.0))) / ee
                        t = min(max(t, 1e-6), 1.0)
                    else:  # a capsule: bisection, sdf(x − t e) >= 0 at t0, < 0 at t1
                        t0, t1 = 0.0, 1.0
                        for _ in range(30):
                            tm = 0.5 * (t0 + t1)
                            if _sdf(x - tm * ex, y - tm * ey, z - tm * ez, cx, cy, cz, px, py,
                                    pz, ell, a) >= 0.0:  # fmt: skip
                                t0 = tm
                            else:
                                t1 = tm
                        t = max(0.5 * (t0 + t1), 1e-6)
                    xw, yw, zw = x - t * ex, y - t * ey, z - t * ez
                    rx, ry, rz = xw - cx, yw - cy, zw - cz
                    vx = ux + wy * rz - wz * ry
                    vy = uy + wz * rx - wx * rz
                    vz = uz + wx * ry - wy * rx
                    eu = ex * vx + ey * vy + ez * vz
                    o = _OPP[q]
                    fo = f[o, n]
                    cz_ = 6.0 * _W[q] if t < 0.5 else 3.0 * _W[q] / t
                    jv[0], jv[1], jv[2] = ex, ey, ez
                    jv[3] = ry * ez - rz * ey
                    jv[4] = rz * ex - rx * ez
                    jv[5] = rx * ey - ry * ex
                    for r1 in range(6):
                        for r2 in range(6):
                            out[7 + 6 * r1 + r2] += cz_ * jv[r1] * jv[r2]
                    if t < 0.5:
                        n2 = _node(ii + _E[q, 0], jj + _E[q, 1], kk + _E[q, 2], nx, ny, nz,
                                   shift, py_, zp)  # fmt: skip
                        if sym and kk + _E[q, 2] >= nz:
                            n2 = -1
                        if n2 >= 0 and flags[n2] == 0:
                            val = 2.0 * t * fo + (1.0 - 2.0 * t) * f[o, n2] + 6.0 * _W[q] * eu
                        else:
                            val = fo + 6.0 * _W[q] * eu
                    else:
                        val = (fo + 6.0 * _W[q] * eu) / (2.0 * t) + (1.0 - 0.5 / t) * f[q, n]
                    fn[q, n] = val
                    # momentum to the particle: f*_o e_o − f_q e_q, in the wall's frame
                    s = fo + val
                    d = fo - val
                    gx = -s * ex - d * vx
                    gy = -s * ey - d * vy
                    gz = -s * ez - d * vz
                    out[0] += gx
                    out[1] += gy
                    out[2] += gz
                    out[3] += ry * gz - rz * gy
                    out[4] += rz * gx - rx * gz
                    out[5] += rx * gy - ry * gx
                    out[6] += 1.0


@nb.njit(cache=True)
def refill(f, flags, dims, body, reach, out):
    """Mark the nodes the particle now covers; refill those it uncovered.

    An uncovered node gets the equilibrium at the surface velocity there and
    the mean density of its fluid neighbours (Aidun, Lu & Ding 1998); the
    momentum it receives is taken from the particle, and a covered node's
    momentum given to it. ``reach``: how far [lattice units] the particle may
    have moved since the last call. ``out`` (6,) is set to the impulse and its
    moment about the centre.
    """
    nx, ny, nz, shift = dims[0], dims[1], dims[2], dims[3]
    py_, zp, sym = dims[4] != 0, dims[5] != 0, dims[6] != 0
    cx, cy, cz = body[0], body[1], body[2]
    px, py, pz, ell, a = body[3], body[4], body[5], body[6], body[7]
    ux, uy, uz, wx, wy, wz = body[8], body[9], body[10], body[11], body[12], body[13]
    ext = ell + a + 2.0 + reach
    for c in range(6):
        out[c] = 0.0
    for kk in range(int(np.floor(cz - ext)), int(np.ceil(cz + ext)) + 1):
        if sym and kk >= nz:
            continue
        for jj in range(int(np.floor(cy - ext)), int(np.ceil(cy + ext)) + 1):
            for ii in range(int(np.floor(cx - ext)), int(np.ceil(cx + ext)) + 1):
                n = _node(ii, jj, kk, nx, ny, nz, shift, py_, zp)
                if n < 0 or flags[n] == 1:
                    continue
                x, y, z = ii + 0.5, jj + 0.5, kk + 0.5
                inside = _sdf(x, y, z, cx, cy, cz, px, py, pz, ell, a) < 0.0
                rx, ry, rz = x - cx, y - cy, z - cz
                if flags[n] == 2 and not inside:
                    rho = 0.0
                    cnt = 0
                    for q in range(1, 19):
                        m = _node(ii + _E[q, 0], jj + _E[q, 1], kk + _E[q, 2], nx, ny, nz,
                                  shift, py_, zp)  # fmt: skip
                        if m >= 0 and flags[m] == 0:
                            for p in range(19):
                                rho += f[p, m]
                            cnt += 1
                    rho = rho / cnt if cnt > 0 else 1.0
                    vx = ux + wy * rz - wz * ry
                    vy = uy + wz * rx - wx * rz
                    vz = uz + wx * ry - wy * rx
                    usq = 1.5 * (vx * vx + vy * vy + vz * vz)
                    for q in range(19):
                        eu = _EF[q, 0] * vx + _EF[q, 1] * vy + _EF[q, 2] * vz
                        f[q, n] = _W[q] * rho * (1.0 + 3.0 * eu + 4.5 * eu * eu - usq)
                    flags[n] = 0
                    gx, gy, gz = -rho * vx, -rho * vy, -rho * vz
                elif flags[n] == 0 and inside:
                    gx, gy, gz = 0.0, 0.0, 0.0
                    for q in range(19):
                        gx += f[q, n] * _EF[q, 0]
                        gy += f[q, n] * _EF[q, 1]
                        gz += f[q, n] * _EF[q, 2]
                    flags[n] = 2
                else:
                    continue
                out[0] += gx
                out[1] += gy
                out[2] += gz
                out[3] += ry * gz - rz * gy
                out[4] += rz * gx - rx * gz
                out[5] += rx * gy - ry * gx


@nb.njit(cache=True, parallel=True, fastmath=True)
def moments(f, flags, force, rho, u):
    """Density (N,) and velocity (3, N) with the half-force shift; zero off the fluid."""
    N = f.shape[1]
    for n in nb.prange(N):
        if flags[n] != 0:
            rho[n] = 0.0
            u[0, n] = 0.0
            u[1, n] = 0.0
            u[2, n] = 0.0
            continue
        r = 0.0
        jx = 0.0
        jy = 0.0
        jz = 0.0
        for q in range(19):
            v = f[q, n]
            r += v
            jx += v * _EF[q, 0]
            jy += v * _EF[q, 1]
            jz += v * _EF[q, 2]
        rho[n] = r
        u[0, n] = (jx + 0.5 * force[0]) / r
        u[1, n] = (jy + 0.5 * force[1]) / r
        u[2, n] = (jz + 0.5 * force[2]) / r
