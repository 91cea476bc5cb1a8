"""``appearance``: Hungarian assignment on appearance similarity alone (no spatial structure)."""

from __future__ import annotations

import time

from matchers.blocks.appearance_similarity import appearance_similarity
from matchers.blocks.memory_models import unary_memory
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.options import check_problem, rng_from_seed
from matchers.core.problem import Problem
from matchers.core.result import finish


@budgeted(unary_memory, "the number of objects")
def appearance(problem: Problem, seed: int | None = 0, threshold: float | None = None) -> Matching:
    """Match by appearance only: scores = b, the cosine similarity of the features in [0, 1]
    (:func:`~matchers.blocks.appearance_similarity.appearance_similarity`), used as is — an absolute
    scale, not divided by its maximum. The reference point that shows what spatial structure
    adds. Deterministic (``seed`` is accepted for the common signature and unused). Without
    features every score is 1 and the assignment is arbitrary (identity order)."""
    started = time.perf_counter()
    check_problem(problem)
    rng_from_seed(seed)
    scores = appearance_similarity(problem)
    return finish(
        "appearance", scores, threshold, started, 0, {"features": problem.features1 is not None}
    )


appearance.deterministic = True  # the result does not depend on `seed`
