"""``none``: the trivial baseline that declares no match at all.

Every object is declared non-covisible: it shows what a metric awards for abstaining (under
per-object accuracy, the share of non-covisible objects), so every table can carry it.
"""

from __future__ import annotations

import time

import numpy as np

from matchers.blocks.memory_models import unary_memory
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.options import check_problem, rng_from_seed
from matchers.core.problem import Problem


@budgeted(unary_memory, "the number of objects")
def none(problem: Problem, seed: int | None = 0, threshold: float | None = None) -> Matching:
    """Declare no match: scores all 0 and no pairs, whatever ``threshold`` (also None — the one
    matcher that does not return the full assignment then, by definition). Deterministic;
    ``seed`` is accepted for the common signature and unused.

    >>> none(Problem(np.zeros((3, 3)), np.zeros((2, 3)))).pairs.shape
    (0, 2)
    """
    started = time.perf_counter()
    check_problem(problem)
    rng_from_seed(seed)
    if threshold is not None and (
        isinstance(threshold, bool)
        or not isinstance(threshold, int | float | np.number)
        or not np.isfinite(threshold)
    ):
        raise ValueError(f"threshold: expected None or a finite number, got {threshold!r}")
    return Matching(
        pairs=np.zeros((0, 2), dtype=np.int64),
        scores=np.zeros((problem.n1, problem.n2)),
        name="none",
        iterations=0,
        time_s=time.perf_counter() - started,
        info={},
    )


none.deterministic = True  # the result does not depend on `seed`
