"""Where a LiDAR sits: its 4×4 pose (LiDAR frame → world) on a vehicle's roof or on a pole.

A roof unit sits ``ROOF_CLEARANCE_M`` above the carrier's roof on its centre line, axes aligned
with the carrier's body (x forward, y left, z up); with a 1.5 m car this puts the optical centre
at ≈ 1.75 m, KITTI's HDL-64E height (1.73 m). A roadside unit is level at its pole's head, x along
the pole's heading. Sines and cosines only (the same bits on every CPU).
"""

from __future__ import annotations

import math

import numpy as np

from cadsim.world import WorldObject

ROOF_CLEARANCE_M = 0.25


def level_pose(position: tuple[float, float, float] | np.ndarray, yaw: float) -> np.ndarray:
    """4×4 pose of a level sensor at ``position`` (world metres) heading ``yaw`` (radians CCW
    from +x)."""
    c, s = math.cos(float(yaw)), math.sin(float(yaw))
    T = np.eye(4)
    T[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    T[:3, 3] = np.asarray(position, dtype=np.float64)
    return T


def roof_pose(carrier: WorldObject) -> np.ndarray:
    """4×4 LiDAR → world pose of a roof unit on ``carrier``."""
    x, y, z = (float(v) for v in carrier.center)
    return level_pose((x, y, z + float(carrier.size[2]) / 2.0 + ROOF_CLEARANCE_M), carrier.yaw)


def rigid_inverse(pose: np.ndarray) -> np.ndarray:
    """Inverse of a 4×4 rigid transform, element-wise (no LAPACK)."""
    R = np.asarray(pose, dtype=np.float64)[:3, :3]
    t = np.asarray(pose, dtype=np.float64)[:3, 3]
    inv = np.eye(4)
    inv[:3, :3] = R.T
    inv[:3, 3] = -(R.T[:, 0] * t[0] + R.T[:, 1] * t[1] + R.T[:, 2] * t[2])
    return inv
