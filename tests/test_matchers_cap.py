"""Bounded size: the tensor cap, the sparse pairwise affinity and the fused products."""

import functools

import numpy as np
import pytest
import scipy.sparse as sp

from matchers import Problem, SparseTensor, build_tensor, get
from matchers.blocks.pairwise import pairwise_affinity, resolve_affinity, sparse_pairwise_affinity
from matchers.hypergraph import tensor_build
from matchers.hypergraph.tensor_build import MAX_ENTRIES
from matchers.hypergraph.tensor_product import FUSE_AFTER


def _problem(n, m, dim=3, seed=0, noise=0.05, features=True):
    """View 2 = a shuffled noisy copy of the first min(n, m) objects of view 1 plus outliers."""
    rng = np.random.default_rng(seed)
    p1 = rng.uniform(0, 10, (n, dim))
    common = min(n, m)
    p2 = np.concatenate([p1[:common], rng.uniform(0, 10, (m - common, dim))])
    p2 = p2 + noise * rng.normal(size=p2.shape)
    f1 = rng.random((n, 5))
    f2 = np.concatenate([f1[:common], rng.random((m - common, 5))])
    perm = rng.permutation(m)
    truth = np.argsort(perm)[:common]
    feats = (f1, f2[perm]) if features else (None, None)
    return Problem(p1, p2[perm], *feats), truth


def _triples(tensor: SparseTensor) -> set:
    return {tuple(sorted(row)) for row in tensor.indices.tolist()}


