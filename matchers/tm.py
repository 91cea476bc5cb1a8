"""``tm``: Tensor Matching (Duchenne, Bach, Kweon & Ponce, CVPR 2009 / PAMI 2011)."""

from __future__ import annotations

import time

import numpy as np

from matchers.blocks.cue_terms import weighted_tensor
from matchers.blocks.memory_models import tensor_matcher
from matchers.core.jit import njit
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.numpy_sum import reproducible, row_sum_jit
from matchers.core.options import check_count, check_problem, check_range, rng_from_seed
from matchers.core.problem import Problem
from matchers.core.result import finish, max_normalised
from matchers.hypergraph.sparse_tensor import SparseTensor
from matchers.hypergraph.tensor_build import MAX_ENTRIES, resolve_tensor
from matchers.hypergraph.tensor_product import FUSE_AFTER, slot_sums_jit

NORMALISATIONS = ("doubly", "rows", "global")


def _l2_normalise(x: np.ndarray, axis: int | None) -> np.ndarray:
    norm = np.sqrt(np.sum(x * x, axis=axis, keepdims=axis is not None))
    return np.divide(x, norm, out=np.zeros_like(x), where=norm > 0)


DOUBLY_ROUNDS = 10  # alternating row/column passes of one "doubly" normalisation


def normalise_l2(
    x: np.ndarray, n: int, m: int, mode: str, rounds: int = DOUBLY_ROUNDS
) -> np.ndarray:
    """TM's normalisation of the n x m iterate: "global" l2; "rows" l2 per object of view 1;
    "doubly" ``rounds`` alternating passes of row then column l2 normalisation, each pass
    working on the result of the previous one (the fixed variant, see :func:`tensor_power`)."""
    mat = x.reshape(n, m)
    if mode == "global":
        return _l2_normalise(mat, None).reshape(-1)
    if mode == "rows":
        return _l2_normalise(mat, 1).reshape(-1)
    if mat.size and mat.min() > 0:
        fast = doubly_positive(mat.copy(), rounds)
        if np.isfinite(fast).all():
            return fast.reshape(-1)
    for _ in range(rounds):
        mat = _l2_normalise(_l2_normalise(mat, 1), 0)
    return mat.reshape(-1)


def _doubly_positive(mat: np.ndarray, rounds: int) -> np.ndarray:
    """The "doubly" passes for a strictly positive matrix (TM's iterate always is: X0 > 0),
    in place: the same squares, sums, roots and divisions as :func:`_l2_normalise`, so
    bit-identical, without its per-call allocations and zero-norm masking."""
    square = np.empty_like(mat)
    rows, cols = np.empty((mat.shape[0], 1)), np.empty((1, mat.shape[1]))
    add, multiply, sqrt, divide = np.add.reduce, np.multiply, np.sqrt, np.divide
    for _ in range(rounds):
        multiply(mat, mat, square)
        sqrt(add(square, 1, None, rows, True), rows)
        divide(mat, rows, mat)
        multiply(mat, mat, square)
        sqrt(add(square, 0, None, cols, True), cols)
        divide(mat, cols, mat)
    return mat


def _doubly_kernel(mat: np.ndarray, rounds: int) -> None:
    # _doubly_positive as one loop: rows summed pairwise and columns row after row, as numpy
    size_r, size_c = mat.shape
    rows = np.empty(size_r)
    cols = np.empty(size_c)
    for _ in range(rounds):
        for r in range(size_r):
            for c in range(size_c):
                cols[c] = mat[r, c] * mat[r, c]
            rows[r] = np.sqrt(row_sum_jit(cols, size_c))
        for r in range(size_r):
            for c in range(size_c):
                mat[r, c] = mat[r, c] / rows[r]
        for c in range(size_c):
            cols[c] = mat[0, c] * mat[0, c]
        for r in range(1, size_r):
            for c in range(size_c):
                cols[c] += mat[r, c] * mat[r, c]
        for c in range(size_c):
            cols[c] = np.sqrt(cols[c])
        for r in range(size_r):
            for c in range(size_c):
                mat[r, c] = mat[r, c] / cols[c]


_doubly_kernel_jit = njit(_doubly_kernel) if row_sum_jit is not None else None


