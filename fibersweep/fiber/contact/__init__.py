"""Fiber-pillar contact: the soft-core pair law, the rough and smooth pillar outlines."""
