"""matchers: object correspondence by (hyper)graph matching, usable on its own.

    from matchers import Problem, get, available
    matching = get("maximin")(Problem(points1, points2, features1, features2), seed=0)
    matching.pairs   # (k, 2) int array of (i, j)
    matching.scores  # (n, m) soft scores in [0, 1]

Optional Problem fields: ``pixels1/pixels2`` (box centres, for ``pairwise="image"``) and the
localisation prior ``world1/world2/world_sigma`` (for the ``pose*`` matchers and
``maximin_pose``; :func:`requires` names what a matcher needs). Each matcher has a tuning
grid relative to the problem's own scale, :func:`search_space`.

Index convention (a = i * m + j) in :mod:`matchers.core.indexing`; algorithms, defaults and grids in
docs/matchers.md.
"""

from matchers.core.matching import Matching
from matchers.core.memory_budget import ProblemTooLarge
from matchers.core.plugin_guard import PluginError, PluginTimeout
from matchers.core.problem import Problem
from matchers.core.registry import (
    ENTRY_POINT_GROUP,
    available,
    deterministic,
    get,
    register,
    required_options,
    requires,
    search_space,
    usable,
)
from matchers.hypergraph.sparse_tensor import SparseTensor
from matchers.hypergraph.tensor_build import build_tensor
from matchers.hypergraph.tensor_sharing import shared_tensors

__all__ = [
    "ENTRY_POINT_GROUP",
    "Matching",
    "PluginError",
    "PluginTimeout",
    "Problem",
    "ProblemTooLarge",
    "SparseTensor",
    "available",
    "build_tensor",
    "deterministic",
    "get",
    "register",
    "required_options",
    "requires",
    "search_space",
    "shared_tensors",
    "usable",
]
