"""Benchmark of the D3Q19 kernel against the machine's memory-bandwidth roofline.

Prints, measured in one run so that the ratios are meaningful on a shared or
noisy machine:

- the memory bandwidth of a large stream copy (numpy, and a Numba prange copy
  with 1 and N threads), counted as bytes read + bytes written;
- the MLUPS of one LBM step (stream_collide + pillar fill) on the SPEC channel
  at dx = 4 µm (half depth: 600 x 200 x 5 = 600 k cells), with 1 and N threads;
- the fraction of the roofline reached: bandwidth / bytes per cell update.
  The kernel streams between two float32 arrays: 19 x 4 B read + 19 x 4 B
  written, plus 19 x 4 B of write-allocate reads when stores are not
  streaming stores (228 B); 152 B is the ideal in-place figure.

Usage: python scripts/bench_lbm.py [--steps 30] [--dx 4]
"""

from __future__ import annotations

import argparse
import time

import numba
import numpy as np

from fibersweep.flow import kernels
from fibersweep.flow.lattice import boundary_links, make_grid, pull_sources
from fibersweep.units import Geometry


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


def mlups(dx: float, steps: int, threads: int) -> float:
    numba.set_num_threads(threads)
    grid = make_grid(Geometry(), dx, symmetry=True)
    links, cells = boundary_links(grid)
    src = pull_sources(grid)
    g = np.zeros(grid.padded_shape, dtype=np.float32)
    gn = np.zeros_like(g)

    def run() -> None:
        nonlocal g, gn
        for _ in range(steps):
            kernels.stream_collide(g, gn, src, 1e-6, 1.25, 1.1)
            kernels.fill_pillar(gn, cells, links)
            g, gn = gn, g

    dt = _best(run, 3)
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
    for t in threads:
        m = mlups(args.dx, args.steps, t)
        bw_t = max(bws[t], bw_np if t == n_max else bws[t])
        print(
            f"LBM {t} thread(s): {m:7.1f} MLUPS; roofline at {bw_t:.1f} GB/s: "
            f"{bw_t * 1e3 / 228:6.1f} MLUPS (228 B/cell) -> {m * 228 / (bw_t * 1e3):5.1%}, "
            f"{bw_t * 1e3 / 152:6.1f} MLUPS (152 B/cell) -> {m * 152 / (bw_t * 1e3):5.1%}"
        )
    print(f"best measured bandwidth {bw:.1f} GB/s")


if __name__ == "__main__":
    main()
