"""Tensor internals: triangles, descriptors, canonical sparse storage, products, the builder."""

from itertools import permutations

import numpy as np
import pytest

from matchers import Problem, SparseTensor, build_tensor
from matchers.hypergraph.triangles import (
    all_triangles,
    angle_cosines,
    ordered_descriptors,
    ordered_triples,
    sample_triangles,
    signed_sines,
)


def _rotation3(rng):
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


def test_triangle_enumerations_are_complete_and_distinct():
    tri = all_triangles(7)
    assert len(tri) == 35 and np.all(tri[:, 0] < tri[:, 1]) and np.all(tri[:, 1] < tri[:, 2])
    assert len({tuple(t) for t in tri}) == 35
    ordered = ordered_triples(6)
    assert len(ordered) == 6 * 5 * 4 == len({tuple(t) for t in ordered})
    assert sample_triangles(2, 10, np.random.default_rng(0)).shape == (0, 3)


def test_sampled_triangles_are_distinct_and_seeded():
    a = sample_triangles(12, 50, np.random.default_rng(3))
    b = sample_triangles(12, 50, np.random.default_rng(3))
    assert np.array_equal(a, b) and len({tuple(t) for t in a}) == 50
    assert np.all(a[:, 0] < a[:, 1]) and np.all(a[:, 1] < a[:, 2])
    assert len(sample_triangles(5, 50, np.random.default_rng(0))) == 10  # all C(5,3)


def test_angle_cosines_of_a_right_isosceles_triangle():
    pts = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]])
    cos, valid = angle_cosines(pts, np.array([[0, 1, 2]]))
    assert valid[0]
    np.testing.assert_allclose(cos[0], [0.0, np.sqrt(0.5), np.sqrt(0.5)], atol=1e-12)


def test_signed_sines_flip_with_orientation_in_2d_and_not_in_3d():
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    ccw, _ = signed_sines(pts, np.array([[0, 1, 2]]))
    cw, _ = signed_sines(pts, np.array([[0, 2, 1]]))
    assert np.all(ccw > 0) and np.all(cw < 0)
    pts3 = np.c_[pts, np.zeros(3)]
    s3, _ = signed_sines(pts3, np.array([[0, 1, 2], [0, 2, 1]]))
    assert np.all(s3 > 0)
    np.testing.assert_allclose(s3[0], np.abs(ccw[0]))


def test_coincident_vertices_are_invalid():
    pts = np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 1.0], [2.0, 0.5]])
    _, valid = angle_cosines(pts, np.array([[0, 1, 2], [0, 2, 3]]))
    assert valid.tolist() == [False, True]


@pytest.mark.parametrize("descriptor,oriented", [(angle_cosines, False), (signed_sines, True)])
def test_ordered_descriptors_match_direct_computation(descriptor, oriented):
    pts = np.random.default_rng(1).normal(size=(6, 2))
    triples, desc, valid = ordered_descriptors(pts, descriptor, oriented)
    direct, direct_valid = descriptor(pts, triples)
    np.testing.assert_allclose(desc, direct, atol=1e-12)
    assert np.array_equal(valid, direct_valid)


@pytest.mark.parametrize("descriptor", [angle_cosines, signed_sines])
def test_descriptors_are_invariant_to_rotation_translation_scale_3d(descriptor):
    rng = np.random.default_rng(2)
    pts = rng.normal(size=(6, 3))
    moved = 3.7 * pts @ _rotation3(rng).T + rng.normal(size=3)
    tri = ordered_triples(6)
    np.testing.assert_allclose(descriptor(pts, tri)[0], descriptor(moved, tri)[0], atol=1e-9)


def test_from_entries_sorts_dedups_keeping_max_and_drops_repeats():
    t = SparseTensor.from_entries(
        [[2, 0, 1], [1, 2, 0], [0, 1, 2], [3, 3, 1], [0, 1, 3], [1, 2, 3]],
        [0.2, 0.9, 0.5, 1.0, 0.0, 0.4],
        2,
        2,
    )
    rows = {tuple(r): v for r, v in zip(t.indices.tolist(), t.values, strict=True)}
    assert rows == {(0, 1, 2): 0.9, (1, 2, 3): 0.4}


def test_from_entries_rejects_bad_input():
    with pytest.raises(ValueError, match="indices"):
        SparseTensor.from_entries([[0, 1, 9]], [1.0], 2, 2)
    with pytest.raises(ValueError, match="values"):
        SparseTensor.from_entries([[0, 1, 2]], [1.0, 2.0], 2, 2)


def test_symmetrised_holds_all_six_permutations_sorted():
    t = SparseTensor.from_entries([[0, 1, 2], [1, 2, 3]], [0.5, 0.25], 2, 2)
    idx, val = t.symmetrised()
    assert len(idx) == 12
    assert {tuple(r) for r in idx[:6].tolist()} | {tuple(r) for r in idx[6:].tolist()} == {
        p for base in ((0, 1, 2), (1, 2, 3)) for p in permutations(base)
    }
    assert np.all(np.diff(idx[:, 0]) >= 0)  # lexicographic
    dense = t.dense()
    np.testing.assert_array_equal(val, dense[idx[:, 0], idx[:, 1], idx[:, 2]])


