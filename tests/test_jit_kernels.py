"""The compiled kernels (matchers.core.jit) agree with the numpy code they replace, and the matchers give
the same matchings with and without them.

Kernels follow numpy's summation order and are compared bit for bit; the tensor values' ``exp``
is the portable one (:mod:`matchers.core.portable_exp`) in both paths, so whole matchers give the
same bits with and without numba."""

from __future__ import annotations

import numpy as np
import pytest

from matchers import Problem, get, tm
from matchers.blocks import sinkhorn
from matchers.core import portable_exp
from matchers.hypergraph import candidate_search, sparse_tensor, tensor_build, tensor_product
from matchers.hypergraph.tensor_build import build_tensor


def test_numba_is_installed_and_the_kernels_compile():
    # numba is a declared dependency: without it every kernel test below would test nothing new
    assert tensor_product.COMPILED
    assert sinkhorn._positive_kernel_jit is not None
    assert tm._doubly_kernel_jit is not None


@pytest.mark.parametrize("seed", range(6))
def test_compiled_sinkhorn_sweeps_are_bit_identical(seed):
    rng = np.random.default_rng(seed)
    for _ in range(60):
        n = int(rng.integers(2, 70))
        m = n if rng.random() < 0.5 else int(rng.integers(2, 70))
        x = rng.random((n, m))
        work = np.exp(rng.uniform(1, 40) * x / x.max())  # RRWM's peaked jump
        target = (1.0, 1.0) if n == m else (1.0, min(n, m) / max(n, m))
        expected = sinkhorn._positive_sweeps(work.copy(), 100, 1e-3, *target)
        got = sinkhorn.positive_sweeps(work.copy(), 100, 1e-3, *target)
        assert (expected is None) == (got is None)
        if expected is not None:
            assert got[1] == expected[1]
            assert np.array_equal(got[0], expected[0])


def test_compiled_sinkhorn_falls_back_outside_its_shapes():
    work = np.exp(np.random.default_rng(0).random((5, 1)))
    expected = sinkhorn._positive_sweeps(work.copy(), 100, 1e-3, 0.2, 1.0)
    got = sinkhorn.positive_sweeps(work.copy(), 100, 1e-3, 0.2, 1.0)
    assert np.array_equal(got[0], expected[0]) and got[1] == expected[1]


def _reference_products(tensor, x, y, z):
    """slot_sums and bilinear as one np.bincount over the incidences in triple order (slots 0,
    1, 2 of triple 0, then of triple 1, ...)."""
    ia, ib, ic = (tensor.indices[:, k] for k in range(3))
    slots = np.stack([ia, ib, ic], axis=1).reshape(-1)
    v = np.repeat(tensor.values, 3)
    sums = np.bincount(
        slots,
        np.stack([x[ib] * x[ic], x[ia] * x[ic], x[ia] * x[ib]], axis=1).reshape(-1) * v,
        tensor.size,
    )
    w = np.stack(
        [
            y[ib] * z[ic] + y[ic] * z[ib],
            y[ia] * z[ic] + y[ic] * z[ia],
            y[ia] * z[ib] + y[ib] * z[ia],
        ],
        axis=1,
    ).reshape(-1)
    return sums, np.bincount(slots, w * v, tensor.size)


@pytest.mark.parametrize("seed", range(3))
def test_compiled_doubly_normalisation_is_bit_identical(seed):
    rng = np.random.default_rng(seed)
    for _ in range(200):
        n, m = (int(v) for v in rng.integers(1, 45, size=2))  # m = 1 and m > 8 included
        mat = rng.random((n, m)) ** rng.uniform(1, 12) + 1e-300  # TM's iterate: positive
        expected = tm._doubly_positive(mat.copy(), 10)
        assert np.array_equal(tm.doubly_positive(mat.copy(), 10), expected)


@pytest.mark.parametrize("shape", [(6, 7), (12, 13), (17, 15)])
def test_compiled_products_are_bit_identical_to_bincount(shape):
    rng = np.random.default_rng(shape[0])
    problem = Problem(rng.uniform(0, 20, (shape[0], 3)), rng.uniform(0, 20, (shape[1], 3)))
    tensor = build_tensor(problem, "paper", 0)
    assert tensor.nnz > 0
    x, y, z = rng.random((3, tensor.size))
    sums, bilinear = _reference_products(tensor, x, y, z)
    assert np.array_equal(tensor.slot_sums(x), sums)
    assert np.array_equal(tensor.bilinear(y, z), bilinear)
    assert not tensor._matrix  # compiled products need no sorted layout
    assert tensor.compact_slots.dtype == np.uint16  # they stream 2-byte indices
    tensor.prepare_products()
    assert not tensor._matrix  # ... even when asked for it (TM): the compiled loop is faster


