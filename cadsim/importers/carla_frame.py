"""The OPV2V family's pose convention, converted here and only here.

OPV2V, V2XSet and OpenCOOD state a pose as ``[x, y, z, roll, yaw, pitch]`` (metres, degrees) in
CARLA's world, which is left-handed (x forward, y right, z up); its rotation matrix is CARLA's
``Transform.get_matrix``: R = Rz(yaw) · Ry(pitch) · Rx(roll) with CARLA's sign conventions
(m20 = sin pitch, m21 = −cos pitch · sin roll, m22 = cos pitch · cos roll). V2V4Real gives a pose
as a rotation and a translation (or a 4×4 matrix) in the same axes. Mirroring y (F = diag(1, −1,
1)) makes every such transform right-handed: T_rh = F · T · F, and a point's world y is negated —
cadsim's world (x, y horizontal, z up, counter-clockwise headings). Both directions are here:
:func:`pose_matrix` (source → ours) and :func:`pose_angles` (ours → source), exact inverses up
to rounding; inverse trigonometry through :mod:`cadsim.portable_math` (same bytes on any CPU).
"""

from __future__ import annotations

import numpy as np

from cadsim import portable_math as pm

_SIGNS = np.outer([1.0, -1.0, 1.0, 1.0], [1.0, -1.0, 1.0, 1.0])  # F · T · F, elementwise (exact)


def carla_matrix(pose: np.ndarray) -> np.ndarray:
    """4×4 CARLA-frame transform of ``[x, y, z, roll, yaw, pitch]`` (metres, degrees)."""
    x, y, z, roll, yaw, pitch = (float(v) for v in pose)
    cr, sr = np.cos(np.radians(roll)), np.sin(np.radians(roll))
    cy, sy = np.cos(np.radians(yaw)), np.sin(np.radians(yaw))
    cp, sp = np.cos(np.radians(pitch)), np.sin(np.radians(pitch))
    out = np.eye(4)
    out[:3, :3] = [
        [cp * cy, cy * sp * sr - sy * cr, -cy * sp * cr - sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, -sy * sp * cr + cy * sr],
        [sp, -cp * sr, cp * cr],
    ]
    out[:3, 3] = (x, y, z)
    return out


def mirrored(transform: np.ndarray) -> np.ndarray:
    """A 4×4 transform between CARLA-axis frames as the same transform between right-handed
    frames (and back: the map is its own inverse)."""
    return np.asarray(transform, dtype=np.float64) * _SIGNS


def pose_matrix(pose: np.ndarray) -> np.ndarray:
    """4×4 right-handed transform (x forward, y left, z up → cadsim world) of an OPV2V pose."""
    return mirrored(carla_matrix(pose))


def mirrored_points(points: np.ndarray) -> np.ndarray:
    """(k, 3) points with y negated: CARLA world ↔ right-handed world."""
    return np.asarray(points, dtype=np.float64).reshape(-1, 3) * [1.0, -1.0, 1.0]


def pose_angles(transform: np.ndarray) -> list[float]:
    """``[x, y, z, roll, yaw, pitch]`` (metres, degrees, CARLA world) of a right-handed 4×4
    transform: the inverse of :func:`pose_matrix`."""
    m = mirrored(transform)
    pitch = np.degrees(pm.arcsin(float(np.clip(m[2, 0], -1.0, 1.0))))
    yaw = np.degrees(pm.arctan2(m[1, 0], m[0, 0]))
    roll = np.degrees(pm.arctan2(-m[2, 1], m[2, 2]))
    return [float(m[0, 3]), float(m[1, 3]), float(m[2, 3]), float(roll), float(yaw), float(pitch)]


__all__ = ["carla_matrix", "mirrored", "mirrored_points", "pose_angles", "pose_matrix"]
