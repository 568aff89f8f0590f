"""Hydrodynamics of the beads: RPY mobility, and the sphere-wall resistances and drag near the
pillar."""
