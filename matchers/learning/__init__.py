"""Learned pairwise affinities: candidate-pair features, the model file, training."""
