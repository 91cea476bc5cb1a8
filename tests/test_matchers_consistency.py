"""``consistency``: the largest mutually consistent set of candidate matches, no prior needed."""

import numpy as np
import pytest

from matchers import Problem, get
from matchers.consistency import consistency_weights, consistent_set, greedy_cliques
from matchers.core.indexing import conflict_mask, match_index


def planted(seed, inliers=8, outliers1=6, outliers2=5, noise=0.02):
    """View 2 holds view 1's first ``inliers`` objects after a 3-D rigid motion (+ noise), and
    its own outliers; view 1 has outliers too. Both shuffled. Returns (problem, truth)."""
    rng = np.random.default_rng(seed)
    p1 = rng.uniform(0, 40, (inliers + outliers1, 3))
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))
    moved = p1[:inliers] @ q.T + rng.normal(size=3) * 20 + noise * rng.normal(size=(inliers, 3))
    p2 = np.vstack([moved, rng.uniform(0, 40, (outliers2, 3)) @ q.T])
    perm1, perm2 = rng.permutation(len(p1)), rng.permutation(len(p2))
    inv1, inv2 = np.argsort(perm1), np.argsort(perm2)
    truth = {(int(inv1[k]), int(inv2[k])) for k in range(inliers)}
    return Problem(p1[perm1], p2[perm2]), truth


@pytest.mark.parametrize("seed", range(5))
def test_consistency_recovers_a_planted_consistent_set_among_outliers(seed):
    problem, truth = planted(seed)
    matching = get("consistency")(problem, threshold=0.5, tolerance_scale=0.03)
    assert {(int(i), int(j)) for i, j in matching.pairs} == truth
    assert matching.info["clique"] == len(truth)
    members = [matching.scores[i, j] for i, j in truth]
    assert min(members) > 0.9  # each member agrees with (nearly) all the others
    assert matching.name == "consistency"


def test_consistency_ignores_features_and_the_prior():
    problem, _ = planted(1)
    rng = np.random.default_rng(0)
    dressed = Problem(
        problem.points1,
        problem.points2,
        rng.random((problem.n1, 4)),
        rng.random((problem.n2, 4)),
        world1=np.zeros((problem.n1, 3)),
        world2=np.zeros((problem.n2, 3)),
        world_sigma=1.0,
    )
    np.testing.assert_array_equal(
        get("consistency")(problem).scores, get("consistency")(dressed).scores
    )


def test_relative_and_absolute_tolerance_agree():
    problem, _ = planted(2)
    from matchers.core.scale import median_spacing

    spacing = median_spacing(problem.points1, problem.points2)
    rel = get("consistency")(problem, tolerance_scale=0.07)
    absolute = get("consistency")(problem, tolerance=0.07 * spacing)
    np.testing.assert_array_equal(rel.scores, absolute.scores)


def test_consistency_weights_and_graph():
    p1 = np.array([[0.0, 0, 0], [3.0, 0, 0], [0.0, 4.0, 0]])
    p2 = np.array([[0.0, 0, 0], [3.1, 0, 0]])
    w = consistency_weights(Problem(p1, p2), tolerance=0.5)
    a, b = match_index(0, 0, 2), match_index(1, 1, 2)  # edge 3.0 vs 3.1
    assert w[a, b] == pytest.approx(np.exp(-2 * (0.1 / 0.5) ** 2)) and w[a, b] == w[b, a]
    assert w[match_index(2, 0, 2), match_index(0, 1, 2)] == 0.0  # 4.0 vs 3.1: inconsistent
    assert np.all(w[conflict_mask(3, 2)] == 0)


def test_greedy_cliques_grow_every_start_to_a_maximal_clique():
    adjacent = np.zeros((5, 5), dtype=bool)
    for a, b in [(0, 1), (0, 2), (1, 2), (3, 4), (2, 3)]:
        adjacent[a, b] = adjacent[b, a] = True
    cliques = greedy_cliques(adjacent, np.array([0.1, 0.2, 0.3, 0.9, 0.8]), np.array([0, 3]))
    assert cliques[0].tolist() == [True, True, True, False, False]
    assert cliques[1].tolist() == [False, False, False, True, True]
    weights = adjacent.astype(float)
    assert consistent_set(weights).tolist() == [True, True, True, False, False]  # largest wins


@pytest.mark.parametrize(
    ("option", "value"), [("tolerance_scale", 0.0), ("tolerance", -1.0), ("starts", 0)]
)
def test_bad_consistency_options_are_named(option, value):
    problem, _ = planted(0)
    with pytest.raises(ValueError, match=option):
        get("consistency")(problem, **{option: value})


def _faulty_exp(monkeypatch, seed: int) -> None:
    """np.exp whose float64 results move up by one ulp at seeded places (another CPU's SIMD
    exp, as tests/cpu_dispatch.py injects it)."""
    real = np.exp
    rng = np.random.default_rng(seed)

    def exp(x, *args, **kwargs):
        out = np.asarray(real(x, *args, **kwargs))
        if out.dtype == np.float64 and out.size:
            moved = rng.random(out.shape) < 0.5
            out = np.where(moved, np.nextafter(out, np.inf), out)
        return out

    monkeypatch.setattr(np, "exp", exp)


def test_mirror_tied_cliques_are_decided_the_same_way_whatever_the_last_bits(monkeypatch):
    """View 2 holds two objects 6 m apart; view 1 two objects 5.9 m apart and distractors: the
    cliques {(0, 0), (1, 1)} and {(0, 1), (1, 0)} are exactly tied (mirror images). With
    last-bit noise in exp the tie must still go the same way (canonical W, u and clique
    weights, ties by index)."""
    from matchers import Problem, get

    view1 = np.array([[0, 0, 10], [5.9, 0, 10], [40, 0, 60], [-30, 0, 55]], dtype=float)
    view2 = np.array([[1, 0, 12], [7, 0, 12]], dtype=float)
    problem = Problem(view1, view2)
    want = get("consistency")(problem, tolerance=0.5)
    for seed in range(12):
        with monkeypatch.context() as m:
            _faulty_exp(m, seed)
            got = get("consistency")(problem, tolerance=0.5)
        assert got.pairs.tolist() == want.pairs.tolist(), seed
        assert np.array_equal(got.scores, want.scores), seed
