"""Maximin (Algorithm 1, Eqs. 5-8) on a tiny hand-checkable case, plus solver-specific checks of
the baselines (HGM projection, TM normalisation, BCAGM fixed point, RRWM/RRWHM walks)."""

import numpy as np
import pytest

from matchers import Problem, SparseTensor, get
from matchers.bcagm import bcagm_solve, best_assignment
from matchers.blocks.sinkhorn import sinkhorn
from matchers.hgm import nearest_substochastic_kl
from matchers.maximin import appearance_jump, maximin_iterate, worst_case_tensor
from matchers.tm import normalise_l2

# 3 vs 3 objects, matches a = i*3 + j. Right matching (0,0),(1,1),(2,2) = matches 0, 4, 8;
# wrong matching (0,1),(1,2),(2,0) = matches 1, 5, 6.
RIGHT, WRONG = (0, 4, 8), (1, 5, 6)
B = np.array([[1.0, 0.2, 0.5], [0.5, 1.0, 0.2], [0.2, 0.5, 1.0]]).reshape(-1)


def tiny_tensor(right=1.0, wrong=0.5):
    return SparseTensor.from_entries([RIGHT, WRONG], [right, wrong], 3, 3)


def test_eq5_eq6_worst_case_tensor_by_hand():
    p = worst_case_tensor(tiny_tensor(), B)
    values = {tuple(sorted(r)): v for r, v in zip(p.indices.tolist(), p.values, strict=True)}
    # Eq. 5: T' = T * min(b): 1.0 * min(1, 1, 1) = 1 and 0.5 * min(.2, .2, .2) = 0.1
    # Eq. 6: max_a sum_{b,c} T'[a,b,c] = 2 * 1 (the 2 orders of the other two slots) = 2
    assert values == pytest.approx({RIGHT: 0.5, WRONG: 0.05})
    assert (2 * p.degrees()).max() == pytest.approx(1.0)  # P is "stochastic" in mode 1


def test_eq7_jump_is_bistochastic_exp_of_scaled_x_times_b():
    x = np.linspace(1, 2, 9)
    z = appearance_jump(x, B, 3, 3, beta=1.0, sinkhorn_iter=1000).reshape(3, 3)
    raw = np.exp((x * B) / (x * B).max()).reshape(3, 3)
    np.testing.assert_allclose(z.sum(axis=0), 1, atol=1e-3)
    np.testing.assert_allclose(z.sum(axis=1), 1, atol=1e-3)
    ratio = z / raw  # Sinkhorn only rescales rows and columns: ratio is rank one
    np.testing.assert_allclose(ratio / ratio[0], np.tile(ratio[:, :1] / ratio[0, 0], 3), rtol=1e-9)


@pytest.mark.parametrize("normalise", ["none", "sum"])
def test_eq8_one_step_by_hand(normalise):
    p = worst_case_tensor(tiny_tensor(), B)
    u = np.full(9, 1 / 9)
    x1, iterations, converged = maximin_iterate(
        p, B, u, alpha=0.3, max_iter=1, tol=0.0, normalise=normalise
    )
    assert iterations == 1 and not converged
    walk = np.zeros(9)
    walk[list(RIGHT)] = 2 * 0.5 / 81  # sum_{b,c} P[a,b,c] u_b u_c = u^2 * (row sum of P)
    walk[list(WRONG)] = 2 * 0.05 / 81
    z, _ = sinkhorn(np.exp(B / B.max()).reshape(3, 3), 100)
    z = z.reshape(-1)
    if normalise == "sum":
        expected = 0.3 * walk / walk.sum() + 0.7 * z / z.sum()
        expected /= expected.sum()
    else:
        expected = 0.3 * walk + 0.7 * z
    np.testing.assert_allclose(x1, expected, rtol=1e-12)


def test_convergence_test_and_iteration_cap():
    p = worst_case_tensor(tiny_tensor(), B)
    u = np.full(9, 1 / 9)
    x, its, converged = maximin_iterate(p, B, u, max_iter=500, tol=1e-10)
    assert converged and its < 500 and x.sum() == pytest.approx(1.0)
    x_next, _, _ = maximin_iterate(p, B, x, max_iter=1, tol=0.0)
    assert np.abs(x_next - x).sum() < 1e-10 * 10  # a fixed point of Eqs. 7-8
    _, its, converged = maximin_iterate(p, B, u, max_iter=3, tol=0.0)
    assert its == 3 and not converged


