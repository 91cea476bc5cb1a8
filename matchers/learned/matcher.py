"""``learned`` and ``learned_pose``: a learned pairwise affinity — a gradient-boosted classifier's
probability that (i, j) is a true match, from the candidate-pair features of
:mod:`matchers.learned.features` (appearance, local context, distance consistency, class,
depth and bearing; ``learned_pose`` adds the localisation prior) — then the shared Hungarian and
τ, as every matcher. The classifier comes from a model file written by ``cadsim train``
(:mod:`matchers.learned.model`): option ``model`` (its path) is required, ``model_sha256``
(optional) pins its content.

Variants ``maximin_learned`` and ``rrwm_learned`` (:mod:`matchers.learned.unary`) use the same
probability as the unary term of maximin and RRWM.
"""

from __future__ import annotations

import time

import numpy as np

from matchers.blocks.memory_models import learned_memory
from matchers.blocks.prior import PRIOR_FIELDS
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.options import check_problem, rng_from_seed
from matchers.core.problem import Problem
from matchers.core.result import finish
from matchers.learned.features import pair_features
from matchers.learned.model import VARIANTS, load_model

REQUIRED_OPTIONS = ("model",)


def learned_probability(
    problem: Problem, model: str | None, model_sha256: str | None, variant: str
) -> np.ndarray:
    """(n, m) P(match) of every candidate match under ``variant``'s classifier of the model file
    at ``model``; ValueError when no model is given or it cannot be used."""
    if model is None:
        raise ValueError(
            f"model: matcher {variant!r} needs a model file (option model=PATH, written by "
            "`cadsim train`; `cadsim evaluate --model PATH`)"
        )
    loaded = load_model(model, model_sha256)
    n, m = problem.n1, problem.n2
    features = pair_features(problem, VARIANTS[variant])
    return np.clip(loaded.predict(variant, features), 0.0, 1.0).reshape(n, m)


def _learned(name: str, problem: Problem, seed, threshold, model, model_sha256) -> Matching:
    started = time.perf_counter()
    check_problem(problem)
    rng_from_seed(seed)
    scores = learned_probability(problem, model, model_sha256, name)
    return finish(name, scores, threshold, started, 0, {"model": str(model)})


@budgeted(learned_memory(False), "the number of objects")
def learned(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    model: str | None = None,
    model_sha256: str | None = None,
) -> Matching:
    """Scores = the classifier's P(match) in [0, 1] (an absolute scale: τ reads as a
    probability), then Hungarian. Needs ``model`` (a model file's path). Deterministic."""
    return _learned("learned", problem, seed, threshold, model, model_sha256)


@budgeted(learned_memory(True), "the number of objects")
def learned_pose(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    model: str | None = None,
    model_sha256: str | None = None,
) -> Matching:
    """As :func:`learned`, with the localisation prior among the features. Needs ``model`` and
    ``problem.world1/world2/world_sigma``. Deterministic."""
    return _learned("learned_pose", problem, seed, threshold, model, model_sha256)


for _fn in (learned, learned_pose):
    _fn.deterministic = True  # the result does not depend on `seed`
    _fn.required_options = REQUIRED_OPTIONS
learned_pose.requires = PRIOR_FIELDS
