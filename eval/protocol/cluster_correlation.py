"""How alike the frame pairs of one cluster are: the intra-cluster correlation (ICC) of a per-pair
value (F1, a paired difference) and the design effect it implies.

``intra_cluster_correlation``: ICC(1) of the one-way random-effects ANOVA, unequal cluster sizes
allowed (Donner 1986): with G clusters, N items, MSB = Σ_g n_g (ȳ_g − ȳ)² / (G − 1), MSW =
Σ_g Σ_i (y_gi − ȳ_g)² / (N − G) and n₀ = (N − Σ_g n_g² / N) / (G − 1),

    ICC = (MSB − MSW) / (MSB + (n₀ − 1) · MSW),

the share of the variance that lies between clusters (negative estimates are possible when
clusters are less alike than chance). ``design_effect`` = 1 + (n̄ − 1) · ICC: how many times the
variance of a mean exceeds that of as many independent items, so N items in clusters of n̄ are
worth N / design effect independent ones. ICC near 0 justifies treating the items (or smaller
groups of them, such as snapshots far apart in one simulation) as separate clusters; a large one
says that only more clusters, not more pairs per cluster, narrow an interval.
"""

from __future__ import annotations

import numpy as np


def intra_cluster_correlation(values: np.ndarray, clusters: np.ndarray) -> float:
    """ICC(1) of per-item ``values`` grouped by ``clusters`` (one label per item; module
    docstring). NaN with fewer than two clusters, with no cluster of two or more items, or
    with no variance at all."""
    values = np.asarray(values, dtype=float).reshape(-1)
    labels, index = np.unique(np.asarray(clusters).reshape(-1), return_inverse=True)
    if len(values) != len(index):
        raise ValueError(f"clusters: {len(index)} labels for {len(values)} values")
    groups, count = len(labels), len(values)
    if groups < 2 or count <= groups:
        return float("nan")
    sizes = np.bincount(index, minlength=groups).astype(float)
    means = np.bincount(index, weights=values, minlength=groups) / sizes
    between = (sizes * (means - values.mean()) ** 2).sum() / (groups - 1)
    within = ((values - means[index]) ** 2).sum() / (count - groups)
    n0 = (count - (sizes**2).sum() / count) / (groups - 1)
    denominator = between + (n0 - 1) * within
    return float((between - within) / denominator) if denominator > 0 else float("nan")


def design_effect(icc: float, mean_cluster_size: float) -> float:
    """1 + (n̄ − 1) · ICC: the variance inflation of a mean over clusters of ``mean_cluster_size``."""
    return 1.0 + (float(mean_cluster_size) - 1.0) * float(icc)
