"""``maximin_pose``: maximin hypergraph matching given what a connected vehicle knows — the
localisation prior's likelihood folded into maximin's first-order (appearance) term.

    b'_ij = b_ij * L_ij      b: cosine appearance similarity, L: prior likelihood (ground plane)

b' replaces b everywhere Algorithm 1 uses it: the worst-case tensor of Eqs. (5)-(6) (a
hyperedge is as strong as its least likely match, so hyperedges through pairs the prior rules
out vanish) and the appearance jump of Eq. (7). Everything else is :func:`matchers.maximin.maximin`
unchanged (this module only builds b' and calls it).
"""

from __future__ import annotations

import time

from .appearance_similarity import appearance_similarity
from .matching import Matching
from .maximin import maximin
from .memory_budget import budgeted
from .memory_models import tensor_matcher
from .options import check_problem
from .pose_refine import pose_likelihood
from .prior import PRIOR_FIELDS
from .problem import Problem


@budgeted(tensor_matcher("maximin"), "max_tensor_entries, triangles or neighbours")
def maximin_pose(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    spread: float = 2.0,
    gate: float = 8.0,
    refine: bool = False,
    **options,
) -> Matching:
    """Maximin with b' = b * L (module docstring). ``spread`` (2) and ``gate`` (8) shape the
    prior likelihood L as for :func:`matchers.pose.pose` (multiples of world_sigma; ground
    plane x, y, z up); ``refine`` (False) first corrects the prior's relative rigid error as
    :func:`matchers.pose_refine.pose_refine` does; every other option is :func:`~matchers.maximin.maximin`'s (tensor,
    alpha, beta, init, ...), except ``first_order``, which this matcher sets. Scores as
    maximin's (x / max). Needs ``problem.world1/world2/world_sigma``.

    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> xyz = rng.uniform(-20, 20, (6, 3)) * [1, 1, 0]
    >>> p = Problem(xyz, xyz[::-1], world1=xyz, world2=xyz[::-1] + 0.5, world_sigma=1.0)
    >>> maximin_pose(p, threshold=0.5).pairs[:, 1].tolist()
    [5, 4, 3, 2, 1, 0]
    """
    started = time.perf_counter()
    check_problem(problem)
    if "first_order" in options:
        raise TypeError("maximin_pose() sets first_order itself; pass spread/gate instead")
    likelihood, info = pose_likelihood(problem, "maximin_pose", spread, gate, bool(refine))
    b = appearance_similarity(problem) * likelihood
    matching = maximin(problem, seed, threshold, first_order=b, **options)
    matching.name = "maximin_pose"
    matching.info |= info
    matching.time_s = time.perf_counter() - started
    return matching


maximin_pose.requires = PRIOR_FIELDS
