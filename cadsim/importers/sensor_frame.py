"""World boxes into a sensor's view: the one place imported boxes change frame.

Every importer states its source's poses as 4×4 rigid transforms into a right-handed world
(x, y horizontal, z up, metres) and its boxes as world centres and world length directions;
this module turns them into what a box-only view holds (``cadsim.sensing.box_features``):
the sensor as a :class:`~cadsim.camera.Camera` pose — its optical axis the sensor's forward
(x) axis, so heading (yaw) and pitch are kept and roll is dropped (a LiDAR's roll is a
mounting tolerance, a few tenths of a degree; the planar metrics ignore it) — and each box's
centre and heading in that camera-frame convention (x right, y down, z forward, metres;
heading ``atan2(d_x, d_z)``, radians). The exporters use :func:`sensor_pose` to go back.
Products and inverse trigonometry go through :mod:`cadsim.portable_math` (same bytes on any
CPU).
"""

from __future__ import annotations

import math

import numpy as np

from cadsim import portable_math as pm
from cadsim.camera import Camera


def sensor_camera(sensor_to_world: np.ndarray) -> Camera:
    """The sensor (4×4 sensor → world, sensor frame x forward) as a camera pose: its position,
    the heading and pitch (radians) of its forward axis."""
    t = np.asarray(sensor_to_world, dtype=np.float64)
    fx, fy, fz = (float(v) for v in t[:3, 0])
    yaw = float(pm.arctan2(fy, fx))
    pitch = float(pm.arctan2(fz, math.hypot(fx, fy)))
    return Camera(tuple(float(v) for v in t[:3, 3]), yaw, pitch)


def sensor_pose(camera: Camera) -> np.ndarray:
    """4×4 sensor → world transform (sensor frame x forward, y left, z up) of a box view's
    ``camera`` entry: the inverse of :func:`sensor_camera` (roll 0)."""
    rotation = camera.rotation_cam_to_world()  # columns: right, down, forward
    out = np.eye(4)
    out[:3, :3] = np.column_stack([rotation[:, 2], -rotation[:, 0], -rotation[:, 1]])
    out[:3, 3] = camera.position
    return out


def boxes_in_view(
    camera: Camera, centres_world: np.ndarray, directions_world: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """((k, 3) centres in ``camera``'s frame, metres; (k,) headings, radians) of k boxes with
    world centres (k, 3) and world length directions (k, 3, any length)."""
    rotation = camera.rotation_cam_to_world()
    centres = np.asarray(centres_world, dtype=np.float64).reshape(-1, 3)
    positions = pm.matmul(centres - np.asarray(camera.position), rotation)
    local = pm.matmul(np.asarray(directions_world, dtype=np.float64).reshape(-1, 3), rotation)
    return positions, pm.arctan2(local[:, 0], local[:, 2]).reshape(-1)


def world_directions(camera: Camera, headings: np.ndarray) -> np.ndarray:
    """(k, 3) world length directions of boxes with ``headings`` (radians) in ``camera``'s
    frame (level in that frame): the inverse of :func:`boxes_in_view`'s headings."""
    h = np.asarray(headings, dtype=np.float64).reshape(-1)
    local = np.column_stack([np.sin(h), np.zeros_like(h), np.cos(h)])
    return pm.matmul(local, camera.rotation_cam_to_world().T)


def rigid_inverse(transform: np.ndarray) -> np.ndarray:
    """The inverse of a 4×4 rigid transform (Rᵀ, −Rᵀt)."""
    t = np.asarray(transform, dtype=np.float64)
    out = np.eye(4)
    out[:3, :3] = t[:3, :3].T
    out[:3, 3] = -pm.matmul(t[:3, :3].T, t[:3, 3])
    return out


def apply(transform: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(k, 3) points moved by a 4×4 transform."""
    t = np.asarray(transform, dtype=np.float64)
    return pm.matmul(np.asarray(points, dtype=np.float64).reshape(-1, 3), t[:3, :3].T) + t[:3, 3]


def heading_of(directions: np.ndarray) -> np.ndarray:
    """(k,) world headings (radians CCW from +x) of (k, 3) directions."""
    d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    return pm.arctan2(d[:, 1], d[:, 0]).reshape(-1)


def yaw_directions(yaw: np.ndarray) -> np.ndarray:
    """(k, 3) horizontal unit directions of world headings ``yaw`` (radians CCW from +x)."""
    y = np.asarray(yaw, dtype=np.float64).reshape(-1)
    return np.column_stack([np.cos(y), np.sin(y), np.zeros_like(y)])


__all__ = [
    "apply", "boxes_in_view", "heading_of", "rigid_inverse", "sensor_camera", "sensor_pose",
    "world_directions", "yaw_directions",
]  # fmt: skip
