"""Time steppers of the bead-spring fiber: BDF2 and the Rosenbrock-W methods with their LU solve."""
