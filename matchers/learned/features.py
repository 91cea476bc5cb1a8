"""The candidate-pair features of the learned matchers: one row per candidate match (i, j), in
the a = i * m + j order, computed from one :class:`~matchers.core.problem.Problem`.

Every feature is either invariant to the rigid motion between the two vehicles or a property of
one detection in its own camera frame, so that a model trained on one dataset can be applied to
another (sim-to-external transfer). Three evidence scores, each with three relative forms:

* ``appearance``: cosine similarity of the appearance features, clipped to [0, 1] (1 without
  features);
* ``context``: local context (:func:`~matchers.blocks.local_context.context_similarity`) — how
  well the distances to the 6 nearest objects agree, tolerance 0.15 × the median within-view
  distance;
* ``consistency``: the prior-free consistency matcher's support of (i, j)
  (:func:`matchers.consistency.consistency`, defaults) — the share of the largest mutually
  distance-consistent set of matches that agrees with it;

``<score>_row`` = score / the largest in its row, ``<score>_col`` = score / the largest in its
column (0 when that is 0), ``<score>_mutual`` = 1 when (i, j) is the best of both. Then
``class_same`` (1 / 0, NaN without class labels), ``depth1`` / ``depth2`` (metres from each
camera), ``depth_gap`` and ``bearing1`` / ``bearing2`` (first position axis over the distance:
the sine of the horizontal bearing in a camera frame whose first axis points right).

The prior variant (``prior=True``) adds the localisation prior: ``prior_gap`` (ground-plane
distance between the two world positions over the stated sigma), and the refined prior's score
(:func:`matchers.pose_refine.pose_refine`, defaults) as ``prior`` with its three relative forms.

Every value is rounded to 1e-6 (``DECIMALS``), so that the last-bit differences of BLAS kernels
and SIMD code paths between CPUs do not reach the model. Bump :data:`FEATURES_VERSION` when a
feature changes: model files record it and are refused by code that computes other features.
"""

from __future__ import annotations

import numpy as np

from matchers.blocks.appearance_similarity import appearance_similarity
from matchers.blocks.local_context import NEIGHBOURS, context_similarity
from matchers.blocks.prior import require_prior
from matchers.core.problem import Problem
from matchers.core.scale import median_spacing

FEATURES_VERSION = 1
DECIMALS = 6
CONTEXT_TOLERANCE_SCALE = 0.15
_RELATIVE = ("", "_row", "_col", "_mutual")
_SCORES = ("appearance", "context", "consistency")
_GEOMETRY = ("class_same", "depth1", "depth2", "depth_gap", "bearing1", "bearing2")


def feature_names(prior: bool) -> list[str]:
    """The feature columns, in order, of the plain (``prior=False``) or prior variant."""
    names = [s + r for s in _SCORES for r in _RELATIVE] + list(_GEOMETRY)
    if prior:
        names += ["prior_gap"] + ["prior" + r for r in _RELATIVE]
    return names


def relative_forms(score: np.ndarray) -> list[np.ndarray]:
    """(n, m) ``score`` -> [score, score / row max, score / column max, mutual-best flag]."""
    row = score.max(axis=1, keepdims=True)
    col = score.max(axis=0, keepdims=True)
    by_row = np.divide(score, row, out=np.zeros_like(score), where=row > 0)
    by_col = np.divide(score, col, out=np.zeros_like(score), where=col > 0)
    mutual = ((score == row) & (score == col) & (score > 0)).astype(float)
    return [score, by_row, by_col, mutual]


def _class_same(problem: Problem) -> np.ndarray:
    n, m = problem.n1, problem.n2
    if problem.classes1 is None:
        return np.full((n, m), np.nan)
    c1 = np.asarray(problem.classes1, dtype=object)
    c2 = np.asarray(problem.classes2, dtype=object)
    return (c1[:, None] == c2[None, :]).astype(float)


def _own_frame(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(distance from the camera, first axis / distance) of each detection."""
    depth = np.sqrt((points**2).sum(axis=1))
    bearing = np.divide(points[:, 0], depth, out=np.zeros_like(depth), where=depth > 0)
    return depth, bearing


def _consistency_scores(problem: Problem) -> np.ndarray:
    from matchers.consistency import consistency

    return consistency(problem, threshold=None).scores


def _prior_columns(problem: Problem) -> list[np.ndarray]:
    from matchers.pose_refine import pose_refine

    xy1, xy2, sigma = require_prior(problem, "learned_pose")
    gap = np.sqrt(((xy1[:, None, :] - xy2[None, :, :]) ** 2).sum(axis=-1))
    refined = pose_refine(problem, threshold=None).scores
    return [gap / sigma, *relative_forms(refined)]


def pair_features(problem: Problem, prior: bool = False) -> np.ndarray:
    """(n * m, F) float64 features of every candidate match (module docstring), rows in the
    a = i * m + j order, columns as :func:`feature_names`. ``prior=True`` needs the problem's
    localisation prior (ValueError naming the missing field)."""
    n, m = problem.n1, problem.n2
    width = len(feature_names(prior))
    if n == 0 or m == 0:
        return np.zeros((n * m, width))
    spacing = median_spacing(problem.points1, problem.points2)
    tolerance = max(CONTEXT_TOLERANCE_SCALE * spacing, 1e-9)
    context = context_similarity(problem.points1, problem.points2, NEIGHBOURS, tolerance)
    depth1, bearing1 = _own_frame(problem.points1)
    depth2, bearing2 = _own_frame(problem.points2)
    ones = np.ones((n, m))
    columns = [
        *relative_forms(appearance_similarity(problem)),
        *relative_forms(context),
        *relative_forms(_consistency_scores(problem)),
        _class_same(problem),
        depth1[:, None] * ones,
        depth2[None, :] * ones,
        np.abs(depth1[:, None] - depth2[None, :]),
        bearing1[:, None] * ones,
        bearing2[None, :] * ones,
    ]
    if prior:
        columns += _prior_columns(problem)
    table = np.stack([c.reshape(-1) for c in columns], axis=1)
    return np.round(table, DECIMALS)
