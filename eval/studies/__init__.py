"""Studies built on the evaluation: the evaluation itself, the external benchmark, ranking agreement, dataset spread, regime cards."""
