"""T-type topology tests: closed-loop simulator, plant, metrics, plots."""
