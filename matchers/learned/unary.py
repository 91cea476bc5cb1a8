"""``maximin_learned`` and ``rrwm_learned``: the learned affinity of :mod:`matchers.learned` as the
unary term of a higher-order matcher — does geometry beyond pairs add anything once the unary is
learned?

* ``maximin_learned``: maximin with b = the classifier's P(match) (the ``first_order`` option:
  the worst-case tensor of Eqs. (5)-(6) and the jump of Eq. (7)); every other option is
  maximin's.
* ``rrwm_learned``: RRWM on the pairwise affinity K weighted by the unary, K'[a, b] = K[a, b] u_a
  u_b (a candidate match's walk weight falls with its learned probability); every other option
  is RRWM's.

Both need ``model`` (a model file's path) and use its plain (prior-free) classifier.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from matchers.blocks.memory_models import learned_memory, pairwise_matcher, tensor_matcher
from matchers.blocks.pairwise import NEIGHBOURS, resolve_affinity
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.options import check_problem
from matchers.core.problem import Problem
from matchers.learned.matcher import REQUIRED_OPTIONS, learned_probability
from matchers.maximin import maximin
from matchers.rrwm import rrwm


def unary_weighted(
    affinity: np.ndarray | sp.spmatrix, unary: np.ndarray
) -> np.ndarray | sp.spmatrix:
    """K'[a, b] = K[a, b] * u[a] * u[b] for a dense or scipy-sparse (nm, nm) K and (nm,) u."""
    u = np.asarray(unary, dtype=float).reshape(-1)
    if sp.issparse(affinity):
        weighted = sp.csr_matrix(affinity, dtype=float, copy=True)
        rows = np.repeat(np.arange(weighted.shape[0]), np.diff(weighted.indptr))
        weighted.data *= u[rows] * u[weighted.indices]
        return weighted
    return np.asarray(affinity, dtype=float) * u[:, None] * u[None, :]


def _renamed(matching: Matching, name: str, started: float, model: str) -> Matching:
    matching.name = name
    matching.info |= {"model": str(model)}
    matching.time_s = time.perf_counter() - started
    return matching


@budgeted(learned_memory(False, tensor_matcher("maximin")), "max_tensor_entries or the objects")
def maximin_learned(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    model: str | None = None,
    model_sha256: str | None = None,
    **options,
) -> Matching:
    """Maximin with the learned P(match) as its first-order term b (module docstring); scores as
    maximin's (x / max). Needs ``model``."""
    started = time.perf_counter()
    check_problem(problem)
    if "first_order" in options:
        raise TypeError("maximin_learned() sets first_order itself")
    unary = learned_probability(problem, model, model_sha256, "learned")
    matching = maximin(problem, seed, threshold, first_order=unary, **options)
    return _renamed(matching, "maximin_learned", started, model)


@budgeted(learned_memory(False, pairwise_matcher("rrwm")), "affinity_neighbours or the objects")
def rrwm_learned(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    model: str | None = None,
    model_sha256: str | None = None,
    sigma2: float | None = None,
    sigma_scale: float | None = None,
    pairwise: str = "positions",
    affinity_neighbours: int | None = NEIGHBOURS,
    **options,
) -> Matching:
    """RRWM on K'[a, b] = K[a, b] u_a u_b (module docstring): K is RRWM's own affinity
    (``sigma2`` / ``sigma_scale``, ``pairwise``, ``affinity_neighbours``), u the learned
    P(match); every other option is RRWM's. Needs ``model``. Deterministic."""
    started = time.perf_counter()
    check_problem(problem)
    if "affinity" in options:
        raise TypeError("rrwm_learned() builds its affinity itself")
    unary = learned_probability(problem, model, model_sha256, "learned")
    affinity = resolve_affinity(problem, None, sigma2, sigma_scale, pairwise, affinity_neighbours)
    weighted = unary_weighted(affinity, unary)
    matching = rrwm(problem, seed, threshold, affinity=weighted, **options)
    return _renamed(matching, "rrwm_learned", started, model)


for _fn in (maximin_learned, rrwm_learned):
    _fn.required_options = REQUIRED_OPTIONS
rrwm_learned.deterministic = True  # the result does not depend on `seed`
