"""One agent's own tracker: its detections linked over time, from its own detections and
odometry only (never a true id).

Every detection is first put into the agent's frame-0 ground plane
(:func:`matchers.core.sequence_problem.ground_positions`), where a parked object stands still
whatever the agent does. Then, frame by frame:

    predicted_k = last_k + velocity_k * (t - seen_k)      (constant velocity; 0 until seen twice)
    cost_kd     = ||predicted_k - position_d||             (tracks alive x detections)
    Hungarian on cost with cost > gate forbidden;  matched detections continue their track,
    the others start new tracks;  a track unseen for more than ``max_age`` frames ends.

The gate and the assignment read distances on the canonical grid
(:func:`~matchers.core.discretise.canonical_scores`, 2^-40 m), so that two equally distant
detections tie exactly, and a tie goes the same way, on every CPU. Track ids are 0, 1, 2, ...
in order of creation. The loop runs over frames; each frame's cost
matrix is one vectorised ``cdist``. Why this rather than a tracking library: docs/matchers.md
("Each agent's own tracks").
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist

from matchers.core.discretise import canonical_scores
from matchers.core.options import check_count, check_range
from matchers.core.sequence_problem import SequenceProblem, ground_positions

_FORBIDDEN = 1e9


def link(positions: list[np.ndarray], gate: float = 2.0, max_age: int = 2) -> list[np.ndarray]:
    """Per frame, the (n_t,) int track id of each of the (n_t, 2) ``positions`` (one agent's
    detections in its frame-0 ground plane, metres). ``gate``: the largest distance (metres)
    between a track's predicted position and a detection it may take; ``max_age``: frames a track
    may go unseen and still continue.

    >>> [ids.tolist() for ids in link([np.array([[0.0, 0], [5, 0]]), np.array([[5.1, 0], [0.2, 0]])])]
    [[0, 1], [1, 0]]
    """
    gate = check_range("gate", gate, 0.0, np.inf, open_low=True)
    max_age = check_count("max_age", max_age)
    last = np.zeros((0, 2))
    velocity = np.zeros((0, 2))
    seen = np.zeros(0, dtype=np.int64)
    out: list[np.ndarray] = []
    for t, xy in enumerate(positions):
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        ids = np.full(len(xy), -1, dtype=np.int64)
        alive = np.flatnonzero(t - seen <= max_age)
        if len(alive) and len(xy):
            predicted = last[alive] + velocity[alive] * (t - seen[alive])[:, None]
            cost = canonical_scores(cdist(predicted, xy))  # gate and ties: same on every CPU
            rows, cols = linear_sum_assignment(np.where(cost <= gate, cost, _FORBIDDEN))
            keep = cost[rows, cols] <= gate
            tracks, dets = alive[rows[keep]], cols[keep]
            ids[dets] = tracks
            velocity[tracks] = (xy[dets] - last[tracks]) / (t - seen[tracks])[:, None]
            last[tracks] = xy[dets]
            seen[tracks] = t
        new = np.flatnonzero(ids < 0)
        ids[new] = len(last) + np.arange(len(new))
        last = np.concatenate([last, xy[new]])
        velocity = np.concatenate([velocity, np.zeros((len(new), 2))])
        seen = np.concatenate([seen, np.full(len(new), t, dtype=np.int64)])
        out.append(ids)
    return out


def track_views(
    seq: SequenceProblem, gate: float = 2.0, max_age: int = 2
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Each agent's own tracks for ``seq``'s detections (its ``tracks1/tracks2`` are ignored):
    (per-frame ids of view 1, per-frame ids of view 2), from :func:`link` on each view's
    frame-0 ground-plane positions."""
    return (
        link(ground_positions(seq, 1), gate, max_age),
        link(ground_positions(seq, 2), gate, max_age),
    )


def with_own_tracks(seq: SequenceProblem, gate: float = 2.0, max_age: int = 2) -> SequenceProblem:
    """``seq`` with its track ids replaced by :func:`track_views`'s."""
    return seq.with_tracks(*track_views(seq, gate, max_age))


def tracked_sequence(
    frames: list,
    odometry1: np.ndarray,
    odometry2: np.ndarray,
    mount1: np.ndarray | None = None,
    mount2: np.ndarray | None = None,
    gate: float = 2.0,
    max_age: int = 2,
) -> SequenceProblem:
    """The :class:`SequenceProblem` of per-frame ``frames`` (time order) with each agent's own
    tracks from its detections and odometry alone (:func:`track_views`): what a vehicle can build
    itself, never a true id. The detection indices only fill the contract's track fields until
    :func:`with_own_tracks` replaces them."""
    indices1 = [np.arange(f.n1) for f in frames]
    indices2 = [np.arange(f.n2) for f in frames]
    untracked = SequenceProblem(frames, indices1, indices2, odometry1, odometry2, mount1, mount2)
    return with_own_tracks(untracked, gate, max_age)
