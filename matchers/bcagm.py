"""``bcagm``: tensor block coordinate ascent (Nguyen, Gautier & Hein, CVPR 2015 / T-PAMI 2017)."""

from __future__ import annotations

import time

import numpy as np

from matchers.blocks.cue_terms import weighted_tensor
from matchers.blocks.memory_models import tensor_matcher
from matchers.core.discretise import hungarian
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.options import check_count, check_problem, rng_from_seed
from matchers.core.problem import Problem
from matchers.core.result import finish
from matchers.hypergraph.sparse_tensor import SparseTensor
from matchers.hypergraph.tensor_build import MAX_ENTRIES, resolve_tensor

_ASCENT = 1e-12  # relative increase of the objective that counts as ascent


def best_assignment(gradient: np.ndarray, n: int, m: int) -> np.ndarray:
    """Binary vector of the assignment (min(n, m) ones) maximising <gradient, x> (Hungarian)."""
    rows, cols = hungarian(gradient.reshape(n, m))
    x = np.zeros(n * m)
    x[rows * m + cols] = 1.0
    return x


class _Lifted:
    """F4_alpha(x, y, z, t) = |x|_1 F3(y,z,t) + |y|_1 F3(x,z,t) + |z|_1 F3(x,y,t) + |t|_1 F3(x,y,z)
    + alpha (<x,y><z,t> + <x,z><y,t> + <x,t><y,z>) / 3, the order-4 lift of the third-order
    score F3 (F4(x,x,x,x) = 4 |x|_1 F3(x,x,x), constant |x|_1 on assignments)."""

    def __init__(self, tensor: SparseTensor):
        self.tensor = tensor
        self.alpha = 0.0
        self._mask = np.zeros(tensor.size, dtype=bool)
        self._sub = tensor.restricted(self._mask)

    def _restricted(self, blocks: list[np.ndarray]) -> SparseTensor:
        """The tensor restricted to the union of the blocks' supports, cached while the
        supports stay inside the cached mask and fill at least half of it (once the blocks
        settle, one restriction serves a whole sweep)."""
        support = np.logical_or.reduce([b > 0 for b in blocks])
        if np.any(support & ~self._mask) or self._mask.sum() > 2 * support.sum():
            self._mask = support
            self._sub = self.tensor.restricted(support)
        return self._sub

    def gradient(self, others: list[np.ndarray]) -> np.ndarray:
        """Gradient w.r.t. one block, the other three fixed (its constant part dropped)."""
        y, z, t = others
        sub = self._restricted(others)
        grad = t.sum() * sub.bilinear(y, z) + z.sum() * sub.bilinear(y, t)
        grad += y.sum() * sub.bilinear(z, t)
        if self.alpha:
            grad += self.alpha * (y * (z @ t) + z * (y @ t) + t * (y @ z)) / 3.0
        return grad

    def value(self, blocks: list[np.ndarray]) -> float:
        x, y, z, t = blocks
        sub = self._restricted(blocks)
        f3_yzt = float(y @ sub.bilinear(z, t))
        return float(x @ self.gradient([y, z, t])) + x.sum() * f3_yzt


def bcagm_solve(tensor: SparseTensor, max_iter: int = 50) -> tuple[np.ndarray, int, dict]:
    """BCAGM, the 4-block order-4 lift with Hungarian block updates (CVPR 2015 "BCAGM").

    Values are scaled to sum 1 over the full super-symmetric tensor (the reference); the blocks
    start at all-ones and are updated in turn, x^i <- argmax over assignments of
    <grad_i F4_alpha, x^i> (Hungarian), which never decreases F4_alpha. When a sweep brings no
    ascent: stop if all four blocks are equal; else jump to the best homogeneous point (u,u,u,u),
    u one of the blocks, if it scores at least as high; else convexify once with
    alpha = 3 * ||T||_F (the reference's bound), which makes homogeneous points optimal, and
    continue. Stops after ``max_iter`` sweeps (reference 50) at the best homogeneous point.
    Returns (binary x with min(n, m) ones, sweeps, info).
    """
    n, m = tensor.n, tensor.m
    if not tensor.nnz:
        return best_assignment(np.zeros(n * m), n, m), 0, {"converged": True, "alpha": 0.0}
    values = tensor.values / (6.0 * tensor.values.sum())
    lifted = _Lifted(tensor.with_values(values))
    bound = 3.0 * np.sqrt(6.0 * np.sum(values**2))
    blocks = [np.ones(n * m) for _ in range(4)]
    best = -np.inf
    converged = False
    sweeps = 0
    for sweeps in range(1, max_iter + 1):  # noqa: B007 - reported
        for i in range(4):
            blocks[i] = best_assignment(lifted.gradient(blocks[:i] + blocks[i + 1 :]), n, m)
        score = lifted.value(blocks)
        if score - best > _ASCENT * abs(score):
            best = score
            continue
        if all(np.array_equal(blocks[0], b) for b in blocks[1:]):
            converged = True
            break
        homogeneous = [lifted.value([u] * 4) for u in blocks]
        u = blocks[int(np.argmax(homogeneous))]
        if max(homogeneous) >= score:
            blocks, best = [u] * 4, max(homogeneous)
        elif lifted.alpha == 0.0:
            lifted.alpha = bound
            best = lifted.value(blocks)
        else:
            blocks = [u] * 4
            break
    else:
        homogeneous = [lifted.value([u] * 4) for u in blocks]
        blocks = [blocks[int(np.argmax(homogeneous))]] * 4
    return blocks[0], sweeps, {"converged": converged, "alpha": float(lifted.alpha)}


@budgeted(tensor_matcher("bcagm"), "max_tensor_entries, triangles or neighbours")
def bcagm(
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
    max_iter: int = 50,
) -> Matching:
    """BCAGM (:func:`bcagm_solve`; the plain 4-block variant, no MP/IPFP sub-solver), then the
    shared discretisation.

    BCAGM's answer is discrete, so the soft score of each of its pairs a is the pair's
    hyperedge support from the rest of the matching, (T x_2 x x_3 x)[a], divided by the best
    pair's; every other candidate scores 0. Hungarian on these scores returns BCAGM's own
    assignment, and a threshold drops its least supported pairs. Tensor options as for every
    hypergraph matcher (see :func:`matchers.rrwhm.rrwhm`); ``max_iter`` 50 sweeps.
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
    n, m = problem.n1, problem.n2
    built = weighted_tensor(
        resolve_tensor(problem, tensor, rng, triangles, neighbours, sigma, max_tensor_entries),
        problem,
        distance_scale,
        appearance,
    )
    x, sweeps, info = bcagm_solve(built, max_iter)
    support = x * built.product(x)
    top = support.max() if support.size else 0.0
    scores = (support / top).reshape(n, m) if top > 0 else np.zeros((n, m))
    info |= {"tensor_entries": built.nnz, "tensor": built.info, "objective": built.value(x)}
    return finish("bcagm", scores, threshold, started, sweeps, info)
