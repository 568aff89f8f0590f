"""Analysis of pillar-array results: critical lengths, refinement, modes, the designer's answer."""
