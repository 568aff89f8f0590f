"""Steady 3D Stokes flow past the pillar: D3Q19 lattice Boltzmann, FlowField, cache."""

from fibersweep.numba_cache import sync_kernel_cache

sync_kernel_cache()  # before any cached kernel loads: drop caches of older sources
