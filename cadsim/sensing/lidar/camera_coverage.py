"""Where a camera and a LiDAR on the same vehicle both sense: the camera's frustum up to its
detector's range, within the LiDAR's range — decided from geometry alone (a detection's reported
centre, the sensors' poses), never from ground-truth ids, so false positives are kept or dropped
by the same rule as real objects (docs/lidar.md, "Both sensors on the same objects").

A reported centre is *covered* when it lies in front of the camera, projects inside its image
(0 ≤ u < width, 0 ≤ v < height, pixels), is at most ``max_depth_m`` (the camera detector's
``[detection]`` range, metres) deep along the camera's optical axis, and at most
``max_range_m`` (the LiDAR's specified range) from the LiDAR. A LiDAR sees all around and further;
its boxes outside that region are its *extra* objects, counted apart from the comparison. The
LiDAR's vertical field of view is not applied: an object standing on the road within its range
always has a part between its lowest and highest channel (the HDL-64E's −24.9° … +2° from a
roof), even where its centre lies above the top one.
Imports numpy and ``cadsim.camera`` only.
"""

from __future__ import annotations

import numpy as np

from cadsim import portable_math as pm
from cadsim.camera import Camera


def covered(
    world_points: np.ndarray,
    camera: Camera,
    lidar_pose: np.ndarray,
    max_depth_m: float,
    max_range_m: float,
) -> np.ndarray:
    """(k,) bool: which of the (k, 3) world points (metres) lie in the region both sensors cover
    (module docstring); ``lidar_pose``: (4, 4) LiDAR → world.

    >>> cam = Camera((0.0, 0.0, 1.6), 0.0, width=640, height=480)
    >>> pose = np.eye(4); pose[:3, 3] = (0.0, 0.0, 1.8)
    >>> covered(np.array([[20.0, 0, 1], [-20.0, 0, 1], [90.0, 0, 1]]), cam, pose, 80.0, 120.0)
    array([ True, False, False])
    """
    p = np.asarray(world_points, dtype=np.float64).reshape(-1, 3)
    if not len(p):
        return np.zeros(0, dtype=bool)
    c = camera.world_to_camera(p)
    z = c[:, 2]
    ahead = z > 1e-6
    uv = camera.project(np.where(ahead[:, None], c, 1.0))
    inside = (
        (uv[:, 0] >= 0) & (uv[:, 0] < camera.width) & (uv[:, 1] >= 0) & (uv[:, 1] < camera.height)
    )
    offset = p - np.asarray(lidar_pose, dtype=np.float64)[:3, 3]
    reach = np.sqrt(np.sum(offset * offset, axis=1)) <= max_range_m
    return ahead & inside & (z <= max_depth_m) & reach


def lidar_box_world(centres: np.ndarray, lidar_pose: np.ndarray) -> np.ndarray:
    """(k, 3) world positions of box centres given in the LiDAR frame (metres)."""
    c = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    T = np.asarray(lidar_pose, dtype=np.float64)
    return pm.matmul(c, T[:3, :3].T) + T[:3, 3]


__all__ = ["covered", "lidar_box_world"]