def _features(spread):
    f = np.eye(3) + spread
    return f, f.copy()


def test_worst_case_appearance_overrides_a_stronger_wrong_hyperedge():
    tensor = tiny_tensor(right=0.6, wrong=1.0)  # the wrong triangle pair is more similar
    pts = np.random.default_rng(0).normal(size=(3, 2))
    plain = Problem(pts, pts)
    right = {(0, 0), (1, 1), (2, 2)}
    wrong = {(0, 1), (1, 2), (2, 0)}
    as_set = lambda m: {tuple(map(int, p)) for p in m.pairs}  # noqa: E731
    assert as_set(get("rrwhm")(plain, tensor=tensor)) == wrong
    assert as_set(get("maximin")(plain, tensor=tensor)) == wrong  # b = 1: no worst case
    with_features = Problem(pts, pts, *_features(0.3))  # cos = 1 on the diagonal, 0.47 off it
    assert as_set(get("maximin")(with_features, tensor=tensor)) == right


def test_maximin_inits_are_seeded_and_valid():
    pts = np.random.default_rng(1).normal(size=(6, 3))
    problem = Problem(pts, pts[::-1])
    for init in ("uniform", "appearance", "random"):
        a = get("maximin")(problem, seed=3, init=init)
        b = get("maximin")(problem, seed=3, init=init)
        assert np.array_equal(a.scores, b.scores)
        assert {tuple(p) for p in a.pairs.tolist()} == {(i, 5 - i) for i in range(6)}


def test_hgm_projection_meets_its_constraints():
    y = np.random.default_rng(2).random((4, 6)) + 0.01
    z, _, converged = nearest_substochastic_kl(y, total=4.0, tol=1e-6)
    assert converged
    assert z.sum() == pytest.approx(4.0)
    assert z.sum(axis=1).max() <= 1 + 1e-6 and z.sum(axis=0).max() <= 1 + 1e-6
    zero, _, _ = nearest_substochastic_kl(np.zeros((2, 2)), 2.0)
    assert np.all(zero == 0)


def test_tm_doubly_normalisation_is_sequential():
    x = np.random.default_rng(3).random(12) + 0.1
    out = normalise_l2(x, 3, 4, "doubly", rounds=200).reshape(3, 4)
    np.testing.assert_allclose(np.linalg.norm(out, axis=0), 1, atol=1e-6)
    rows = normalise_l2(x, 3, 4, "rows").reshape(3, 4)
    np.testing.assert_allclose(np.linalg.norm(rows, axis=1), 1)


def test_bcagm_returns_a_homogeneous_fixed_point():
    from matchers import build_tensor

    rng = np.random.default_rng(4)
    p1 = rng.normal(size=(8, 2))
    problem = Problem(p1, p1 + 0.2 * rng.normal(size=(8, 2)))
    tensor = build_tensor(problem, "duchenne", 0)
    x, sweeps, info = bcagm_solve(tensor)
    assert info["converged"] and sweeps >= 1 and x.sum() == 8 and set(np.unique(x)) <= {0, 1}
    # homogeneous point: its own block update gives it back
    grad = 3 * 8 * tensor.with_values(tensor.values / (6 * tensor.values.sum())).product(x)
    grad += info["alpha"] * 8 * x / 3 * 3
    assert np.array_equal(best_assignment(grad, 8, 8), x)


def test_walks_put_their_mass_on_the_right_matching():
    pts = np.random.default_rng(5).normal(size=(3, 2))
    problem = Problem(pts, pts)
    for name in ("rrwhm", "mos", "maximin", "tm", "hgm", "bcagm"):
        m = get(name)(problem, tensor=tiny_tensor(right=1.0, wrong=0.2))
        assert {tuple(p) for p in m.pairs.tolist()} == {(0, 0), (1, 1), (2, 2)}, name
