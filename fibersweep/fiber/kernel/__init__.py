"""What every fiber kernel shares: typed input bundles, effect stages, the record and stop rule."""
