"""Pose-free building blocks of the field's V2X association baselines (CBM, FreeAlign, optimal
transport): each object's *local context* — the distances to its nearest neighbours in its own
view, which a rigid motion between the two vehicles leaves unchanged — and a 3-D rigid fit.

Imports nothing from ``cadsim`` or ``eval``.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import cdist

from matchers.blocks.prior import check_prior_options, prior_likelihood, require_prior
from matchers.core.options import check_count, check_problem, check_range, rng_from_seed
from matchers.core.scale import median_spacing

NEIGHBOURS = 6


def neighbour_distances(points: np.ndarray, k: int) -> np.ndarray:
    """(n, k) distances (position units) from each point to its k nearest other points,
    ascending; inf where a view has fewer than k + 1 points."""
    points = np.asarray(points, dtype=float)
    n = len(points)
    out = np.full((n, k), np.inf)
    if n < 2:
        return out
    d = cdist(points, points)
    np.fill_diagonal(d, np.inf)
    near = np.sort(d, axis=1)[:, : min(k, n - 1)]
    out[:, : near.shape[1]] = near
    return out


def context_similarity(
    points1: np.ndarray, points2: np.ndarray, k: int, tolerance: float
) -> np.ndarray:
    """(n, m) similarity in [0, 1] of the local contexts of object i (view 1) and j (view 2):
    each of i's k neighbour distances scores exp(−½ (Δ / tolerance)²) for the closest of j's
    (Δ the difference, metres), and each of j's likewise against i's; the two means, averaged.
    Objects with no neighbour score 0."""
    d1, d2 = neighbour_distances(points1, k), neighbour_distances(points2, k)
    n, m = len(d1), len(d2)
    if n == 0 or m == 0:
        return np.zeros((n, m))
    with np.errstate(invalid="ignore"):  # inf − inf where both views lack a neighbour
        gap = np.abs(d1[:, None, :, None] - d2[None, :, None, :])  # [i, j, a, b]
    gap[~np.isfinite(gap)] = np.inf
    valid1, valid2 = np.isfinite(d1), np.isfinite(d2)
    near1 = np.exp(-0.5 * (gap.min(axis=3) / tolerance) ** 2)  # [i, j, a]
    near2 = np.exp(-0.5 * (gap.min(axis=2) / tolerance) ** 2)  # [i, j, b]
    side1 = np.where(valid1[:, None, :], near1, 0.0).sum(axis=2)
    side2 = np.where(valid2[None, :, :], near2, 0.0).sum(axis=2)
    side1 /= np.maximum(valid1.sum(axis=1), 1)[:, None]
    side2 /= np.maximum(valid2.sum(axis=1), 1)[None, :]
    return np.clip(0.5 * (side1 + side2), 0.0, 1.0)


def rigid_fit(source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """(R (D, D), t (D,)) minimising sum ||R source_k + t − target_k||² (Kabsch; a proper
    rotation; D = 2 or 3, the positions' dimension), or None for fewer than 3 points, points of
    different dimensions, or (in 3-D) collinear ``source``, about which the rotation is free."""
    source, target = np.asarray(source, dtype=float), np.asarray(target, dtype=float)
    if source.ndim != 2 or source.shape != target.shape or len(source) < 3:
        return None
    dim = source.shape[1]
    mu_s, mu_t = source.mean(axis=0), target.mean(axis=0)
    a, b = source - mu_s, target - mu_t
    spread = np.linalg.svd(a, compute_uv=False)
    if not spread[0] > 0 or (dim > 2 and spread[1] < 1e-3 * spread[0]):
        return None
    u, _, vt = np.linalg.svd(b.T @ a)
    fix = np.ones(dim)
    fix[-1] = 1.0 if np.linalg.det(u @ vt) >= 0 else -1.0
    rotation = (u * fix) @ vt
    return rotation, mu_t - rotation @ mu_s


def alignment_scores(
    points1: np.ndarray,
    points2: np.ndarray,
    motion: tuple[np.ndarray, np.ndarray],
    tolerance: float,
) -> np.ndarray:
    """(n, m) scores exp(−r² / (2 tolerance²)) of the residual r between object i of view 1 and
    object j of view 2 moved by ``motion`` (R, t) into view 1's frame."""
    rotation, translation = motion
    moved = np.asarray(points2, dtype=float) @ rotation.T + translation
    residual = cdist(np.asarray(points1, dtype=float), moved)
    return np.exp(-0.5 * (residual / tolerance) ** 2)


def top_candidates(priority: np.ndarray, count: int) -> list[tuple[int, int]]:
    """The ``count`` (i, j) of largest positive ``priority`` (ties: row-major index order)."""
    flat = priority.reshape(-1)
    order = np.argsort(-flat, kind="stable")
    order = order[flat[order] > 0][:count]
    return [divmod(int(a), priority.shape[1]) for a in order]


def tolerance_of(problem, tolerance_scale: float, tolerance: float | None) -> float:
    """eps in position units: ``tolerance`` if given, else ``tolerance_scale`` × the problem's
    median within-view distance (as :func:`matchers.consistency.consistency`)."""
    if tolerance is not None:
        return check_range("tolerance", tolerance, 0.0, np.inf, open_low=True)
    scale = check_range("tolerance_scale", tolerance_scale, 0.0, np.inf, open_low=True)
    return max(scale * median_spacing(problem.points1, problem.points2), 1e-9)


def checked_tolerance(
    problem, seed, tolerance_scale: float, tolerance: float | None, **counts: int
) -> float:
    """The checks every local-context matcher starts with (problem, seed, its positive
    ``counts`` by name); returns eps (:func:`tolerance_of`)."""
    check_problem(problem)
    rng_from_seed(seed)
    for name, value in counts.items():
        check_count(name, value)
    return tolerance_of(problem, tolerance_scale, tolerance)


def prior_weights(problem, matcher: str, spread: float, gate: float) -> np.ndarray:
    """(n, m) prior likelihood a ``_pose`` variant multiplies its ranking by
    (:func:`~matchers.blocks.prior.prior_likelihood`); ValueError naming a missing prior field."""
    spread, gate = check_prior_options(spread, gate)
    xy1, xy2, sigma = require_prior(problem, matcher)
    return prior_likelihood(xy1, xy2, sigma, spread, gate)


def prior_motion(
    points1: np.ndarray, world1: np.ndarray, points2: np.ndarray, world2: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """The view-2-to-view-1 motion (R, t) two noisy poses imply: each view's detections fitted
    to its own prior world positions (a rigid map per view, recovered exactly); None when a view
    has too few non-collinear detections."""
    to_world1, to_world2 = rigid_fit(points1, world1), rigid_fit(points2, world2)
    if to_world1 is None or to_world2 is None:
        return None
    (r1, t1), (r2, t2) = to_world1, to_world2
    return r1.T @ r2, r1.T @ (t2 - t1)
