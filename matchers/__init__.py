"""matchers: object correspondence by (hyper)graph matching, usable on its own.

    from matchers import Problem, get, available
    matching = get("maximin")(Problem(points1, points2, features1, features2), seed=0)
    matching.pairs   # (k, 2) int array of (i, j)
    matching.scores  # (n, m) soft scores in [0, 1]

Optional Problem fields: ``pixels1/pixels2`` (box centres, for ``pairwise="image"``) and the
localisation prior ``world1/world2/world_sigma`` (for the ``pose*`` matchers and
``maximin_pose``; :func:`requires` names what a matcher needs). Each matcher has a tuning
grid relative to the problem's own scale, :func:`search_space`.

Index convention (a = i * m + j) in :mod:`matchers.indexing`; algorithms, defaults and grids in
docs/matchers.md.
"""

from .matching import Matching
from .memory_budget import ProblemTooLarge
from .problem import Problem
from .registry import (
    ENTRY_POINT_GROUP,
    available,
    deterministic,
    get,
    register,
    requires,
    search_space,
)
from .sparse_tensor import SparseTensor
from .tensor_build import build_tensor
from .tensor_sharing import shared_tensors

__all__ = [
    "ENTRY_POINT_GROUP",
    "Matching",
    "Problem",
    "ProblemTooLarge",
    "SparseTensor",
    "available",
    "build_tensor",
    "deterministic",
    "get",
    "register",
    "requires",
    "search_space",
    "shared_tensors",
]
