"""Hydrodynamics of the beads: RPY mobility, and the sphere-wall resistances near the pillar."""
