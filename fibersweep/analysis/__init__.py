"""fibersweep.analysis."""
