"""fibersweep.discrepancy."""
