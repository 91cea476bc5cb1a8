"""Image-plane footprint of an object's 3-D bounding box: how much of it a camera could see.

The area of the convex hull of the projected box (clipped at a near plane in front of the camera)
is an upper bound of the object's unoccluded silhouette; the detection adapter compares it with
the visible pixel count (occlusion) and with its own part inside the image (truncation).
"""

from __future__ import annotations

import cv2
import numpy as np

from cadsim import portable_math as pm
from cadsim.camera import Camera
from cadsim.world import WorldObject

_CORNER_SIGNS = np.array(
    [[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float
)
# The 12 edges of a box as pairs of corner indices (corners differ in exactly one sign).
_EDGES = np.array(
    [
        (i, j)
        for i in range(8)
        for j in range(i + 1, 8)
        if np.sum(_CORNER_SIGNS[i] != _CORNER_SIGNS[j]) == 1
    ]
)
NEAR_PLANE_M = 0.05


def box_corners(obj: WorldObject) -> np.ndarray:
    """(8, 3) corners of the object's bounding box, world frame, metres."""
    local = _CORNER_SIGNS * (np.asarray(obj.size, float) / 2.0)
    T = obj.pose()
    return pm.matmul(local, T[:3, :3].T) + T[:3, 3]


def projected_box_areas(obj: WorldObject, camera: Camera) -> tuple[float, float]:
    """(hull area, hull area inside the image), pixels², of the object's bounding box projected
    into ``camera`` after clipping it at z = NEAR_PLANE_M. (0, 0) if it is entirely behind."""
    pc = camera.world_to_camera(box_corners(obj))
    z = pc[:, 2]
    points = [pc[z >= NEAR_PLANE_M]]
    a, b = pc[_EDGES[:, 0]], pc[_EDGES[:, 1]]
    za, zb = a[:, 2], b[:, 2]
    crossing = (za - NEAR_PLANE_M) * (zb - NEAR_PLANE_M) < 0
    if crossing.any():
        t = (NEAR_PLANE_M - za[crossing]) / (zb[crossing] - za[crossing])
        points.append(a[crossing] + t[:, None] * (b[crossing] - a[crossing]))
    pts = np.concatenate(points)
    if len(pts) < 3:
        return 0.0, 0.0
    uv = camera.project(pts).astype(np.float32)
    hull = cv2.convexHull(uv)
    area = float(cv2.contourArea(hull))
    if area <= 0:
        return 0.0, 0.0
    w, h = camera.width, camera.height
    image = np.array([[0, 0], [w, 0], [w, h], [0, h]], dtype=np.float32)
    inside, _ = cv2.intersectConvexConvex(hull.reshape(-1, 2), image)
    return area, float(max(inside, 0.0))
