"""Small world snapshots for the LiDAR tests: planted boxes and cars around a sensor at the
origin, and a flat beam pattern whose ranges can be checked by hand."""

from __future__ import annotations

import numpy as np

from cadsim.sensing.lidar.beam_pattern import BeamPattern
from cadsim.sensing.lidar.mount import level_pose
from cadsim.world import Snapshot, WorldObject

SENSOR_HEIGHT_M = 1.8


def box(oid: str, x: float, y: float, size=(2.0, 2.0, 2.0), yaw: float = 0.0, cls: str = "box", shape: str = "box") -> WorldObject:  # fmt: skip
    """A target standing on the ground at (x, y), world metres."""
    return WorldObject(oid, cls, shape, (x, y, size[2] / 2.0), yaw, tuple(size), (0.5, 0.5, 0.5))


def car(oid: str, x: float, y: float, yaw: float = 0.0, size=(4.5, 1.8, 1.5)) -> WorldObject:
    return box(oid, x, y, size, yaw, cls="car", shape="car")


def sensor_pose(height: float = SENSOR_HEIGHT_M) -> np.ndarray:
    """A level sensor above the world origin heading +x."""
    return level_pose((0.0, 0.0, height), 0.0)


def flat_pattern(azimuth_steps: int = 360, elevations=(0.0,), sigma: float = 0.0, dropout: float = 0.0) -> BeamPattern:  # fmt: skip
    """Noise-free channels at the given elevations (degrees)."""
    return BeamPattern("test", tuple(elevations), azimuth_steps, 0.1, 200.0, sigma, dropout)


def snapshot(*objects: WorldObject) -> Snapshot:
    return Snapshot(0.0, list(objects))
