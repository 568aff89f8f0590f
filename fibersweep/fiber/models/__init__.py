"""The fiber's body: rigid and bead-spring models, their forces, spacing and deformation."""
