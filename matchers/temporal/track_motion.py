"""The window's planar motion refined by track assignment: the refinement step the windowed
pose methods (:mod:`matchers.temporal.temporal_pose`, :mod:`matchers.temporal.trajectory_pose`)
share.

Observations k are candidate pairs of detections (src_k in view 2, dst_k in view 1, ground plane,
metres) that belong to own tracks a_k (view 1) and b_k (view 2). Each round: residuals r_k under
the current motion; per track pair the mean likelihood exp(−r²/(4 width²)) (0 beyond ``cutoff``,
times the pair's class weight); one-to-one track assignment maximising it (Hungarian); then the
weighted 2-D Procrustes motion of the assigned pairs' observations (weights: Tukey's biweight of
r at ``cutoff``) plus the prior's anchor points. Stops when the motion changes by < 1e-9.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from matchers.blocks.rigid2d import biweight, procrustes_2d


def refine_motion(
    turn: np.ndarray,
    move: np.ndarray,
    observations: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    tracks: tuple[int, int],
    cutoff: float,
    width: float,
    anchors: tuple[np.ndarray, np.ndarray, np.ndarray],
    max_iter: int,
    class_weight: np.ndarray | None = None,
    stop_when_unweighted: bool = False,
) -> tuple[np.ndarray, np.ndarray, int]:
    """(rotation (2, 2), translation (2,), rounds) after at most ``max_iter`` rounds (module
    docstring). ``observations``: (src (K, 2), dst (K, 2), a (K,), b (K,)) with a, b track
    indices below ``tracks`` = (tracks in view 1, tracks in view 2); ``anchors``: (src, dst,
    weights) of the prior, possibly empty; ``class_weight`` (K,) multiplies each likelihood;
    ``stop_when_unweighted``: stop when no assigned observation keeps a weight."""
    src, dst, a, b = observations
    anchor_src, anchor_dst, anchor_w = anchors
    rounds = 0
    for _ in range(max_iter):
        rounds += 1
        r = np.linalg.norm(src @ turn.T + move - dst, axis=1)
        like = np.where(r <= cutoff, np.exp(-(r**2) / (4 * width**2)), 0.0)
        if class_weight is not None:
            like = like * class_weight
        pair = np.zeros(tracks)
        seen = np.zeros(tracks)
        np.add.at(pair, (a, b), like)
        np.add.at(seen, (a, b), 1.0)
        mean = pair / np.maximum(seen, 1.0)
        ra, cb = linear_sum_assignment(mean, maximize=True)
        chosen = np.zeros_like(mean, dtype=bool)
        chosen[ra, cb] = mean[ra, cb] > 0
        w = chosen[a, b] * biweight(r, cutoff)
        if stop_when_unweighted and not (w.sum() > 0):
            break
        new_turn, new_move = procrustes_2d(
            np.r_[src, anchor_src], np.r_[dst, anchor_dst], np.r_[w, anchor_w]
        )
        change = np.abs(new_turn - turn).max() + np.abs(new_move - move).max()
        turn, move = new_turn, new_move
        if change < 1e-9:
            break
    return turn, move, rounds


__all__ = ["refine_motion"]
