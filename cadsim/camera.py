"""Pinhole camera model and the frames it connects.

Camera frame (the frame of every position a matcher sees): OpenCV convention, x right, y down,
z forward along the optical axis, metres, origin at the optical centre. World frame: see
``cadsim.world``. Pixel (u, v): u to the right, v down, origin at the top-left pixel's corner,
pixel centres at half-integers. The OpenGL camera frame pyrender uses (x right, y up, -z forward)
is converted here, and only here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cadsim import portable_math as pm

# OpenCV camera axes expressed in the OpenGL camera frame: flip y and z.
_CV_TO_GL = np.diag([1.0, -1.0, -1.0])


@dataclass(frozen=True)
class Camera:
    """A camera at ``position`` (world, metres) looking along heading ``yaw`` (radians CCW from +x)
    tilted by ``pitch`` (radians, negative looks down), with a ``width``×``height`` image and
    horizontal field of view ``hfov_deg`` (degrees). Square pixels, principal point at the centre."""

    position: tuple[float, float, float]
    yaw: float
    pitch: float = 0.0
    width: int = 640
    height: int = 480
    hfov_deg: float = 90.0

    @property
    def fx(self) -> float:
        return self.width / (2.0 * pm.tan(np.radians(self.hfov_deg) / 2.0))

    @property
    def vfov_rad(self) -> float:
        return 2.0 * pm.arctan(self.height / (2.0 * self.fx))

    def intrinsics(self) -> np.ndarray:
        """3x3 K (pixels)."""
        f = self.fx
        return np.array([[f, 0.0, self.width / 2.0], [0.0, f, self.height / 2.0], [0.0, 0.0, 1.0]])

    def rotation_cam_to_world(self) -> np.ndarray:
        """3x3 R with world = R @ cam + position (OpenCV camera axes)."""
        cy, sy = np.cos(self.yaw), np.sin(self.yaw)
        cp, sp = np.cos(self.pitch), np.sin(self.pitch)
        forward = np.array([cy * cp, sy * cp, sp])
        right = np.array([sy, -cy, 0.0])
        down = np.cross(forward, right)
        return np.column_stack([right, down, forward])

    def pose_gl(self) -> np.ndarray:
        """4x4 camera-to-world pose in OpenGL camera axes (what pyrender expects)."""
        T = np.eye(4)
        T[:3, :3] = pm.matmul(self.rotation_cam_to_world(), _CV_TO_GL)
        T[:3, 3] = self.position
        return T

    def world_to_camera(self, points: np.ndarray) -> np.ndarray:
        """(k, 3) world points -> (k, 3) camera-frame points."""
        R = self.rotation_cam_to_world()
        return pm.matmul(np.asarray(points, float) - np.asarray(self.position), R)

    def camera_to_world(self, points: np.ndarray) -> np.ndarray:
        """(k, 3) camera-frame points -> (k, 3) world points."""
        R = self.rotation_cam_to_world()
        return pm.matmul(np.asarray(points, float), R.T) + np.asarray(self.position)

    def project(self, points_cam: np.ndarray) -> np.ndarray:
        """(k, 3) camera-frame points (z > 0) -> (k, 2) pixel coordinates (u, v)."""
        p = np.asarray(points_cam, float)
        K = self.intrinsics()
        uv = p[:, :2] / p[:, 2:3]
        return uv * [K[0, 0], K[1, 1]] + [K[0, 2], K[1, 2]]

    def back_project(self, uv: np.ndarray, depth: np.ndarray) -> np.ndarray:
        """Pixels (k, 2) with depth along the optical axis (k,) metres -> (k, 3) camera points."""
        uv = np.asarray(uv, float)
        z = np.asarray(depth, float)
        K = self.intrinsics()
        x = (uv[:, 0] - K[0, 2]) / K[0, 0] * z
        y = (uv[:, 1] - K[1, 2]) / K[1, 1] * z
        return np.column_stack([x, y, z])

    def as_dict(self) -> dict:
        return {
            "position": [float(v) for v in self.position],
            "yaw": float(self.yaw),
            "pitch": float(self.pitch),
            "width": int(self.width),
            "height": int(self.height),
            "hfov_deg": float(self.hfov_deg),
        }

    @classmethod
    def from_dict(cls, d: dict) -> Camera:
        return cls(
            position=tuple(d["position"]),
            yaw=float(d["yaw"]),
            pitch=float(d.get("pitch", 0.0)),
            width=int(d.get("width", 640)),
            height=int(d.get("height", 480)),
            hfov_deg=float(d.get("hfov_deg", 90.0)),
        )
