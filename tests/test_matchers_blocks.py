"""Shared building blocks: appearance similarity, pairwise affinity, Sinkhorn, discretisation,
index convention, score normalisation."""

import numpy as np
import pytest

from matchers import Problem
from matchers.blocks.appearance_similarity import appearance_similarity
from matchers.blocks.pairwise import pairwise_affinity
from matchers.blocks.sinkhorn import sinkhorn
from matchers.core.discretise import discretise
from matchers.core.indexing import conflict_mask, from_column_major, match_index, to_column_major
from matchers.core.result import max_normalised


def test_appearance_similarity_is_clipped_cosine():
    f1 = np.array([[1.0, 0.0], [1.0, 1.0], [0.0, 0.0]])
    f2 = np.array([[2.0, 0.0], [-1.0, 0.0]])
    b = appearance_similarity(Problem(np.zeros((3, 2)), np.zeros((2, 2)), f1, f2))
    np.testing.assert_allclose(b, [[1.0, 0.0], [np.sqrt(0.5), 0.0], [0.0, 0.0]])


def test_no_features_means_uniform_appearance():
    assert np.array_equal(
        appearance_similarity(Problem(np.zeros((3, 3)), np.ones((4, 3)))), np.ones((3, 4))
    )


def test_pairwise_affinity_values_conflicts_and_index_convention():
    p1 = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 2.0]])
    p2 = np.array([[0.0, 0.0], [0.0, 1.5]])
    m = pairwise_affinity(Problem(p1, p2), sigma2=0.5)
    a, b = match_index(0, 0, 2), match_index(1, 1, 2)  # edges 0-1 (length 1) and 0-1 (1.5)
    assert m[a, b] == pytest.approx(np.exp(-(0.5**2) / 0.5))
    assert np.all(m[conflict_mask(3, 2)] == 0)
    np.testing.assert_allclose(m, m.T)


def test_column_major_conversion_round_trips():
    rng = np.random.default_rng(0)
    k = rng.random((6, 6))
    col = to_column_major(k, 2, 3)
    # our a = i*3 + j; theirs a' = j*2 + i
    assert col[1 * 2 + 0, 2 * 2 + 1] == k[0 * 3 + 1, 1 * 3 + 2]
    np.testing.assert_array_equal(from_column_major(col, 2, 3), k)


def test_sinkhorn_square_is_bistochastic():
    mat = np.random.default_rng(1).random((5, 5)) + 0.1
    out, _ = sinkhorn(mat, max_iter=1000, tol=1e-9)
    np.testing.assert_allclose(out.sum(axis=0), 1, atol=1e-8)
    np.testing.assert_allclose(out.sum(axis=1), 1, atol=1e-8)


def test_sinkhorn_slack_lets_unmatched_columns_shed_mass():
    mat = np.array([[50.0, 1.0, 1.0], [1.0, 50.0, 1.0]])  # column 2 has no good partner
    out, _ = sinkhorn(mat, max_iter=1000, tol=1e-9)
    np.testing.assert_allclose(out.sum(axis=1), 1, atol=1e-6)  # smaller side: rows sum 1
    assert np.all(out.sum(axis=0) <= 1 + 1e-6)
    plain, _ = sinkhorn(mat, max_iter=1000, tol=1e-9, slack=False)
    np.testing.assert_allclose(plain.sum(axis=0), 2 / 3, atol=1e-6)
    assert out[:, 2].sum() < 0.5 * plain[:, 2].sum() and out[0, 0] > plain[0, 0]


def test_discretise_full_and_thresholded():
    scores = np.array([[0.9, 0.1, 0.0], [0.2, 0.3, 0.25]])
    assert discretise(scores).tolist() == [[0, 0], [1, 1]]
    assert discretise(scores, threshold=0.5).tolist() == [[0, 0]]
    assert discretise(scores, threshold=0.3).tolist() == [[0, 0], [1, 1]]  # >= keeps
    assert discretise(np.zeros((0, 4))).shape == (0, 2)
    with pytest.raises(ValueError, match="threshold"):
        discretise(scores, threshold=float("nan"))


def test_max_normalised_scores():
    np.testing.assert_allclose(
        max_normalised(np.array([1.0, 4.0, -1.0, 2.0]), 2, 2), [[0.25, 1], [0, 0.5]]
    )
    assert np.all(max_normalised(np.zeros(4), 2, 2) == 0)
    assert np.all(max_normalised(np.array([np.nan, 1.0]), 1, 2) == [[0.0, 1.0]])
