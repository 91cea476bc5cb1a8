"""``pose_appearance``: the localisation prior's likelihood times appearance similarity."""

from __future__ import annotations

import time

from .appearance_similarity import appearance_similarity
from .matching import Matching
from .memory_budget import budgeted
from .memory_models import unary_memory
from .options import check_problem, rng_from_seed
from .pose_refine import pose_likelihood
from .prior import PRIOR_FIELDS
from .problem import Problem
from .result import finish


@budgeted(unary_memory, "the number of objects")
def pose_appearance(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    spread: float = 2.0,
    gate: float = 8.0,
    refine: bool = False,
) -> Matching:
    """Scores = L_ij * b_ij in [0, 1]: the prior likelihood (options ``spread``, ``gate`` as
    for :func:`matchers.pose.pose`; ground plane, z up; with ``refine`` the prior corrected
    as :func:`matchers.pose_refine.pose_refine` does) times the appearance similarity b
    (cosine, :func:`~matchers.appearance_similarity.appearance_similarity`; 1 without
    features), then Hungarian. Absolute scale, not max-normalised. Needs
    ``problem.world1/world2/world_sigma``. Deterministic; ``seed`` unused.

    >>> import numpy as np
    >>> p = Problem(np.zeros((2, 3)), np.zeros((2, 3)), [[1, 0], [0, 1]], [[0, 1], [1, 0]],
    ...             world1=np.zeros((2, 3)), world2=np.zeros((2, 3)), world_sigma=1.0)
    >>> pose_appearance(p, threshold=0.5).pairs.tolist()  # the prior cannot tell; appearance can
    [[0, 1], [1, 0]]
    """
    started = time.perf_counter()
    check_problem(problem)
    rng_from_seed(seed)
    likelihood, info = pose_likelihood(problem, "pose_appearance", spread, gate, bool(refine))
    scores = likelihood * appearance_similarity(problem)
    info["features"] = problem.features1 is not None
    return finish("pose_appearance", scores, threshold, started, 0, info)


pose_appearance.requires = PRIOR_FIELDS

pose_appearance.deterministic = True  # the result does not depend on `seed`
