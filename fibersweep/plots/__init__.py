"""fibersweep.plots."""
