"""Intra-cluster correlation: exact on a hand-made case, recovers a planted between-cluster share
of the variance, is near 0 without cluster effects and 1 when clusters hold identical items."""

from __future__ import annotations

import numpy as np
import pytest

from eval.protocol.cluster_correlation import design_effect, intra_cluster_correlation


def test_a_hand_computed_case():
    # clusters {1, 3} and {5, 7, 9}, grand mean 5: MSB = (2·(2 − 5)² + 3·(7 − 5)²) / 1 = 30,
    # MSW = (2 + 8) / 3, n0 = (5 − 13 / 5) / 1 = 2.4
    values = np.array([1.0, 3.0, 5.0, 7.0, 9.0])
    labels = np.array(["a", "a", "b", "b", "b"])
    msb, msw, n0 = 30.0, 10 / 3, 2.4
    expected = (msb - msw) / (msb + (n0 - 1) * msw)
    assert intra_cluster_correlation(values, labels) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("between_sd, expected", [(0.1, 0.5), (0.05, 0.2), (0.0, 0.0)])
def test_recovers_a_planted_share_of_the_variance(between_sd, expected):
    rng = np.random.default_rng(4)
    clusters, per, within_sd = 2000, 4, 0.1
    effect = rng.normal(0, between_sd, size=clusters) if between_sd else np.zeros(clusters)
    values = np.repeat(effect, per) + rng.normal(0, within_sd, size=clusters * per)
    icc = intra_cluster_correlation(values, np.repeat(np.arange(clusters), per))
    assert icc == pytest.approx(expected, abs=0.03)


def test_identical_items_within_clusters_and_degenerate_input():
    values = np.repeat([0.2, 0.9, 0.4], 3)
    assert intra_cluster_correlation(values, np.repeat([0, 1, 2], 3)) == pytest.approx(1.0)
    assert np.isnan(intra_cluster_correlation(np.arange(3.0), np.arange(3)))  # singletons only
    assert np.isnan(intra_cluster_correlation(np.ones(4), np.array([0, 0, 1, 1])))  # no variance
    with pytest.raises(ValueError, match="clusters"):
        intra_cluster_correlation(np.zeros(3), np.zeros(4))


def test_design_effect():
    assert design_effect(0.0, 5) == 1.0
    assert design_effect(1.0, 5) == 5.0
    assert design_effect(0.25, 3) == pytest.approx(1.5)
