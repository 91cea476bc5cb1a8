"""Ground removal: fit the road plane to a LiDAR cloud and keep the points standing on it.

The road is sought near where it must be — ``sensor_height_m`` below the sensor (the mount's
nominal height, known from calibration) — among points within ``GROUND_SEARCH_M`` of that height;
a plane ``z = a·x + b·y + c`` is fitted to them by least squares, refitted once to the points
within ``GROUND_INLIER_M`` of the first fit, and every point less than ``min_height_m`` above the
plane is ground. Fewer than ``MIN_GROUND_POINTS`` candidates: the level plane at the nominal
height. The fit uses explicit sums and Cramer's rule (no LAPACK), so it is the same bits on every
CPU. Frame: the LiDAR frame (x forward, y left, z up, metres). Imports numpy only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

GROUND_SEARCH_M = 0.5
GROUND_INLIER_M = 0.15
MIN_GROUND_POINTS = 20


@dataclass(frozen=True)
class GroundPlane:
    """z = a·x + b·y + c in the LiDAR frame, metres."""

    a: float
    b: float
    c: float

    def height_above(self, points: np.ndarray) -> np.ndarray:
        """(n,) height of each point above the plane along z, metres."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        return p[:, 2] - (self.a * p[:, 0] + self.b * p[:, 1] + self.c)


def _fit(points: np.ndarray) -> GroundPlane | None:
    x, y, z = points[:, 0], points[:, 1], points[:, 2]
    n = float(len(points))
    sxx, sxy, syy = np.sum(x * x), np.sum(x * y), np.sum(y * y)
    sx, sy = np.sum(x), np.sum(y)
    sxz, syz, sz = np.sum(x * z), np.sum(y * z), np.sum(z)
    m = ((sxx, sxy, sx), (sxy, syy, sy), (sx, sy, n))
    rhs = (sxz, syz, sz)

    def det(r):
        return (r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
                - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
                + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]))  # fmt: skip

    d = det(m)
    if not abs(d) > 1e-9 * max(1.0, n) ** 3:
        return None
    coef = []
    for col in range(3):
        r = [list(row) for row in m]
        for row in range(3):
            r[row][col] = rhs[row]
        coef.append(det(r) / d)
    return GroundPlane(float(coef[0]), float(coef[1]), float(coef[2]))


def fit_ground(points: np.ndarray, sensor_height_m: float) -> GroundPlane:
    """The road plane under a cloud (module docstring); ``points`` (n, 3) LiDAR frame, metres."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    level = GroundPlane(0.0, 0.0, -float(sensor_height_m))
    plane = level
    for band in (GROUND_SEARCH_M, GROUND_INLIER_M):
        near = p[np.abs(plane.height_above(p)) < band]
        if len(near) < MIN_GROUND_POINTS:
            return plane
        plane = _fit(near) or plane
    return plane


def remove_ground(points: np.ndarray, sensor_height_m: float, min_height_m: float = 0.2) -> tuple[np.ndarray, GroundPlane]:  # fmt: skip
    """``(above, plane)``: (n,) bool, True for points at least ``min_height_m`` above the fitted
    road plane, and the plane."""
    plane = fit_ground(points, sensor_height_m)
    return plane.height_above(points) >= min_height_m, plane