def test_products_equal_brute_force_dense_products():
    rng = np.random.default_rng(4)
    raw = rng.integers(0, 9, size=(60, 3))
    t = SparseTensor.from_entries(raw, rng.random(60) + 0.1, 3, 3)
    dense = t.dense()
    assert np.allclose(dense, dense.transpose(1, 0, 2)) and np.allclose(
        dense, dense.transpose(2, 1, 0)
    )
    assert np.all(dense[np.arange(9), np.arange(9), :] == 0)
    x, y, z = rng.random((3, 9))
    np.testing.assert_allclose(t.product(x), np.einsum("abc,b,c->a", dense, x, x))
    np.testing.assert_allclose(t.bilinear(y, z), np.einsum("abc,b,c->a", dense, y, z))
    np.testing.assert_allclose(2 * t.degrees(), dense.sum(axis=(1, 2)))
    np.testing.assert_allclose(t.value(x), np.einsum("abc,a,b,c->", dense, x, x, x))
    mask = rng.random(9) < 0.5
    ym, zm = y * mask, z * mask
    np.testing.assert_allclose(t.restricted(mask).bilinear(ym, zm), t.bilinear(ym, zm))


def _problem(n, m, dim=2, seed=0, noise=0.0):
    rng = np.random.default_rng(seed)
    p1 = rng.normal(size=(n, dim))
    p2 = np.concatenate(
        [
            p1[: min(n, m)] + noise * rng.normal(size=(min(n, m), dim)),
            rng.normal(size=(m - min(n, m), dim)),
        ]
    )
    return Problem(p1, p2)


@pytest.mark.parametrize("recipe", ["paper", "duchenne"])
def test_builder_entries_are_unique_and_sized_as_documented(recipe):
    problem = _problem(7, 9, seed=5)
    t = build_tensor(problem, recipe, 0)
    assert t.info["triangles"] == 35  # C(7, 3) <= 7*9: all triangles of the smaller view
    assert t.info["neighbours"] == 63 and t.info["entries_raw"] == 35 * 63
    again = SparseTensor.from_entries(t.indices, t.values, 7, 9)  # full de-duplication
    assert again.nnz == t.nnz == 35 * 63
    i, j = np.divmod(t.indices, 9)
    assert np.all((i[:, 0] != i[:, 1]) & (i[:, 1] != i[:, 2]) & (i[:, 0] != i[:, 2]))
    assert np.all((j[:, 0] != j[:, 1]) & (j[:, 1] != j[:, 2]) & (j[:, 0] != j[:, 2]))
    assert np.all((t.values > 0) & (t.values <= 1))


def test_paper_value_is_eq1_of_the_matched_vertex_pairs():
    problem = _problem(5, 5, seed=6, noise=0.05)
    t = build_tensor(problem, "paper", 0, neighbours=10_000)  # every ordered triple
    tri = np.array([0, 2, 4])
    target = (1, 3, 0)  # view-2 vertices matched to 0, 2, 4
    key = sorted(int(a) for a in tri * 5 + np.array(target))
    row = np.flatnonzero(np.all(np.sort(t.indices, axis=1) == key, axis=1))
    assert len(row) == 1
    c1, _ = angle_cosines(problem.points1, tri[None])
    c2, _ = angle_cosines(problem.points2, np.array([target]))
    np.testing.assert_allclose(t.values[row[0]], np.exp(-np.abs(c1 - c2).sum() / 0.5))


def test_builder_swaps_views_when_view_2_is_smaller_and_is_seeded():
    big, small = _problem(9, 6, seed=7), _problem(6, 9, seed=7)
    t = build_tensor(big, "paper", 1)
    assert t.info["triangles"] == 20 and t.n == 9 and t.m == 6  # C(6, 3) of view 2
    assert t.indices.max() < 54
    a, b = (
        build_tensor(small, "duchenne", 3, triangles=10),
        build_tensor(small, "duchenne", 3, triangles=10),
    )
    assert np.array_equal(a.indices, b.indices) and np.array_equal(a.values, b.values)


def test_builder_gives_empty_tensors_for_tiny_or_degenerate_views():
    assert build_tensor(_problem(2, 8), "paper").nnz == 0
    assert build_tensor(Problem(np.zeros((5, 3)), np.zeros((5, 3))), "duchenne").nnz == 0


def test_builder_rejects_unknown_recipe_and_bad_counts():
    with pytest.raises(ValueError, match="tensor"):
        build_tensor(_problem(4, 4), "bogus")
    with pytest.raises(ValueError, match="neighbours"):
        build_tensor(_problem(4, 4), "paper", neighbours=0)
