"""The MRC observers: a ground robot's side camera and an aerial robot's overhead camera.

World frame as in ``cadsim.world`` (x east, y north, z up, metres). The side camera rides on the
ground observer robot, ``camera_height`` above the floor at the robot's front, looking along the
robot's heading. The overhead camera hovers where its optical axis meets the floor at a point
ahead of the side camera (``lead``) and to its left (``lateral``), so the two footprints overlap
partially; its heading, altitude and pitch are drawn per candidate.
"""

from __future__ import annotations

import numpy as np

from cadsim import portable_math as pm
from cadsim.camera import Camera
from cadsim.sources.arena.config import AerialObserver, GroundObserver
from cadsim.world import WorldObject


def side_camera(robot: WorldObject, ground: GroundObserver) -> Camera:
    """The side camera on ``robot`` (its front face, ``camera_height`` m above the floor)."""
    forward = np.array([np.cos(robot.yaw), np.sin(robot.yaw)])
    xy = np.asarray(robot.center[:2]) + forward * robot.size[0] / 2.0
    cam = ground.intrinsics
    return Camera(
        position=(float(xy[0]), float(xy[1]), float(ground.camera_height)),
        yaw=float(robot.yaw),
        pitch=float(np.radians(ground.pitch_deg)),
        width=cam.width,
        height=cam.height,
        hfov_deg=cam.hfov_deg,
    )


def overhead_cameras(
    side: Camera,
    aerial: AerialObserver,
    half_extent: np.ndarray,
    rng: np.random.Generator,
) -> list[tuple[Camera, np.ndarray]]:
    """``aerial.candidates`` overhead cameras, each with the floor point (2,) its optical axis
    meets. The point lies ``lead`` ahead and ``lateral`` to the left of the side camera, clipped to
    the arena box [-half_extent, half_extent]."""
    k = aerial.candidates
    lead = rng.uniform(*aerial.lead, k)
    lateral = rng.uniform(*aerial.lateral, k)
    altitude = rng.uniform(*aerial.altitude, k)
    pitch = np.radians(rng.uniform(*aerial.pitch_deg, k))
    heading = side.yaw + np.radians(rng.uniform(*aerial.relative_yaw_deg, k))
    f = np.array([np.cos(side.yaw), np.sin(side.yaw)])
    left = np.array([-f[1], f[0]])
    target = np.asarray(side.position[:2]) + lead[:, None] * f + lateral[:, None] * left
    target = np.clip(target, -np.asarray(half_extent), np.asarray(half_extent))
    back = altitude / pm.tan(-pitch)
    xy = target - back[:, None] * np.column_stack([np.cos(heading), np.sin(heading)])
    cam = aerial.intrinsics
    return [
        (
            Camera(
                position=(float(xy[i, 0]), float(xy[i, 1]), float(altitude[i])),
                yaw=float(pm.arctan2(np.sin(heading[i]), np.cos(heading[i]))),
                pitch=float(pitch[i]),
                width=cam.width,
                height=cam.height,
                hfov_deg=cam.hfov_deg,
            ),
            target[i],
        )
        for i in range(k)
    ]
