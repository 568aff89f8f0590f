"""Resolved rigid particles (spheres, short rods) two-way coupled to a D3Q19 lattice Boltzmann flow.

A reference for the one-way fiber models: the particle is a moving no-slip
boundary of the lattice (interpolated bounce-back, momentum-exchange force and
torque, refilling of uncovered nodes), force- and torque-free or held, in a
box with walls, a pillar and periodic or shifted-periodic faces. Only tests,
scripts and (later) the CLI import it; see docs/validation/resolved.md.
"""
