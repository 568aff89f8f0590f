"""Benchmark of the D3Q19 kernel against the machine's memory-bandwidth roofline.

Prints, measured in one run so that the ratios are meaningful on a shared or
noisy machine:

- the memory bandwidth of a large stream copy (numpy, and a Numba prange copy
  with 1 and N threads), counted as bytes read + bytes written;
- the MLUPS of the LBM steps (kernel + pillar fix-ups) on the full channel at
  dx = 4 µm (half depth: 600 x 200 x 5 = 600 k cells), with 1 and N threads,
  for the in-place AA kernel (default) and the two-array pull kernel;
- the fraction of the roofline reached: bandwidth / bytes per cell update;
- the AA kernel with the interpolated pillar (sub-grid link tables) against
  the staircase pillar, same run, as a ratio.
  AA: 19 x 4 B read + 19 x 4 B written in place (152 B). Pull: the same plus
  19 x 4 B of write-allocate reads of the second array (228 B).

Usage: python scripts/benchmarks/bench_lbm.py [--steps 30] [--dx 4]
"""

from __future__ import annotations

import argparse
import time

import numba
import numpy as np

from fibersweep.flow.cuts import pillar_cuts
from fibersweep.flow.lattice import make_grid
from fibersweep.flow.steppers import make_stepper
from fibersweep.units import Geometry

#: Arguments of a run of seconds (scripts/benchmarks/run.py --smoke): the script runs
#: end to end, its numbers mean nothing.
SMOKE = ["--steps", "2", "--mbytes", "8"]


@numba.njit(parallel=True, cache=True)
def _copy(a: np.ndarray, b: np.ndarray) -> None:
    for i in numba.prange(a.shape[0]):
        b[i] = a[i]


def _best(fn, repeat: int) -> float:
    fn()
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def bandwidth(nbytes: int, threads: int | None) -> float:
    """Stream-copy bandwidth [GB/s], read + write bytes."""
    a = np.ones(nbytes // 4, dtype=np.float32)
    b = np.empty_like(a)
    if threads is None:
        dt = _best(lambda: np.copyto(b, a), 5)
    else:
        numba.set_num_threads(threads)
        dt = _best(lambda: _copy(a, b), 5)
    return 2 * a.nbytes / dt / 1e9


def mlups(dx: float, steps: int, threads: int, kernel: str, boundary: str = "staircase") -> float:
    """Cell updates per second of ``kernel`` ("aa" or "pull") incl. its pillar fix-ups."""
    numba.set_num_threads(threads)
    closed = boundary != "staircase"
    grid = make_grid(Geometry(), dx, symmetry=True, closed=closed)
    cuts = pillar_cuts(grid, Geometry().vertices, boundary)
    shape = (grid.nz, grid.ny, grid.nx)
    u0 = np.zeros((3, *shape))
    stepper = make_stepper(
        kernel, grid, u0, np.zeros(shape), np.zeros((3, 3, *shape)), 1e-6, 1.25, 1.1, cuts=cuts
    )
    steps += steps % 2
    dt = _best(lambda: stepper.advance(steps), 3)
    return grid.cells * steps / dt / 1e6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=30)
    ap.add_argument("--dx", type=float, default=4.0)
    ap.add_argument("--mbytes", type=int, default=512, help="size of each copied array [MB]")
    args = ap.parse_args()
    n_max = numba.config.NUMBA_NUM_THREADS
    threads = sorted({1, n_max})
    nbytes = args.mbytes * 2**20
    print(f"machine: {n_max} threads available to Numba")
    bw_np = bandwidth(nbytes, None)
    print(f"stream copy, numpy:            {bw_np:7.1f} GB/s (read + write)")
    bws = {}
    for t in threads:
        bws[t] = bandwidth(nbytes, t)
        print(f"stream copy, numba {t} thread(s): {bws[t]:7.1f} GB/s")
    print(f"numba threading layer: {numba.threading_layer()}")
    bw = max([bw_np, *bws.values()])
    grid = make_grid(Geometry(), args.dx, symmetry=True)
    print(f"LBM grid: {grid.nx} x {grid.ny} x {grid.nz} = {grid.cells / 1e6:.2f} M cells, float32")
    for kernel, nbytes_cell in (("aa", 152), ("pull", 228)):
        for t in threads:
            m = mlups(args.dx, args.steps, t, kernel)
            bw_t = bws[t]
            print(
                f"LBM {kernel:4s} {t} thread(s): {m:7.1f} MLUPS; roofline {nbytes_cell} B/cell "
                f"at {bw_t:.1f} GB/s = {bw_t * 1e3 / nbytes_cell:6.1f} MLUPS -> "
                f"{m * nbytes_cell / (bw_t * 1e3):5.1%}"
            )
    print(f"best measured bandwidth {bw:.1f} GB/s")
    for t in threads:
        stair = mlups(args.dx, args.steps, t, "aa", "staircase")
        interp = mlups(args.dx, args.steps, t, "aa", "interpolated")
        print(
            f"LBM aa   {t} thread(s): staircase pillar {stair:7.1f} MLUPS, interpolated "
            f"{interp:7.1f} MLUPS (ratio {interp / stair:.3f})"
        )


if __name__ == "__main__":
    main()
