"""The matcher contract and its infrastructure: the problem, the result, options, the registry, the memory budget, compiled-kernel support, the shared discretisation."""