def doubly_positive(mat: np.ndarray, rounds: int) -> np.ndarray:
    """:func:`_doubly_positive`, compiled when numba is available and the matrix has 2 to
    :data:`~matchers.core.numpy_sum.PAIRWISE_BLOCK` columns (numpy's summation order is reproduced
    only there); bit-identical either way. In place; returns ``mat``."""
    if _doubly_kernel_jit is None or not reproducible(mat):
        return _doubly_positive(mat, rounds)
    _doubly_kernel_jit(mat, rounds)
    return mat


CHECK_EVERY = 5  # products between two convergence checks
TOL = 1e-3  # relative l1 change of x over CHECK_EVERY products that counts as converged


def tensor_power(
    tensor: SparseTensor,
    max_iter: int = 100,
    normalisation: str = "doubly",
    sparsity: bool = True,
    tol: float = TOL,
) -> tuple[np.ndarray, int]:
    """Duchenne's higher-order power iteration with the l1 ("sparsity") relaxation.

        X0: every object of view 1 spreads mass 1 uniformly (x0 = 1/m)
        repeat at most max_iter times:
            t = X0 + x o S(x o x)   [sparsity]   or   t = X0 + S(x)   [no sparsity]
            x = normalise(t)
        every CHECK_EVERY (5) products: stop once |x - x_5 products ago|_1 <= tol |x|_1

    The reference runs a fixed nIter (100) products; on CAD pairs the iterate mostly settles long
    before, so the loop stops once x changes by at most ``tol`` (1e-3, relative l1 over 5
    products; ``tol=0``: the reference's fixed count). With numba, the default iteration
    (sparsity, "doubly") runs its 5 products per check in one compiled call (:func:`_steps_kernel`),
    the numpy loop's operations in its order: the same bits. Returns (relaxed assignment
    x o x (length nm), products made).
    where S(v)[a] = sum over stored triples (a, b, c) of h v_b v_c (each triple stored once,
    accumulated into all three slots — the reference mex's loop) and X0 is re-added every
    iteration as in the reference. Values are used raw (no normalisation), as the reference.

    Bug-fixed variant: the vendored mex (BCAGM/RRWHM toolboxes) groups candidates for the
    per-point normalisation with the wrong stride when n != m, and its "doubly" mode
    normalises rows and columns from the same un-normalised buffer so only the column pass
    survives. We implement the corrected behaviour (as HNN-HM's port does): groups are the
    rows/columns of the n x m matrix and passes are applied in sequence. Default "doubly"
    (the BCAGM benchmark's ``stoc='doubly'``). Returns the relaxed assignment x o x (length nm).
    """
    n, m = tensor.n, tensor.m
    if max_iter >= FUSE_AFTER:
        tensor.prepare_products()  # a fixed number of products: sort the layout now (no numba)
    x0 = np.full(n * m, 1.0 / max(m, 1))
    x = x0.copy()
    checked = x
    done = 0
    compiled = _compiled_steps(tensor, normalisation, sparsity)
    while done < max_iter:
        steps = min(CHECK_EVERY - done % CHECK_EVERY, max_iter - done)
        stepped = compiled(x, x0, steps) if compiled is not None else None
        if stepped is None:  # numpy, one product at a time
            for _ in range(steps):
                t = x0 + (x * tensor.slot_sums(x * x) if sparsity else tensor.slot_sums(x))
                x = normalise_l2(t, n, m, normalisation)
        else:
            x = stepped
        done += steps
        if tol > 0 and done % CHECK_EVERY == 0:
            if np.abs(x - checked).sum() <= tol * np.abs(x).sum():
                break
            checked = x
    return (x * x if sparsity else x), done


def _steps_kernel(
    slots: np.ndarray,
    values: np.ndarray,
    x: np.ndarray,
    x0: np.ndarray,
    steps: int,
    n: int,
    m: int,
    rounds: int,
):
    # `steps` products of the sparsity + "doubly" iteration in one compiled loop, with the
    # numpy path's operations in its order (x o S(x o x), + x0, the doubly passes): returns
    # the new x, or an empty array when an iterate was not strictly positive and finite (the
    # numpy path then takes over from the same x)
    size = n * m
    x = x.copy()
    square = np.empty(size)
    for _ in range(steps):
        for a in range(size):
            square[a] = x[a] * x[a]
        sums = _slot_sums_compiled(slots, values, square, size)
        for a in range(size):
            x[a] = x0[a] + x[a] * sums[a]
            if not (x[a] > 0.0 and x[a] < np.inf):  # numpy's fast path needs min > 0
                return np.empty(0)
        _doubly_compiled(x.reshape(n, m), rounds)
        for a in range(size):
            if not np.isfinite(x[a]):  # numpy's fast path is kept only when finite
                return np.empty(0)
    return x


