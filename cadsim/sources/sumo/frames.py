"""SUMO's pose convention -> the world frame. The one place this conversion happens.

SUMO reports a vehicle's (and a person's) position as the centre of its FRONT bumper, and its
angle as a compass heading in degrees: 0 = north (+y), clockwise (90 = east). The world frame
(``cadsim.world``) has x east, y north, z up and yaw in radians counter-clockwise from +x, and a
WorldObject's position is its bounding-box CENTRE. So

    yaw    = radians(90 - angle)                     (wrapped to (-pi, pi])
    centre = front - (length / 2) * (cos yaw, sin yaw),   z_centre = z_ground + height / 2

and SUMO's speed (m/s along the heading) is the world-frame velocity speed * (cos yaw, sin yaw, 0).
"""

from __future__ import annotations

import numpy as np


def compass_to_yaw(angle_deg: np.ndarray | float) -> np.ndarray:
    """SUMO angle (degrees, 0 = north, clockwise) -> yaw (radians CCW from +x, in (-pi, pi])."""
    yaw = np.radians(90.0 - np.asarray(angle_deg, float))
    return np.pi - np.mod(np.pi - yaw, 2.0 * np.pi)


def yaw_to_compass(yaw: np.ndarray | float) -> np.ndarray:
    """Inverse of :func:`compass_to_yaw`: yaw (radians CCW from +x) -> SUMO angle in [0, 360)."""
    return np.mod(90.0 - np.degrees(np.asarray(yaw, float)), 360.0)


def front_to_center(
    front_xyz: np.ndarray, angle_deg: np.ndarray, length: np.ndarray, height: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """SUMO poses -> world bounding-box centres and yaws.

    front_xyz: (k, 3) front-bumper centre at ground level (SUMO's getPosition3D), metres.
    angle_deg: (k,) SUMO compass angles. length, height: (k,) metres.
    Returns centres (k, 3) and yaws (k,) radians CCW from +x.
    """
    front = np.asarray(front_xyz, float).reshape(-1, 3)
    yaw = compass_to_yaw(angle_deg).reshape(-1)
    half = np.asarray(length, float).reshape(-1) / 2.0
    center = front.copy()
    center[:, 0] -= half * np.cos(yaw)
    center[:, 1] -= half * np.sin(yaw)
    center[:, 2] += np.asarray(height, float).reshape(-1) / 2.0
    return center, yaw


def center_to_front(
    center_xyz: np.ndarray, yaw: np.ndarray, length: np.ndarray, height: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`front_to_center`: centres and yaws -> SUMO front positions and angles."""
    center = np.asarray(center_xyz, float).reshape(-1, 3)
    yaw = np.asarray(yaw, float).reshape(-1)
    half = np.asarray(length, float).reshape(-1) / 2.0
    front = center.copy()
    front[:, 0] += half * np.cos(yaw)
    front[:, 1] += half * np.sin(yaw)
    front[:, 2] -= np.asarray(height, float).reshape(-1) / 2.0
    return front, yaw_to_compass(yaw)


def sumo_color(rgba: tuple[int, int, int, int] | np.ndarray) -> tuple[float, float, float]:
    """SUMO colour (0-255 RGBA) -> RGB in [0, 1] (alpha dropped)."""
    c = np.asarray(rgba, float).reshape(-1)[:3] / 255.0
    return tuple(float(v) for v in np.clip(c, 0.0, 1.0))


def speed_to_velocity(speed: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """SUMO speeds (k,) m/s along the heading and world yaws (k,) rad -> (k, 3) world-frame
    velocities, m/s (SUMO's vehicles and persons move along their heading; no vertical part)."""
    speed = np.asarray(speed, float).reshape(-1)
    yaw = np.asarray(yaw, float).reshape(-1)
    return np.column_stack([speed * np.cos(yaw), speed * np.sin(yaw), np.zeros_like(speed)])
