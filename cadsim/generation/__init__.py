"""Dataset generation: episodes of simulation -> observed frame pairs -> records, and the executors it runs on."""
