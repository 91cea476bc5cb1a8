"""``optimal_transport``: association by entropic optimal transport on a distance-based
affinity (as SuperGlue's and many V2X registration methods' final layer does), implemented
from those descriptions, pose-free. A generic baseline: V2X-Reg++'s own association (box-pair
hypotheses scored by the boxes they align, no transport) is :mod:`matchers.v2x_reg`.

Affinity: the local-context similarity S_ij in [0, 1] of the two objects (their neighbour
distances agree within eps, :func:`~matchers.blocks.local_context.context_similarity`), a
measure of how much of their surroundings overlaps. Transport: cost C = 1 − S with a *dustbin*
row and column (cost 1 − ``dustbin``) for objects the other view does not see; every real object
carries mass 1, each dustbin the other view's count; the entropic plan
P = diag(u) exp(−C / ``epsilon``) diag(v) is found by Sinkhorn's scaling iterations
(``iterations`` sweeps). Scores: the real block of P (each row's and column's mass is at most 1), in [0, 1];
then the shared Hungarian + threshold.

Variant ``optimal_transport_pose``: the affinity times the prior likelihood
(:func:`~matchers.blocks.prior.prior_likelihood`).
"""

from __future__ import annotations

import time

import numpy as np

from matchers.blocks.local_context import (
    NEIGHBOURS,
    checked_tolerance,
    context_similarity,
    prior_weights,
)
from matchers.blocks.memory_models import context_memory
from matchers.blocks.prior import PRIOR_FIELDS
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.options import check_range
from matchers.core.problem import Problem
from matchers.core.result import finish


def transport_plan(
    affinity: np.ndarray, epsilon: float, dustbin: float, iterations: int
) -> np.ndarray:
    """(n, m) real block of the entropic transport plan with dustbins (module docstring). The
    costs lie in [0, 1] and ``epsilon`` ≥ 0.01, so the kernel exp(−C / epsilon) stays above
    1e-44 and the scaling form of Sinkhorn (u = a / K v, v = b / Kᵀ u) needs no logarithms."""
    n, m = affinity.shape
    cost = np.full((n + 1, m + 1), 1.0 - dustbin)
    cost[:n, :m] = 1.0 - affinity
    kernel = np.exp(-cost / epsilon)
    a = np.append(np.ones(n), float(m))
    b = np.append(np.ones(m), float(n))
    v = np.ones(m + 1)
    for _ in range(iterations):
        u = a / (kernel @ v)
        v = b / (kernel.T @ u)
    u = a / (kernel @ v)
    return (u[:, None] * kernel * v[None, :])[:n, :m]


def _run(name, problem, threshold, started, eps, neighbours, epsilon, dustbin, iterations, likelihood=None):  # fmt: skip
    n, m = problem.n1, problem.n2
    if n == 0 or m == 0:
        return finish(name, np.zeros((n, m)), threshold, started, 0, {"tolerance": eps})
    affinity = context_similarity(problem.points1, problem.points2, neighbours, eps)
    if likelihood is not None:
        affinity = affinity * likelihood
    plan = transport_plan(affinity, epsilon, dustbin, iterations)
    info = {"tolerance": float(eps)}
    return finish(name, np.clip(plan, 0.0, 1.0), threshold, started, iterations, info)


def _options(problem, seed, tolerance_scale, tolerance, neighbours, epsilon, dustbin, iterations):
    eps = checked_tolerance(
        problem, seed, tolerance_scale, tolerance, neighbours=neighbours, iterations=iterations
    )
    epsilon = check_range("epsilon", epsilon, 0.01, 10.0)
    return eps, epsilon, check_range("dustbin", dustbin, 0.0, 1.0)


@budgeted(context_memory, "the number of objects or neighbours")
def optimal_transport(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    tolerance_scale: float = 0.1,
    tolerance: float | None = None,
    neighbours: int = NEIGHBOURS,
    epsilon: float = 0.1,
    dustbin: float = 0.3,
    iterations: int = 100,
) -> Matching:
    """Entropic optimal transport on the local-context affinity, with dustbins (module
    docstring): eps from ``tolerance_scale`` (0.1 × the median within-view distance) or
    ``tolerance``; ``epsilon`` (0.1) the entropic regularisation in cost units; ``dustbin``
    (0.3) the affinity of leaving an object unmatched. Needs no features and no prior.
    Deterministic.

    >>> rng = np.random.default_rng(1)
    >>> pts = rng.uniform(0, 30, (7, 3))
    >>> other = np.vstack([pts[:5] @ np.diag([-1.0, -1.0, 1.0]) + 4.0, rng.uniform(0, 30, (2, 3))])
    >>> optimal_transport(Problem(pts, other), threshold=0.5).pairs.tolist()
    [[0, 0], [1, 1], [2, 2], [3, 3], [4, 4]]
    """
    started = time.perf_counter()
    eps, epsilon, dustbin = _options(
        problem, seed, tolerance_scale, tolerance, neighbours, epsilon, dustbin, iterations
    )
    return _run(
        "optimal_transport", problem, threshold, started, eps, neighbours, epsilon, dustbin,
        iterations,
    )  # fmt: skip


optimal_transport.deterministic = True


@budgeted(context_memory, "the number of objects or neighbours")
def optimal_transport_pose(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    tolerance_scale: float = 0.1,
    tolerance: float | None = None,
    neighbours: int = NEIGHBOURS,
    epsilon: float = 0.1,
    dustbin: float = 0.3,
    iterations: int = 100,
    spread: float = 3.0,
    gate: float = 8.0,
) -> Matching:
    """:func:`optimal_transport` on the affinity times the prior likelihood (``spread``,
    ``gate`` as for :func:`matchers.pose.pose`). Needs ``problem.world1/world2/world_sigma``."""
    started = time.perf_counter()
    eps, epsilon, dustbin = _options(
        problem, seed, tolerance_scale, tolerance, neighbours, epsilon, dustbin, iterations
    )
    likelihood = prior_weights(problem, "optimal_transport_pose", spread, gate)
    return _run(
        "optimal_transport_pose", problem, threshold, started, eps, neighbours, epsilon,
        dustbin, iterations, likelihood,
    )  # fmt: skip


optimal_transport_pose.requires = PRIOR_FIELDS
optimal_transport_pose.deterministic = True
