"""Fit the sphere-wall kernels of fibersweep.fiber.hydro.wall_mobility and print their coefficients.

Each quiescent resistance is its exact lubrication and far-field terms plus a
remainder x^m [P(x) + (1 − x) ln(h/δ) Q(x)], x = a/h, fitted by least squares
in relative error to the exact bispherical values (fibersweep.fiber.hydro.wall_exact)
on gaps ε = δ/a from 1e-6 to 1e3. The shear force and torque factors are fitted
to Goldman, Cox & Brenner's (1967b) table with their contact values imposed.
Goren & O'Neill's normal push c_n is 1 + (9/8) x + (81/64 + 1/3) x² plus the
same remainder at m = 3, fitted to the exact series (wallexact.normal_push).
The script prints the coefficient tuples to paste into wallmobility.py and the
largest error of each fit on the fit points and on a denser check grid.

    python3 scripts/tools/fit_wall_mobility.py
"""

from __future__ import annotations

import numpy as np

from fibersweep.fiber.hydro import wall_mobility as wm
from fibersweep.fiber.hydro.wall_exact import brenner_normal, normal_push, parallel_resistances

# powers m of the remainders; P of degree 5 and Q of degree 2 for all four. The
# first coefficient P₀ is imposed so that the far field is exact to O(x²)
# (λ⊥: (9/8)², f_tt: (9/16)²), to O(x⁴) for f_tr (x⁴/8) and O(x³) for f_rr (5/16).
M_PERP, M_TT, M_TR, M_RR = wm.ORDERS
DEG_P, DEG_Q = 5, 2


def basis(x: np.ndarray, m: int) -> np.ndarray:
    lg = -np.log1p(-x)
    cols = [x ** (m + k) for k in range(DEG_P + 1)]
    cols += [(1 - x) * lg * x ** (m + k) for k in range(DEG_Q + 1)]
    return np.array(cols).T


def show(name: str, coef) -> None:
    """Print a coefficient tuple as the module defines it."""
    print(f"_{name} = (\n" + "".join(f"    {float(v)!r},\n" for v in coef) + ")")


def fit(x, target, base, m, fixed0=None, scale=None):
    a = basis(x, m)
    y = target - base
    if fixed0 is not None:
        y = y - fixed0 * a[:, 0]
        a = a[:, 1:]
    # relative error; the coupling relative to f_tt (it vanishes like x⁴ far away)
    w = 1.0 / np.abs(target if scale is None else scale)
    c, *_ = np.linalg.lstsq(a * w[:, None], y * w, rcond=None)
    return np.concatenate([[fixed0], c]) if fixed0 is not None else c


def exact(eps):
    par = np.array([parallel_resistances(1.0 + e) for e in eps])
    perp = np.array([brenner_normal(1.0 + e) for e in eps])
    return perp, par[:, 0], par[:, 2], par[:, 3]


def main() -> None:
    eps = np.concatenate([np.logspace(-6, 0, 121), np.logspace(0, 3, 40)[1:]])
    x = 1.0 / (1.0 + eps)
    lg = -np.log1p(-x)
    perp, ftt, ftr, frr = exact(eps)
    fits = {
        "PERP": fit(x, perp, x / (1 - x) + 0.2 * (lg - x) + 1 + x / 8, M_PERP, 81 / 64 - 1.1),
        "TT": fit(x, ftt, 8 / 15 * (lg - x) + 1 + 9 / 16 * x, M_TT, 81 / 256 - 4 / 15),
        "TR": fit(x, ftr, 2 / 15 * (lg - x - x**2 / 2 - x**3 / 3), M_TR, 1 / 8 - 1 / 30, scale=ftt),
        "RR": fit(x, 0.75 * frr, 0.4 * (lg - x - x**2 / 2) + 1, M_RR, fixed0=5 / 16 - 2 / 15),
    }
    push = np.array([normal_push(1.0 + e) for e in eps])
    fits["PUSH"] = fit(x, push, 1 + 9 / 8 * x + wm.PUSH_X2 * x**2, 3)
    for name, c in fits.items():
        show(name, c)

    # shear (table values of the validation test, contact values imposed)
    al = np.array([3.0, 2.0, 1.5, 1.0, 0.5, 0.3, 0.1, 0.08])
    xs = 1.0 / np.cosh(al)
    fs = np.array([1.0587, 1.1671, 1.278, 1.4391, 1.616, 1.6682, 1.6969, 1.6982])
    ts = np.array([0.99981, 0.99711, 0.99010, 0.97419, 0.95374, 0.94769, 0.94442, 0.94427])
    b3 = wm.SHEAR_FORCE_X3
    for name, y, base, y0, m in (
        (
            "FS",
            fs,
            1 + 9 / 16 * xs + 81 / 256 * xs**2 + b3 * xs**3,
            wm.SHEAR_FORCE_CONTACT - (1 + 9 / 16 + 81 / 256 + b3),
            4,
        ),
        ("TS", ts, 1 + 0 * xs, wm.SHEAR_TORQUE_CONTACT - 1, 3),
    ):
        lgs = -np.log1p(-xs)
        a = np.array([xs ** (m + 1) - xs**m, xs ** (m + 2) - xs**m, (1 - xs) * lgs * xs**m]).T
        c, *_ = np.linalg.lstsq(a, y - base - y0 * xs**m, rcond=None)
        coef = (y0 - c[0] - c[1], c[0], c[1], c[2])
        show(name, coef)
        rest = coef[0] + coef[1] * xs + coef[2] * xs**2 + coef[3] * (1 - xs) * lgs
        fitted = base + xs**m * rest
        print(f"max error {name} against the table: {np.max(np.abs(fitted - y)):.1e}")

    # errors of the kernels as they stand (after pasting), on a denser grid
    chk = np.concatenate([np.logspace(-6, 0, 301)[1::2], np.logspace(0, 3, 81)[1::2]])
    perp, ftt, ftr, frr = exact(chk)
    for name, fn, ref in (
        ("normal", wm.normal_resistance, perp),
        ("parallel", wm.parallel_resistance, ftt),
        ("coupling", wm.coupling_resistance, ftr),
        ("rotation", wm.rotation_resistance, frr),
        ("normal push", wm.normal_push, np.array([normal_push(1.0 + e) for e in chk])),
    ):
        got = np.array([fn(e) for e in chk])
        scale = ftt if name == "coupling" else ref
        print(f"max error {name}: {np.max(np.abs(got - ref) / scale):.2e}")


if __name__ == "__main__":
    main()
