"""Steady 3D Stokes flow past the pillar: D3Q19 lattice Boltzmann, FlowField, cache."""
