"""The tensor's candidate search: exact k nearest, ties broken by candidate index, the same
from every path (compiled, numpy, split over threads; capped by radius or grown)."""

from __future__ import annotations

import numpy as np
import pytest

from matchers import Problem, build_tensor
from matchers.core import row_threads
from matchers.hypergraph import candidate_search, tensor_build
from matchers.hypergraph.candidate_search import nearest, nearest_numpy
from matchers.hypergraph.triangles import angle_cosines, ordered_descriptors


def _reference(queries: np.ndarray, candidates: np.ndarray, k: int, p: int):
    """By definition: sort every candidate by (distance, index), keep k, list them by index."""
    diff = queries[:, None, :] - candidates[None, :, :]
    if p == 1:
        dist = (np.abs(diff[..., 0]) + np.abs(diff[..., 1])) + np.abs(diff[..., 2])
    else:
        dist = np.sqrt((diff[..., 0] ** 2 + diff[..., 1] ** 2) + diff[..., 2] ** 2)
    order = np.argsort(dist, axis=1, kind="stable")[:, :k]  # stable: ties by index
    idx = np.sort(order, axis=1)
    return np.take_along_axis(dist, idx, axis=1), idx


def _grid_descriptors():
    """A 3 x 3 x 2 grid of points: hundreds of congruent triangles, so the k-th distance is
    shared by many candidates (exact ties)."""
    grid = np.stack(np.meshgrid(range(3), range(3), range(2)), -1).reshape(-1, 3) * 2.0
    tri, desc, valid = ordered_descriptors(grid, angle_cosines, False)
    desc = np.round(desc[valid], 9)
    return desc[::7].copy(), desc


@pytest.mark.parametrize("p", [1, 2])
@pytest.mark.parametrize("k", [1, 37, 500])
def test_every_path_keeps_the_lowest_indexed_of_tied_candidates(p, k, monkeypatch):
    queries, candidates = _grid_descriptors()
    want_dist, want_idx = _reference(queries, candidates, k, p)
    kth = want_dist.max(axis=1, keepdims=True)
    every, _ = _reference(queries, candidates, len(candidates), p)
    assert ((every == kth).sum(axis=1) > (want_dist == kth).sum(axis=1)).any()  # ties cut
    compiled = nearest(queries, candidates, k, p)
    by_numpy = nearest_numpy(queries, candidates, k, p)
    monkeypatch.setattr(candidate_search, "BLOCK_CELLS", 1000)  # numpy, many small blocks
    blocked = nearest_numpy(queries, candidates, k, p)
    monkeypatch.setattr(row_threads, "MIN_WORK", 1)  # compiled, split over 3 threads
    monkeypatch.setattr(row_threads, "threads", lambda: 3)
    split = nearest(queries, candidates, k, p)
    for dist, idx in (compiled, by_numpy, blocked, split):
        assert np.array_equal(idx, want_idx)
        assert np.array_equal(dist, want_dist)


def test_random_descriptors_match_the_definition():
    rng = np.random.default_rng(4)
    queries = np.round(rng.uniform(-1, 1, (40, 3)), 2)  # coarse: ties everywhere
    candidates = np.round(rng.uniform(-1, 1, (3000, 3)), 2)
    for p in (1, 2):
        want = _reference(queries, candidates, 200, p)
        got = nearest(queries, candidates, 200, p)
        assert np.array_equal(got[1], want[1]) and np.array_equal(got[0], want[0])


def test_distances_beyond_the_histogram_range_are_still_exact():
    # distances below 2**-10 share the first bin and above 16 the last: still exact
    rng = np.random.default_rng(5)
    candidates = np.concatenate([rng.uniform(0, 1e-4, (500, 3)), rng.uniform(50, 90, (500, 3))])
    queries = candidates[::50] + 1e-6
    for k in (10, 600, 1000):
        got = nearest(queries, candidates, k, 1)
        want = _reference(queries, candidates, k, 1)
        assert np.array_equal(got[1], want[1])


def test_a_misleading_sample_falls_back_to_every_candidate():
    # the compiled search estimates its bound from every 8th distance: here those candidates are
    # the only close ones, so the bound keeps fewer than k and the search must widen to all
    rng = np.random.default_rng(6)
    candidates = rng.uniform(5, 9, (800, 3))
    candidates[::8] = rng.uniform(0, 0.1, (100, 3))
    queries = np.zeros((4, 3))
    for k in (150, 400):
        got = nearest(queries, candidates, k, 1)
        want = _reference(queries, candidates, k, 1)
        assert np.array_equal(got[1], want[1]) and np.array_equal(got[0], want[0])


def test_bad_arguments_are_refused():
    q = np.zeros((2, 3))
    with pytest.raises(ValueError, match="p: expected 1 or 2"):
        nearest(q, q, 1, 3)
    with pytest.raises(ValueError, match="k: expected 1..2"):
        nearest(q, q, 3, 1)


def test_the_tensor_does_not_depend_on_the_candidate_search_path(monkeypatch):
    grid = np.stack(np.meshgrid(range(3), range(3), range(2)), -1).reshape(-1, 3) * 2.0
    problem = Problem(grid, grid[::-1] + 1.0)
    compiled = build_tensor(problem, "paper", 0)
    monkeypatch.setattr(candidate_search, "_nearest_jit", None)
    by_numpy = build_tensor(problem, "paper", 0)
    assert np.array_equal(compiled.indices, by_numpy.indices)
    assert np.array_equal(compiled.values, by_numpy.values)


def test_capped_tensor_is_the_same_from_the_radius_and_the_grown_search(monkeypatch):
    rng = np.random.default_rng(3)
    points = np.round(rng.uniform(0, 10, (36, 3)))  # integer coordinates: tied descriptors
    problem = Problem(points[:16], points[::-1])
    by_radius = build_tensor(problem, "paper", 0, max_entries=30_000)
    monkeypatch.setattr(tensor_build, "_radius_pool", lambda *args: None)
    grown = build_tensor(problem, "paper", 0, max_entries=30_000)
    assert by_radius.info["capped"] and by_radius.nnz == 30_000
    assert np.array_equal(by_radius.indices, grown.indices)
    assert np.array_equal(by_radius.values, grown.values)