_slot_sums_compiled = slot_sums_jit
_doubly_compiled = _doubly_kernel_jit
_steps_jit = (
    njit(_steps_kernel) if slot_sums_jit is not None and _doubly_kernel_jit is not None else None
)


def _compiled_steps(tensor: SparseTensor, normalisation: str, sparsity: bool):
    """``steps(x, x0, k)``: k products of :func:`tensor_power`'s default iteration (sparsity,
    "doubly") in one compiled call — the same bits as the numpy loop — or None where it does
    not apply (no numba, another mode, or more than :data:`~matchers.core.numpy_sum.PAIRWISE_BLOCK`
    columns). ``steps`` returns None when an iterate leaves the positive finite numbers."""
    n, m = tensor.n, tensor.m
    if _steps_jit is None or normalisation != "doubly" or not sparsity or not 2 <= m <= 128:
        return None
    slots, values = tensor.compact_slots, tensor.values

    def steps(x: np.ndarray, x0: np.ndarray, count: int) -> np.ndarray | None:
        out = _steps_jit(slots, values, x, x0, count, n, m, DOUBLY_ROUNDS)
        return out if out.size else None

    return steps


@budgeted(tensor_matcher("tm"), "max_tensor_entries, triangles or neighbours")
def tm(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    tensor: str | SparseTensor = "paper",
    triangles: int | None = None,
    neighbours: int | None = None,
    sigma: float | None = None,
    max_tensor_entries: int | None = MAX_ENTRIES,
    distance_scale: float | None = None,
    appearance: bool = False,
    max_iter: int = 100,
    normalisation: str = "doubly",
    sparsity: bool = True,
    tol: float = TOL,
) -> Matching:
    """Tensor Matching (:func:`tensor_power`), then Hungarian.

    Tensor options as for every hypergraph matcher (see :func:`matchers.rrwhm.rrwhm`).
    ``max_iter`` 100 (the reference's nIter, an upper bound here), ``tol`` 1e-3 (relative l1
    change over 5 products that stops the iteration; 0: always ``max_iter`` products, as the
    reference), ``normalisation`` "doubly" | "rows" | "global", ``sparsity`` True (l1
    relaxation). Scores: x o x divided by its maximum (with
    an empty tensor — no hyperedges — the scores are all 0: no evidence).
    ``distance_scale`` (None, as published): multiply every tensor entry by the metric
    affinity of its three edges, width ``distance_scale`` x the median within-view
    distance (the equal-cue protocol; :mod:`matchers.blocks.cue_terms`).
    ``appearance`` (False, as published): multiply every entry by the appearance
    similarity of its three candidate matches.
    """
    started = time.perf_counter()
    check_problem(problem)
    rng = rng_from_seed(seed)
    check_count("max_iter", max_iter)
    tol = check_range("tol", tol, 0.0, 1.0)
    if normalisation not in NORMALISATIONS:
        raise ValueError(f"normalisation: expected one of {NORMALISATIONS}, got {normalisation!r}")
    built = weighted_tensor(
        resolve_tensor(problem, tensor, rng, triangles, neighbours, sigma, max_tensor_entries),
        problem,
        distance_scale,
        appearance,
    )
    x, products = (
        tensor_power(built, max_iter, normalisation, bool(sparsity), tol)
        if built.nnz
        else (None, 0)
    )
    if x is None:  # no hyperedges: nothing but the uniform prior — report no evidence
        scores = np.zeros((problem.n1, problem.n2))
    else:
        scores = max_normalised(x, problem.n1, problem.n2)
    info = {"tensor_entries": built.nnz, "tensor": built.info, "converged": products < max_iter}
    return finish("tm", scores, threshold, started, products, info)
