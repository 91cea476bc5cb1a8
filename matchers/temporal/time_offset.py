"""The time offset between two agents' messages: what ``temporal_pose`` needs to estimate the
latency Δt of agent 2's detections when it is not known.

A message Δt seconds old shows every object where it was Δt ago. In agent 2's frame-0 ground
plane (a fixed frame: :func:`~matchers.core.sequence_problem.ground_positions`) an object seen
along one of agent 2's own tracks moves with the track's apparent velocity v (m/s), so its
position now is about q + v Δt; the sender's own motion over Δt moves every detection alike
x :func:`compensated` the shifted positions, :func:`offset_grid` the candidates a search
scores. Imports nothing from ``cadsim`` or ``eval``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def track_velocities(
    positions: Sequence[np.ndarray], tracks: Sequence[np.ndarray], interval_s: float
) -> list[np.ndarray]:
    """Per frame, the (n_s, 2) apparent velocity (m/s) of each detection: its own track's
    constant velocity over the given frames (least-squares slope of its positions against
    time, frames ``interval_s`` seconds apart; 0 for a track seen in one frame only). A slope
    over the whole window, not a difference of two frames, so that detection noise is not
    amplified into the velocity. ``positions[s]``: (n_s, 2) ground-plane metres;
    ``tracks[s]``: (n_s,) track ids. Vectorised over tracks (one ``bincount`` per moment).

    >>> v = track_velocities([np.zeros((1, 2)), np.ones((1, 2))], [[4], [4]], 0.5)
    >>> v[1].tolist()
    [[2.0, 2.0]]
    """
    sizes = [len(np.asarray(ids).reshape(-1)) for ids in tracks]
    if not sum(sizes):
        return [np.zeros((n, 2)) for n in sizes]
    xy = np.concatenate([np.asarray(p, dtype=float).reshape(-1, 2) for p in positions])
    ids = np.concatenate([np.asarray(i).reshape(-1) for i in tracks])
    time_s = np.repeat(np.arange(len(sizes), dtype=float) * interval_s, sizes)
    _, group = np.unique(ids, return_inverse=True)
    count = np.bincount(group)
    centred_t = time_s - (np.bincount(group, time_s) / count)[group]
    spread = np.bincount(group, centred_t**2)
    slope = np.zeros((len(count), 2))
    for d in (0, 1):
        centred = xy[:, d] - (np.bincount(group, xy[:, d]) / count)[group]
        moment = np.bincount(group, centred_t * centred, len(count))
        slope[:, d] = np.where(spread > 0, moment / np.where(spread > 0, spread, 1.0), 0.0)
    return np.split(slope[group], np.cumsum(sizes)[:-1])


def compensated(
    positions: Sequence[np.ndarray], velocities: Sequence[np.ndarray], offset_s: float
) -> list[np.ndarray]:
    """``positions`` moved forward by ``offset_s`` seconds along their ``velocities``."""
    return [
        np.asarray(xy, float) + offset_s * v for xy, v in zip(positions, velocities, strict=True)
    ]


def offset_grid(max_offset_s: float, step_s: float) -> np.ndarray:
    """Candidate offsets 0, step, 2·step, … ≤ ``max_offset_s`` (seconds), each ``step_s · k``
    (one IEEE multiplication: the same candidates on every CPU)."""
    count = int(np.floor(max_offset_s / step_s + 1e-9))
    return step_s * np.arange(count + 1)
