"""Running: run specs and tasks, the runner and its cache, executors, thinning (a run's transformation of a pair), atomic result files."""
