"""fibersweep.fiber."""
