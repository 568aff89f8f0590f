"""The fiber's body: the rigid and bead-spring models, the elastic rod, forces, spacing, registry
and deformation."""
