"""Terms and solvers several algorithms share: pairwise and appearance affinities, the localisation prior, rigid alignment, Sinkhorn, memory models."""
