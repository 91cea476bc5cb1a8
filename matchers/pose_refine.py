"""``pose_refine``: the localisation prior, corrected by the geometry each view measures well.

Each agent's pose error moves all of its objects by one rigid motion of the ground plane,
while positions within a view are precise. So the relative error of the two priors is one 2-D
rigid motion, which the confident matches reveal (ground plane: x, y of the world frame, z up):

    L = prior likelihood;  t0 = consensus translation over the pairs L allows (a vote: every
        candidate pair proposes the shift that would align it; the proposal that aligns most
        objects wins — immune to a confident wrong pair, unlike a mean or median)
    L = likelihood of xy2 + t0 with width and gate x tighten;  matches = Hungarian on L, >= confident
    repeat (at most max_iter):
        (R, t) = robust weighted Procrustes fit of view 2's matched positions onto view 1's,
                 from the current motion (weights L; Tukey biweight, cutoff = tightened gate)
        L = likelihood of R xy2 + t with width and gate x tighten
        matches' = Hungarian on L, >= confident;  stop when matches' == matches

Every fit starts from the uncorrected prior's coordinates (the motion is re-estimated, not
composed), so each round only re-decides which pairs support it.
"""

from __future__ import annotations

import time

import numpy as np

from matchers.blocks.memory_models import pose_refine_memory
from matchers.blocks.prior import PRIOR_FIELDS, check_prior_options, prior_likelihood, require_prior
from matchers.blocks.rigid2d import consensus_translation, robust_rigid_2d
from matchers.core.discretise import discretise
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.options import check_count, check_problem, check_range, rng_from_seed
from matchers.core.problem import Problem
from matchers.core.result import finish


def refined_prior(
    xy1: np.ndarray,
    xy2: np.ndarray,
    sigma: float,
    spread: float = 2.0,
    gate: float = 8.0,
    tighten: float = 0.5,
    confident: float = 0.1,
    with_rotation: bool = False,
    max_iter: int = 5,
) -> tuple[np.ndarray, dict]:
    """(n, m) likelihood of the prior after removing the relative rigid error (see the module
    docstring), and info: ``rounds`` (fits made), ``converged``, ``yaw_deg`` and
    ``shift_m`` (the correction applied to view 2), ``support`` (pairs in the last fit).
    When no pair is within the gate the prior is returned uncorrected; when none is confident
    after the consensus shift, it is returned with that shift alone (``rounds`` 0)."""
    likelihood = prior_likelihood(xy1, xy2, sigma, spread, gate)
    info = {"rounds": 0, "converged": True, "yaw_deg": 0.0, "shift_m": [0.0, 0.0], "support": 0}
    if not likelihood.any():
        return likelihood, info
    cutoff = gate * tighten * sigma
    vote = spread * tighten * sigma  # aligned, objects meet within the tightened width
    top = np.argsort(-likelihood, axis=None, kind="stable")[: min(256, int((likelihood > 0).sum()))]
    candidates = np.zeros(likelihood.size, dtype=bool)
    candidates[top] = True
    motion = (
        np.eye(2),
        consensus_translation(xy2, xy1, candidates.reshape(likelihood.shape), vote),
    )

    def aligned(turn: np.ndarray, shift: np.ndarray) -> np.ndarray:
        return prior_likelihood(xy1, xy2 @ turn.T + shift, sigma, spread * tighten, gate * tighten)

    likelihood = aligned(*motion)
    pairs = discretise(likelihood, confident)
    info["shift_m"] = [float(v) for v in motion[1]]
    for rounds in range(1, max_iter + 1):
        if not len(pairs):
            break
        i, j = pairs[:, 0], pairs[:, 1]
        turn, shift, _ = robust_rigid_2d(
            xy2[j], xy1[i], likelihood[i, j], cutoff, with_rotation, start=motion
        )
        motion = (turn, shift)
        likelihood = aligned(turn, shift)
        info |= {
            "rounds": rounds,
            "yaw_deg": float(np.degrees(np.arctan2(turn[1, 0], turn[0, 0]))),
            "shift_m": [float(shift[0]), float(shift[1])],
            "support": len(pairs),
        }
        new_pairs = discretise(likelihood, confident)
        info["converged"] = bool(np.array_equal(new_pairs, pairs))
        if info["converged"]:
            break
        pairs = new_pairs
    return likelihood, info


def pose_likelihood(
    problem: Problem, matcher: str, spread: float, gate: float, refine: bool = False
) -> tuple[np.ndarray, dict]:
    """(n, m) prior likelihood for ``matcher`` (checked options ``spread``, ``gate``): as
    stated (:func:`~matchers.blocks.prior.prior_likelihood`) or, with ``refine``, after removing the
    relative rigid error with :func:`refined_prior`'s defaults. Info: ``gate_m`` and, refined,
    the refinement's info. ValueError naming world1/world_sigma if the prior is missing."""
    spread, gate = check_prior_options(spread, gate)
    xy1, xy2, sigma = require_prior(problem, matcher)
    info = {"gate_m": gate * sigma}
    if not refine:
        return prior_likelihood(xy1, xy2, sigma, spread, gate), info
    likelihood, refined = refined_prior(xy1, xy2, sigma, spread, gate)
    return likelihood, info | {"refined": refined}


@budgeted(pose_refine_memory, "the number of objects")
def pose_refine(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    spread: float = 4.0,
    gate: float = 8.0,
    tighten: float = 0.5,
    confident: float = 0.1,
    rotation: bool = True,
    max_iter: int = 5,
) -> Matching:
    """Pose matching with the prior's relative rigid error estimated and removed (module
    docstring, :func:`refined_prior`), then Hungarian.

    Options: ``spread`` (4) and ``gate`` (8) of the first round as for :func:`matchers.pose.pose`
    (multiples of world_sigma); ``tighten`` (0.5) — the factor on width and gate once the
    views are aligned; ``confident`` (0.1) — least likelihood of a match that may support the
    fit; ``rotation`` (True) — fit the yaw as well as the translation (False: translation
    only);
    ``max_iter`` (5) fits.
    Scores: the refined likelihood in [0, 1] (absolute, as ``pose``). Needs
    ``problem.world1/world2/world_sigma``. Deterministic; ``seed`` unused.

    >>> xy = np.array([[0, 0, 0], [8, 1, 0], [3, 9, 0], [-6, 4, 0]], dtype=float)
    >>> p = Problem(xy, xy, world1=xy, world2=xy + [2.5, -2.0, 0], world_sigma=1.2)
    >>> pose_refine(p, threshold=0.5).pairs.tolist()
    [[0, 0], [1, 1], [2, 2], [3, 3]]
    """
    started = time.perf_counter()
    check_problem(problem)
    rng_from_seed(seed)
    spread, gate = check_prior_options(spread, gate)
    tighten = check_range("tighten", tighten, 0.0, 1.0, open_low=True)
    confident = check_range("confident", confident, 0.0, 1.0)
    check_count("max_iter", max_iter)
    xy1, xy2, sigma = require_prior(problem, "pose_refine")
    scores, info = refined_prior(
        xy1, xy2, sigma, spread, gate, tighten, confident, bool(rotation), max_iter
    )
    return finish("pose_refine", scores, threshold, started, info["rounds"], info)


pose_refine.requires = PRIOR_FIELDS

pose_refine.deterministic = True  # the result does not depend on `seed`
