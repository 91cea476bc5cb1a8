"""eval: metrics, experiment runner, tables and figures for cadsim datasets and matchers."""
