"""``pose``: the baseline every connected vehicle has — Hungarian assignment on the
localisation prior alone (each agent's own noisy world positions of its objects), gated by the
prior's stated uncertainty. No appearance, no within-view geometry.

Variant ``pose_appearance`` (below): the prior's likelihood times the appearance similarity.
"""

from __future__ import annotations

import time

from matchers.blocks.appearance_similarity import appearance_similarity
from matchers.blocks.memory_models import prior_evidence_memory, unary_memory
from matchers.blocks.prior import PRIOR_FIELDS, check_prior_options, prior_likelihood, require_prior
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.options import check_problem, rng_from_seed
from matchers.core.problem import Problem
from matchers.core.result import finish
from matchers.pose_refine import pose_likelihood


@budgeted(unary_memory, "the number of objects")
def pose(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    spread: float = 3.0,
    gate: float = 8.0,
) -> Matching:
    """Match by the localisation prior: scores = the prior likelihood L_ij in [0, 1] of the
    ground-plane (x, y; z up) distance between the two views' world positions
    (:func:`~matchers.blocks.prior.prior_likelihood`: Gaussian with ``spread`` x world_sigma per view
    and axis, 0 beyond ``gate`` x world_sigma), used as is — an absolute scale, so tau reads as
    a likelihood (a distance). Hungarian maximises the summed likelihood. Needs
    ``problem.world1/world2/world_sigma`` (ValueError naming the missing one). Deterministic;
    ``seed`` unused. Noise-free priors (both views exact) give the true matching exactly.

    >>> import numpy as np
    >>> p = Problem(np.zeros((2, 3)), np.zeros((2, 3)), world1=[[0, 0, 0], [10, 0, 0]],
    ...             world2=[[10.5, 0, 0], [0.3, 0, 0]], world_sigma=1.0)
    >>> pose(p, threshold=0.5).pairs.tolist()
    [[0, 1], [1, 0]]
    """
    started = time.perf_counter()
    check_problem(problem)
    rng_from_seed(seed)
    spread, gate = check_prior_options(spread, gate)
    xy1, xy2, sigma = require_prior(problem, "pose")
    scores = prior_likelihood(xy1, xy2, sigma, spread, gate)
    return finish("pose", scores, threshold, started, 0, {"gate_m": gate * sigma})


pose.requires = PRIOR_FIELDS

pose.deterministic = True  # the result does not depend on `seed`


@budgeted(prior_evidence_memory(4.0, 8.0, True), "the number of objects, or refine=False")
def pose_appearance(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    spread: float = 4.0,
    gate: float = 8.0,
    refine: bool = True,
) -> Matching:
    """Scores = L_ij * b_ij in [0, 1]: the prior likelihood (options ``spread``, ``gate`` as
    for :func:`matchers.pose.pose`; ground plane, z up; with ``refine`` the prior corrected
    as :func:`matchers.pose_refine.pose_refine` does) times the appearance similarity b
    (cosine, :func:`~matchers.blocks.appearance_similarity.appearance_similarity`; 1 without
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
