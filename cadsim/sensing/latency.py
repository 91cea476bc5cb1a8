"""Message latency: the other vehicle's detections arrive Δt seconds old.

Receiver = view 1 (the vehicle doing the matching, at time t); sender = view 2 (its message was
made at t − Δt). Over Δt every object is taken to move in a straight line at its recorded
velocity (``WorldObject.velocity``, world frame, m/s; dataset format version 3), and so does the
sender itself (its carrying object's velocity; 0 for a roadside unit or an unknown id). The
sender's message holds

    object positions in its own frame at t − Δt:  p' = p − Rᵀ (v_object − v_sender) Δt
    its world pose at t − Δt:                      position − v_sender Δt, heading unchanged

(R: the sender's camera-to-world rotation at t), so its world positions are w − v_object Δt —
each object where it was Δt ago. The true relative pose a matcher can recover is then the
receiver's pose at t against the sender's at t − Δt (:func:`sender_offset`). Detections with no
object behind them (false positives) are static clutter. Pixel boxes and features are left as
rendered at t (appearance changes little in 0.1–0.3 s). Imports numpy only.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from cadsim import portable_math as pm

MIN_VELOCITY_FORMAT = 3  # dataset format version from which records carry velocities


def velocities_of(ids: Sequence[str], by_id: Mapping[str, Sequence[float]]) -> np.ndarray:
    """(k, 3) world velocities (m/s) of the objects ``ids``; 0 for an id not in ``by_id``."""
    out = np.zeros((len(ids), 3))
    for k, oid in enumerate(ids):
        if oid in by_id:
            out[k] = by_id[oid]
    return out


def sender_offset(sender_velocity: Sequence[float], latency_s: float) -> np.ndarray:
    """(3,) world displacement (metres) of the sender's pose at t − Δt from its pose at t."""
    return -np.asarray(sender_velocity, dtype=float).reshape(3) * float(latency_s)


def delayed_positions(
    positions: np.ndarray,
    object_velocities: np.ndarray,
    sender_velocity: Sequence[float],
    rotation_cam_to_world: np.ndarray,
    latency_s: float,
) -> np.ndarray:
    """(k, 3) positions in the sender's camera frame (metres) as its message reports them,
    ``latency_s`` seconds before the snapshot: ``positions`` (k, 3, camera frame at t) moved by
    −Rᵀ (v_object − v_sender) Δt (module docstring)."""
    positions = np.asarray(positions, dtype=float).reshape(-1, 3)
    if latency_s == 0.0 or not len(positions):
        return positions
    relative = np.asarray(object_velocities, dtype=float).reshape(-1, 3) - np.asarray(
        sender_velocity, dtype=float
    ).reshape(1, 3)
    rotation = np.asarray(rotation_cam_to_world, dtype=float).reshape(3, 3)
    return positions - float(latency_s) * pm.matmul(relative, rotation)  # rows: Rᵀ r
