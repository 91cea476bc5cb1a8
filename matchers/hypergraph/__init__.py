"""The third-order tensor: triangle sampling, the tensor build, the sparse tensor and its products, sharing one search between matchers."""
