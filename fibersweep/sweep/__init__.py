"""fibersweep.sweep."""