def _rows(tensor: SparseTensor) -> dict:
    """{sorted triple: (its sampled triangle of view 1, value)} (view 1 is the sampled one)."""
    return {
        tuple(sorted(r)): (tuple(sorted(a // tensor.m for a in r)), v)
        for r, v in zip(tensor.indices.tolist(), tensor.values.tolist(), strict=True)
    }


def _recording(search, calls: list, refuse: bool = False):
    """``search`` (the radius search) recording what it returned, or refusing every radius."""

    def recorded(*args):
        calls.append(None if refuse else search(*args))
        return calls[-1]

    return recorded


@functools.cache
def _uncapped(recipe: str, dim: int) -> tuple[Problem, SparseTensor]:
    """16 vs 36 objects, n*m = 576: C(16, 3) = 560 triangles x 576 neighbours uncapped."""
    problem, _ = _problem(16, 36, dim=dim, seed=3)
    return problem, build_tensor(problem, recipe, 0, max_entries=None)


@pytest.mark.parametrize("recipe,dim", [("paper", 3), ("duchenne", 2), ("paper", 2)])
@pytest.mark.parametrize("cap", [250_000, 30_000])
@pytest.mark.parametrize("search", ["radius", "grown"])
def test_capped_tensor_keeps_every_entry_ranked_above_the_cap(
    recipe, dim, cap, search, monkeypatch
):
    problem, full = _uncapped(recipe, dim)
    pools = []
    original = tensor_build._radius_pool
    fallback = search == "grown"  # the query-by-query fallback of the radius search
    monkeypatch.setattr(tensor_build, "_radius_pool", _recording(original, pools, fallback))
    capped = build_tensor(problem, recipe, 0, max_entries=cap)
    assert len(pools) == 1
    if fallback or cap == 30_000:  # at 250,000 (78 % of all pairs) the sample may refuse
        assert (pools[0] is None) == fallback
    assert full.nnz == 560 * 576 and not full.info["capped"]
    assert capped.nnz == cap and capped.info["capped"]
    full_rows, kept = _rows(full), _rows(capped)
    # the capped search computes distances in another vertex order (1e-12 of rounding) and
    # with another search tree, which may pick another of several candidates tied at a
    # triangle's k-th (last) neighbour: such a candidate is the only allowed difference
    last = {}
    for row, value in full_rows.values():
        last[row] = min(value, last.get(row, np.inf))

    rescale = capped.info["bandwidth"] / full.info["bandwidth"]  # "duchenne": mean of the kept

    def tied_last(triple, rows):
        row, value = rows[triple]
        value = value**rescale if rows is kept else value  # on the uncapped tensor's scale
        return bool(np.isclose(value, last[row], rtol=1e-9, atol=0))

    assert all(t in full_rows or tied_last(t, kept) for t in kept)
    cut = np.sort(full.values)[::-1][cap - 1]
    above = [t for t, (_, v) in full_rows.items() if v > cut * (1 + 1e-12)]
    assert all(t in kept or tied_last(t, full_rows) for t in above)
    assert sum(t not in kept for t in above) <= 10
    if recipe == "paper":  # fixed bandwidth: the kept values are the uncapped best values
        np.testing.assert_allclose(np.sort(capped.values), np.sort(full.values)[-cap:], rtol=1e-12)


def test_cap_respects_the_per_triangle_neighbour_count():
    # k = 5 neighbours per triangle, a cap just below the 5 x triangles entries: a triangle's
    # 6 vertex orders could offer 30 near pairs, but it keeps at most its 5 best, as uncapped
    problem, _ = _problem(14, 40, dim=2, seed=4)
    full = build_tensor(problem, "paper", 1, neighbours=5, max_entries=None)
    capped = build_tensor(problem, "paper", 1, neighbours=5, max_entries=full.nnz - 7)
    assert capped.nnz == full.nnz - 7 and _triples(capped) <= _triples(full)


def test_radius_search_falls_back_on_a_grid_of_identical_triangles(monkeypatch):
    # a 4 x 4 x 2 grid seen twice: thousands of congruent triangles at distance 0, so a radius
    # cannot be vouched for by the sample; the query-by-query search must give the same set
    grid = np.stack(np.meshgrid(range(4), range(4), range(2)), -1).reshape(-1, 3) * 2.0
    problem = Problem(grid, grid[::-1] + 1.0)
    calls = []
    monkeypatch.setattr(tensor_build, "_radius_pool", _recording(tensor_build._radius_pool, calls))
    capped = build_tensor(problem, "paper", 0, max_entries=50_000)
    assert calls == [None]  # the radius was refused
    assert capped.nnz == 50_000 and capped.values.max() == 1.0  # exact copies kept first


def test_cap_does_not_bind_up_to_1000_candidate_matches():
    problem, _ = _problem(25, 40, seed=5)  # n*m = 1000: the paper's 10^6 entries
    default = build_tensor(problem, "paper", 2)
    uncapped = build_tensor(problem, "paper", 2, max_entries=None)
    assert default.nnz == MAX_ENTRIES and not default.info["capped"]
    assert np.array_equal(default.indices, uncapped.indices)
    assert np.array_equal(default.values, uncapped.values)


def test_capped_hypergraph_matchers_recover_a_clean_problem():
    problem, truth = _problem(30, 34, seed=6, noise=0.01, features=False)
    for name in ("maximin", "rrwhm", "tm", "hgm", "mos", "bcagm"):
        m = get(name)(problem, max_tensor_entries=60_000)
        assert m.info["tensor"]["capped"] and m.info["tensor_entries"] <= 60_000
        hits = np.mean(truth[m.pairs[:, 0]] == m.pairs[:, 1])
        assert hits >= 0.9, name


def test_max_tensor_entries_is_checked():
    problem, _ = _problem(6, 6)
    for bad in (0, 2.5, True):
        with pytest.raises(ValueError, match="max_tensor_entries"):
            get("rrwhm")(problem, max_tensor_entries=bad)


def test_sparse_affinity_keeps_the_strongest_partners_with_dense_values():
    problem, _ = _problem(9, 11, seed=7)
    dense = pairwise_affinity(problem)
    sparse = sparse_pairwise_affinity(problem, neighbours=12)
    assert sp.issparse(sparse) and (sparse != sparse.T).nnz == 0  # symmetric
    rows, cols = sparse.nonzero()
    np.testing.assert_array_equal(np.asarray(sparse[rows, cols]).ravel(), dense[rows, cols])
    for a in (0, 17, 98):  # each row keeps at least its 12 largest (ties aside)
        twelfth = np.sort(dense[a])[::-1][11]
        assert set(np.flatnonzero(dense[a] > twelfth)) <= set(sparse[a].indices)
    everything = sparse_pairwise_affinity(problem, neighbours=10_000)
    np.testing.assert_array_equal(everything.toarray(), dense)


@pytest.mark.parametrize("name", ["sm", "rrwm", "mos"])
def test_sparse_and_dense_affinity_give_the_same_matching(name):
    for seed in (8, 9):
        problem, _ = _problem(10, 12, seed=seed, noise=0.1)
        dense = get(name)(problem)
        for neighbours in (10_000, 40):
            affinity = sparse_pairwise_affinity(problem, neighbours=neighbours)
            sparse = get(name)(problem, affinity=affinity)
            assert np.array_equal(dense.pairs, sparse.pairs), (seed, neighbours)
        np.testing.assert_allclose(
            get(name)(
                problem, affinity=sparse_pairwise_affinity(problem, neighbours=10_000)
            ).scores,
            dense.scores,
            atol=1e-9,
        )


def test_pairwise_matchers_go_sparse_above_500_partners():
    problem, truth = _problem(30, 32, seed=10, noise=0.02, features=False)
    assert sp.issparse(resolve_affinity(problem, None, 0.5))
    assert isinstance(resolve_affinity(problem, None, 0.5, neighbours=None), np.ndarray)
    assert isinstance(resolve_affinity(_problem(20, 25)[0], None, 0.5), np.ndarray)
    for name in ("sm", "rrwm", "mos"):
        m = get(name)(problem, max_tensor_entries=60_000) if name == "mos" else get(name)(problem)
        assert np.mean(truth[m.pairs[:, 0]] == m.pairs[:, 1]) >= 0.9, name
    with pytest.raises(ValueError, match="affinity_neighbours"):
        get("sm")(problem, affinity_neighbours=0)


def test_fused_product_is_bit_identical_to_bincount(monkeypatch):
    monkeypatch.setattr("matchers.hypergraph.sparse_tensor.COMPILED", False)  # the numpy paths
    problem, _ = _problem(12, 13, seed=11)
    tensor = build_tensor(problem, "paper", 0)
    again = build_tensor(problem, "paper", 0)
    rng = np.random.default_rng(0)
    x, y, z = rng.random((3, tensor.size))
    plain = [tensor.slot_sums(x), again.bilinear(y, z)]  # first products: bincount passes
    for _ in range(FUSE_AFTER - 2):
        tensor.slot_sums(x)
    assert not tensor._matrix and not again._matrix
    fused = [tensor.slot_sums(x), tensor.bilinear(y, z)]  # from the FUSE_AFTER-th: the layout
    assert tensor._matrix
    for a, b in zip(plain, fused, strict=True):
        assert np.array_equal(a, b)
    twin = tensor.with_values(tensor.values * 0.5)  # shares the layout, not the values
    assert np.array_equal(twin.slot_sums(x), 0.5 * fused[0])
