"""Oriented box of one cluster of LiDAR points: the minimum-area rectangle of its footprint
(OpenCV's ``minAreaRect`` on the points' x, y), from the road plane up to its highest point.

Frame: the LiDAR frame (x forward, y left, z up, metres). The box's *length* is its longer
footprint side, its yaw (radians, counter-clockwise about z from +x) the direction of that side,
folded into (−π/2, π/2]: points alone do not tell a car's front from its back. A cluster seen
from one side only gets the rectangle of what is visible (a thin box along the visible face);
``cadsim.sensing.lidar.size_classes`` completes it to its class's size.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from cadsim.sensing.lidar.ground_removal import GroundPlane

MIN_SIDE_M = 0.05


@dataclass(frozen=True)
class FittedBox:
    """centre: (x, y, z) metres, LiDAR frame; size: (length, width, height) metres; yaw: radians."""

    centre: tuple[float, float, float]
    size: tuple[float, float, float]
    yaw: float


def fold_yaw(yaw: float) -> float:
    """A box axis direction folded into (−π/2, π/2] (radians)."""
    y = math.fmod(float(yaw), math.pi)
    if y <= -math.pi / 2:
        y += math.pi
    elif y > math.pi / 2:
        y -= math.pi
    return y


def fit_box(points: np.ndarray, plane: GroundPlane) -> FittedBox:
    """The oriented box of one cluster's ``points`` (k ≥ 1, 3) standing on ``plane``."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    (cx, cy), (w, h), _ = cv2.minAreaRect(np.ascontiguousarray(p[:, :2], dtype=np.float32))
    corners = cv2.boxPoints(((cx, cy), (w, h), _)).astype(np.float64)
    e0, e1 = corners[1] - corners[0], corners[2] - corners[1]
    n0, n1 = math.hypot(e0[0], e0[1]), math.hypot(e1[0], e1[1])
    axis, length, width = (e0, n0, n1) if n0 >= n1 else (e1, n1, n0)
    yaw = fold_yaw(math.atan2(axis[1], axis[0])) if length > 0 else 0.0
    base = float(plane.a * cx + plane.b * cy + plane.c)
    top = float(p[:, 2].max())
    height = max(top - base, MIN_SIDE_M)
    return FittedBox(
        (float(cx), float(cy), base + height / 2.0),
        (max(length, MIN_SIDE_M), max(width, MIN_SIDE_M), height),
        yaw,
    )
