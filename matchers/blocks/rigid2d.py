"""Rigid motions of the ground plane (rotation about z, then translation), fitted to matched
points: the weighted 2-D Procrustes solution and a robust version of it that a wrong match or
two cannot drag away. Used to estimate the relative error of two agents' localisation.

Imports nothing from ``cadsim`` or ``eval``.
"""

from __future__ import annotations

import numpy as np


def rotation(theta: float) -> np.ndarray:
    """(2, 2) counter-clockwise rotation by ``theta`` radians."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


def procrustes_2d(
    source: np.ndarray, target: np.ndarray, weights: np.ndarray, with_rotation: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """(R (2, 2), t (2,)) minimising sum_k w_k ||R source_k + t - target_k||^2 (closed form).

    R is a proper rotation (no reflection); ``with_rotation=False`` fits the translation alone
    (R = I). Non-negative weights; all-zero weights (or no points) give the identity motion.

    >>> R, t = procrustes_2d(np.array([[0.0, 0.0], [1.0, 0.0]]),
    ...                      np.array([[1.0, 1.0], [1.0, 2.0]]), np.ones(2))
    >>> np.round(R @ [1.0, 0.0] + t, 6).tolist()
    [1.0, 2.0]
    """
    source = np.asarray(source, dtype=float).reshape(-1, 2)
    target = np.asarray(target, dtype=float).reshape(-1, 2)
    weights = np.asarray(weights, dtype=float).reshape(-1)
    total = weights.sum()
    if not total > 0:
        return np.eye(2), np.zeros(2)
    w = weights / total
    source_mean, target_mean = w @ source, w @ target
    turn = np.eye(2)
    if with_rotation:
        a, b = source - source_mean, target - target_mean
        cross = w @ (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
        dot = w @ np.einsum("kd,kd->k", a, b)
        turn = rotation(float(np.arctan2(cross, dot))) if (cross or dot) else np.eye(2)
    return turn, target_mean - turn @ source_mean


def weighted_median(values: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Per-column weighted median of (k, D) ``values`` (the lower one at an exact tie);
    zeros((D,)) when no weight is positive."""
    values = np.asarray(values, dtype=float)
    weights = np.asarray(weights, dtype=float)
    if not weights.sum() > 0:
        return np.zeros(values.shape[1])
    order = np.argsort(values, axis=0, kind="stable")
    sorted_values = np.take_along_axis(values, order, axis=0)
    cumulative = np.cumsum(weights[order], axis=0)
    first = np.argmax(cumulative >= 0.5 * cumulative[-1], axis=0)
    return sorted_values[first, np.arange(values.shape[1])]


def biweight(residual: np.ndarray, cutoff: float) -> np.ndarray:
    """Tukey's biweight (1 - (r / cutoff)^2)^2 for r < cutoff, 0 beyond: full trust in small
    residuals, none in gross ones."""
    u = np.asarray(residual, dtype=float) / cutoff
    return np.where(u < 1.0, (1.0 - u**2) ** 2, 0.0)


def consensus_translation(
    source: np.ndarray,
    target: np.ndarray,
    candidates: np.ndarray,
    cutoff: float,
    limit: int = 256,
) -> np.ndarray:
    """The translation t (2,) that brings most of ``source`` (m, 2) onto ``target`` (n, 2).

    Every candidate pair (i, j) (True in the (n, m) mask ``candidates``; at most ``limit`` of
    them, in row-major order) proposes t = target_i - source_j; each proposal is scored by
    min(sum_i max_j w_ij, sum_j max_i w_ij), w_ij = biweight(|target_i - source_j - t|,
    cutoff) — how many objects it brings close to one of the other view's, counting each
    object once on the sparser side (one point near many counts once: with the score of the
    targets alone, a shift that drops a few sources into a dense crowd of targets outvoted
    the true one when the cutoff was wide) — and the best one wins (ties: the first). A vote
    among hypotheses, so pairs that are wrong, however confident, cannot pull it as they
    would pull a mean or a median. Vectorised: (proposals, n, m) residuals. No candidate
    gives t = 0.
    """
    source = np.asarray(source, dtype=float).reshape(-1, 2)
    target = np.asarray(target, dtype=float).reshape(-1, 2)
    rows, cols = np.nonzero(candidates)
    if not len(rows):
        return np.zeros(2)
    rows, cols = rows[:limit], cols[:limit]
    proposals = target[rows] - source[cols]  # (H, 2)
    offsets = target[:, None, :] - source[None, :, :]  # (n, m, 2)
    residual = np.linalg.norm(offsets[None] - proposals[:, None, None, :], axis=-1)
    near = biweight(residual, cutoff)  # (H, n, m)
    support = np.minimum(near.max(axis=2).sum(axis=1), near.max(axis=1).sum(axis=1))
    return proposals[int(np.argmax(support))]


def robust_rigid_2d(
    source: np.ndarray,
    target: np.ndarray,
    weights: np.ndarray,
    cutoff: float,
    with_rotation: bool = True,
    max_iter: int = 20,
    start: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rigid motion source -> target that ignores gross outliers: (R, t, inlier mask).

    Starts at ``start`` = (R, t) or, by default, at R = I and t = the weighted median of
    (target - source) per axis (robust while less than half the weight is wrong); then
    iteratively reweighted least squares with Tukey's biweight: weight w_k biweight(r_k,
    ``cutoff``) (r_k the residual, same units as the points), each round solved by
    :func:`procrustes_2d`, until the motion stops changing (1e-9) or ``max_iter`` rounds. The
    rotation is fitted only while at least two points carry weight. Inliers: residual < cutoff
    under the final motion.
    """
    source = np.asarray(source, dtype=float).reshape(-1, 2)
    target = np.asarray(target, dtype=float).reshape(-1, 2)
    weights = np.asarray(weights, dtype=float).reshape(-1)
    if start is None:
        turn, shift = np.eye(2), weighted_median(target - source, weights)
    else:
        turn, shift = np.asarray(start[0], dtype=float), np.asarray(start[1], dtype=float)
    for _ in range(max_iter):
        residual = np.linalg.norm(source @ turn.T + shift - target, axis=1)
        robust = weights * biweight(residual, cutoff)
        if not robust.sum() > 0:
            break
        rotate = with_rotation and np.count_nonzero(robust) >= 2
        new_turn, new_shift = procrustes_2d(source, target, robust, rotate)
        change = np.abs(new_turn - turn).max() + np.abs(new_shift - shift).max()
        turn, shift = new_turn, new_shift
        if change < 1e-9:
            break
    residual = np.linalg.norm(source @ turn.T + shift - target, axis=1)
    return turn, shift, residual < cutoff