def _problem(seed: int) -> Problem:
    rng = np.random.default_rng(seed)
    world = rng.uniform(0, 30, (22, 3))
    p1, p2 = world[:16], world[6:] + rng.normal(0, 0.2, (16, 3))
    f = rng.random((22, 8))
    return Problem(p1, p2, f[:16], f[6:] + rng.normal(0, 0.05, (16, 8)))


@pytest.mark.parametrize("name", ["rrwm", "rrwhm", "tm", "mos", "maximin", "bcagm", "hgm"])
def test_matchers_give_the_same_matchings_without_numba(name, monkeypatch):
    problems = [_problem(seed) for seed in range(3)]
    compiled = [get(name)(p, seed=1) for p in problems]
    monkeypatch.setattr(sparse_tensor, "COMPILED", False)
    monkeypatch.setattr(sinkhorn, "_positive_kernel_jit", None)
    monkeypatch.setattr(tm, "_doubly_kernel_jit", None)
    monkeypatch.setattr(tm, "_steps_jit", None)
    monkeypatch.setattr(tensor_build, "_match_indices_jit", None)
    monkeypatch.setattr(portable_exp, "_exp_into_jit", None)
    monkeypatch.setattr(candidate_search, "_nearest_jit", None)
    for problem, fast in zip(problems, compiled, strict=True):
        slow = get(name)(problem, seed=1)
        assert np.array_equal(fast.pairs, slow.pairs)
        assert np.array_equal(fast.scores, slow.scores)  # the same bits


@pytest.mark.parametrize("recipe", ["paper", "duchenne"])
@pytest.mark.parametrize("size", [(9, 11), (20, 20), (40, 38)])  # the last one capped
def test_compiled_tensor_assembly_agrees_with_numpy(recipe, size, monkeypatch):
    rng = np.random.default_rng(size[0])
    problem = Problem(rng.uniform(0, 20, (size[0], 3)), rng.uniform(0, 20, (size[1], 3)))
    compiled = build_tensor(problem, recipe, 3)
    monkeypatch.setattr(tensor_build, "_match_indices_jit", None)
    monkeypatch.setattr(portable_exp, "_exp_into_jit", None)
    plain = build_tensor(problem, recipe, 3)
    assert compiled.nnz > 0
    assert np.array_equal(compiled.indices, plain.indices)
    assert np.array_equal(compiled.values, plain.values)  # exp included: the portable one


def test_compiled_degrees_and_worst_case_weights_are_bit_identical():
    rng = np.random.default_rng(4)
    problem = Problem(rng.uniform(0, 20, (15, 3)), rng.uniform(0, 20, (17, 3)))
    tensor = build_tensor(problem, "paper", 0)
    b = rng.random(tensor.size)
    slots = tensor.indices.reshape(-1)  # triple order
    expected = np.bincount(slots, np.repeat(tensor.values, 3), minlength=tensor.size)
    assert np.array_equal(tensor.degrees(), expected)
    assert np.array_equal(tensor.min_weighted(b), tensor.values * b[tensor.indices].min(axis=1))


def test_compiled_restriction_keeps_the_same_triples_in_the_same_order(monkeypatch):
    rng = np.random.default_rng(5)
    problem = Problem(rng.uniform(0, 20, (14, 3)), rng.uniform(0, 20, (16, 3)))
    tensor = build_tensor(problem, "paper", 0)
    masks = [rng.random(tensor.size) < q for q in (0.0, 0.1, 0.5, 1.0)]
    compiled = [tensor.restricted(mask) for mask in masks]
    monkeypatch.setattr(sparse_tensor, "COMPILED", False)
    for mask, fast in zip(masks, compiled, strict=True):
        slow = tensor.restricted(mask)
        assert np.array_equal(fast.indices, slow.indices) and fast.indices.dtype == np.intp
        assert np.array_equal(fast.values, slow.values)
        y, z = rng.random((2, tensor.size)) * mask
        assert np.array_equal(fast.bilinear(y, z), tensor.bilinear(y, z))
    assert compiled[0].nnz == 0 and compiled[-1].nnz == tensor.nnz


def test_a_numba_that_fails_to_import_is_reported_once_and_numpy_takes_over(monkeypatch, caplog):
    import builtins
    import sys

    from matchers.core import jit

    real_import = builtins.__import__

    def broken(name, *args, **kwargs):
        if name == "numba":
            raise ImportError("Numba needs NumPy 1.x")  # what a version clash looks like
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", broken)
    monkeypatch.setattr(jit, "_WARNED", [])
    monkeypatch.delitem(sys.modules, "numba", raising=False)
    jit._numba.cache_clear()
    try:
        with caplog.at_level("WARNING", logger="matchers.core.jit"):
            assert jit.njit(lambda x: x) is None and jit.njit(lambda x: x) is None
        warnings = [r for r in caplog.records if "failed to import" in r.getMessage()]
        assert len(warnings) == 1 and "Numba needs NumPy 1.x" in warnings[0].getMessage()
    finally:
        jit._numba.cache_clear()
