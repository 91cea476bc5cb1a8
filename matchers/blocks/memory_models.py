"""How much working memory each built-in matcher needs, before it runs.

Every matcher is wrapped by :func:`matchers.core.memory_budget.budgeted` with one of the estimates
below: the call is refused (:class:`~matchers.core.memory_budget.ProblemTooLarge`) before anything large
is allocated when the estimate exceeds the budget. Each estimate follows the arrays the algorithm
builds, was calibrated as an upper envelope (a few per cent above) of the peak that
``tracemalloc`` measures (views of 20-150 objects,
defaults; ``tests/test_matchers_budget.py`` holds every registered matcher to within 1.5× of its
measured peak wherever the peak is above 10 MB):

- pairwise affinity (SM, RRWM, MOS's second order): bytes per kept entry of the sparse (nm, nm)
  affinity, nm × min(``affinity_neighbours``, (n-1)(m-1)) entries, or 24 per entry dense;
- third-order tensor (HGM, TM, BCAGM, RRWHM, maximin, MOS's third order): per entry, for the
  uncapped build (entries ≤ ``max_tensor_entries``) a matcher's own cost, for the capped build
  (radius search, ranking) 92 bytes, plus 200 per triangle of the searched view rising to 350
  at 2 million triangles (its k-d tree and radius search live outside Python's allocator:
  calibrated on the process's resident memory at 100-300 objects);
- consistency: 24 bytes per pair of candidate matches (its dense (nm)², differences, weights);
- pose_refine: 50 bytes per candidate match and translation hypothesis (≤ 256 hypotheses);
- the local-context baselines (CBM, FreeAlign, optimal transport): 9 bytes per candidate match
  and pair of neighbours (the (n, m, k, k) distance comparison), plus a few (n, m) arrays;
- the unary matchers: a few (n, m) float arrays.

An option the matcher will refuse (a negative count, a string) gives an estimate of 0 here, so
the matcher's own check names it.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from matchers.blocks.pairwise import NEIGHBOURS
from matchers.blocks.prior import check_prior_options, prior_likelihood
from matchers.core.problem import Problem
from matchers.hypergraph.tensor_build import MAX_ENTRIES, planned_entries

Estimate = Callable[..., float]

PAIRWISE_BYTES = {"sm": 54.0, "rrwm": 60.0, "mos": 57.0}
DENSE_PAIRWISE_BYTES = 24.0
TENSOR_UNCAPPED_BYTES = {"hgm": 41.0, "tm": 41.0, "rrwhm": 44.0, "maximin": 52.0, "bcagm": 81.0}
TENSOR_CAPPED_BYTES = 92.0
TENSOR_STORED_BYTES = 32.0  # a built tensor's three indices and value, while MOS walks
TRIANGLE_BYTES = (200.0, 350.0, 2e6)  # per triangle: 200 rising to 350 at 2 million triangles
CONSISTENCY_BYTES = 25.0
CONTEXT_BYTES = 9.0  # per candidate match and neighbour pair: float64 difference + bool test
CONTEXT_MATCH_BYTES = 160.0  # per candidate match: similarity, priorities, residuals, plan
HYPOTHESIS_BYTES = 50.0
HYPOTHESES = 256
UNARY_BYTES = 48.0


def _count(value, default: int) -> int | None:
    """A positive count option (None: `default`); None when the value is not one."""
    if value is None:
        return default
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        return None
    return int(value)


def pairwise_entries(problem: Problem, neighbours=NEIGHBOURS) -> tuple[float, bool] | None:
    """(entries, dense) of the pairwise affinity with ``affinity_neighbours`` = `neighbours`."""
    n, m = problem.n1, problem.n2
    if neighbours is None:
        return float(n * m) ** 2, True
    keep = _count(neighbours, NEIGHBOURS)
    if keep is None:
        return None
    return float(n * m) * min(keep, max((n - 1) * (m - 1), 0)), False


def tensor_sizes(problem: Problem, options: dict) -> tuple[float, float, bool] | None:
    """(entries, triangles searched, capped) of the third-order tensor the options ask for."""
    n, m = problem.n1, problem.n2
    if n < 3 or m < 3 or not isinstance(options.get("tensor", "paper"), str):
        return 0.0, 0.0, False
    sampled, full = min(n, m), max(n, m)
    triangles = _count(options.get("triangles"), n * m)
    k = _count(options.get("neighbours"), n * m)
    raw_cap = options.get("max_tensor_entries", MAX_ENTRIES)
    cap = None if raw_cap is None else _count(raw_cap, MAX_ENTRIES)
    if triangles is None or k is None or (raw_cap is not None and cap is None):
        return None
    entries, searched, capped = planned_entries(sampled, full, triangles, k, cap)
    return float(entries), float(searched), capped


def _tensor_bytes(problem: Problem, options: dict, matcher: str) -> float:
    sizes = tensor_sizes(problem, options)
    if sizes is None:
        return 0.0
    entries, triangles, capped = sizes
    per_entry = TENSOR_CAPPED_BYTES if capped else TENSOR_UNCAPPED_BYTES[matcher]
    low, high, full_at = TRIANGLE_BYTES
    per_triangle = low + (high - low) * min(1.0, triangles / full_at)
    return entries * per_entry + per_triangle * triangles * capped


def _unary(problem: Problem) -> float:
    n, m = problem.n1, problem.n2
    d = 0 if problem.features1 is None else problem.features1.shape[1]
    return UNARY_BYTES * n * m + 8.0 * (n + m) * d


def pairwise_matcher(name: str) -> Estimate:
    """The estimate of SM or RRWM."""

    def estimate(problem: Problem, **options) -> float:
        found = pairwise_entries(problem, options.get("affinity_neighbours", NEIGHBOURS))
        if found is None:
            return 0.0
        entries, dense = found
        return entries * (DENSE_PAIRWISE_BYTES if dense else PAIRWISE_BYTES[name]) + _unary(problem)

    estimate.__name__ = f"{name}_memory"
    return estimate


def tensor_matcher(name: str) -> Estimate:
    """The estimate of a hypergraph matcher (``name`` picks its uncapped per-entry cost)."""

    def estimate(problem: Problem, **options) -> float:
        return _tensor_bytes(problem, options, name) + _unary(problem)

    estimate.__name__ = f"{name}_memory"
    return estimate


def mos_memory(problem: Problem, **options) -> float:
    """MOS: the tensor build, then the built tensor beside the pairwise affinity."""
    found = pairwise_entries(problem, options.get("affinity_neighbours", NEIGHBOURS))
    sizes = tensor_sizes(problem, options)
    if found is None or sizes is None:
        return 0.0
    entries, dense = found
    pairwise = entries * (DENSE_PAIRWISE_BYTES if dense else PAIRWISE_BYTES["mos"])
    build = _tensor_bytes(problem, options, "maximin")
    return max(build, sizes[0] * TENSOR_STORED_BYTES + pairwise) + _unary(problem)


def consistency_memory(problem: Problem, **options) -> float:
    return CONSISTENCY_BYTES * float(problem.n1 * problem.n2) ** 2 + _unary(problem)


def pose_refine_memory(problem: Problem, **options) -> float:
    """pose_refine: its translation vote holds (hypotheses, n, m, 2) residuals, one hypothesis per
    pair the first-round likelihood keeps (at most 256): counted from that O(nm) likelihood."""
    nm = problem.n1 * problem.n2
    hypotheses = min(HYPOTHESES, nm)
    if problem.world1 is not None and problem.world_sigma is not None and nm:
        try:
            spread, gate = check_prior_options(options.get("spread", 4.0), options.get("gate", 8.0))
        except ValueError:
            return 0.0
        likelihood = prior_likelihood(
            problem.world1[:, :2], problem.world2[:, :2], problem.world_sigma, spread, gate
        )
        hypotheses = min(HYPOTHESES, int(np.count_nonzero(likelihood)))
    return HYPOTHESIS_BYTES * hypotheses * float(nm) + _unary(problem)


def context_memory(problem: Problem, neighbours=6, **options) -> float:
    """The local-context baselines (:mod:`matchers.blocks.local_context`): the neighbour-pair
    comparison of every candidate match, a few (n, m) arrays and the within-view distances."""
    k = _count(neighbours, 6)
    if k is None:
        return 0.0
    n, m = problem.n1, problem.n2
    pairs = float(n * m)
    return (
        CONTEXT_BYTES * pairs * k * k
        + CONTEXT_MATCH_BYTES * pairs
        + 24.0 * (n * n + m * m)
        + _unary(problem)
    )


def unary_memory(problem: Problem, **options) -> float:
    return _unary(problem)


def prior_evidence_memory(
    spread: float, gate: float, refine: bool, also: Estimate | None = None
) -> Estimate:
    """pose_appearance / maximin_pose: with ``refine`` (default as given) the refined prior's
    translation vote (:func:`pose_refine_memory` at the matcher's own spread and gate), else the
    plain likelihood; ``also`` (maximin's tensor) runs after it, so the larger of the two."""

    def estimate(problem: Problem, **options) -> float:
        if options.get("refine", refine):
            prior = pose_refine_memory(
                problem, spread=options.get("spread", spread), gate=options.get("gate", gate)
            )
        else:
            prior = _unary(problem)
        return prior if also is None else max(prior, also(problem, **options))

    return estimate


FEATURE_BYTES = 8.0 * 40  # per candidate match: the learned matchers' feature row and its copies


def learned_memory(prior: bool, also: Estimate | None = None) -> Estimate:
    """The learned matchers (:mod:`matchers.learned`): their features' largest step — the
    consistency support (dense (nm)^2), the local context, with the prior the refined prior's
    vote — plus the feature table; ``also`` (the matcher that takes the learned unary) runs
    after it, so the larger of the two."""

    def estimate(problem: Problem, **options) -> float:
        steps = [consistency_memory(problem), context_memory(problem)]
        if prior:
            steps.append(pose_refine_memory(problem))
        own = max(steps) + FEATURE_BYTES * problem.n1 * problem.n2
        return own if also is None else max(own, also(problem, **options))

    return estimate
