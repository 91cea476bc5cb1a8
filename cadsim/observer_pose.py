"""The true world pose of an observer and where its camera sits on it.

An observer's *body frame* is that of the object carrying the camera (``WorldObject.pose()``):
origin at its bounding-box centre, x forward along its heading, y left, z up, metres. Its pose is
that origin in the world frame (``cadsim.world``: x east, y north, z up) and the heading ``yaw``
(radians counter-clockwise from +x) — what a vehicle's localisation reports, before any error. A
camera on no object (``observer_id == ""``) is its own body: origin at the optical centre, yaw the
camera's. The camera's *extrinsics* are the 4×4 transform from its OpenCV frame (x right, y down,
z forward) to the body frame. Imports only numpy and the root scene modules.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cadsim.camera import Camera
from cadsim.world import WorldObject


@dataclass(frozen=True)
class ObserverPose:
    """position: (x, y, z) world metres of the body origin; yaw: heading, radians CCW from +x."""

    position: tuple[float, float, float]
    yaw: float

    @classmethod
    def of_carrier(cls, carrier: WorldObject) -> ObserverPose:
        """The pose of the object carrying a camera."""
        return cls(tuple(float(v) for v in carrier.center), float(carrier.yaw))

    @classmethod
    def of_camera(cls, camera: Camera) -> ObserverPose:
        """The pose of a camera on no object: its optical centre and heading."""
        return cls(tuple(float(v) for v in camera.position), float(camera.yaw))

    def body_to_world(self) -> np.ndarray:
        """4×4 transform from the body frame to the world frame."""
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        T = np.eye(4)
        T[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
        T[:3, 3] = self.position
        return T

    def camera_extrinsics(self, camera: Camera) -> np.ndarray:
        """4×4 transform from ``camera``'s OpenCV frame to this body frame (the camera mount).

        >>> pose = ObserverPose((10.0, 0.0, 0.75), np.pi / 2)
        >>> cam = Camera((10.0, 2.35, 1.6), np.pi / 2)
        >>> np.round(pose.camera_extrinsics(cam)[:3, 3], 2).tolist()   # 2.35 m ahead, 0.85 m up
        [2.35, 0.0, 0.85]
        """
        return np.linalg.inv(self.body_to_world()) @ camera_to_world(camera)

    def as_dict(self) -> dict:
        return {"position": [float(v) for v in self.position], "yaw": float(self.yaw)}

    @classmethod
    def from_dict(cls, d: dict) -> ObserverPose:
        return cls(tuple(float(v) for v in d["position"]), float(d["yaw"]))


def camera_to_world(camera: Camera) -> np.ndarray:
    """4×4 transform from ``camera``'s OpenCV frame to the world frame."""
    T = np.eye(4)
    T[:3, :3] = camera.rotation_cam_to_world()
    T[:3, 3] = camera.position
    return T


__all__ = ["ObserverPose", "camera_to_world"]
