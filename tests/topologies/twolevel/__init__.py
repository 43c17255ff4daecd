"""Two-level topology tests: closed-loop simulator, plant, metrics, plots, tables."""
