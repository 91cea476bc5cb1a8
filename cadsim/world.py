"""World snapshot data model shared by every traffic source, the renderer and the detector.

World frame: right-handed, x east, y north, z up, metres (SUMO's network x/y). Headings (``yaw``)
are radians counter-clockwise from +x. Sources convert their own conventions into this frame once,
at the boundary (SUMO: ``cadsim.sources.sumo.frames``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def wrap_angle(angle: np.ndarray | float) -> np.ndarray:
    """Angles [rad] wrapped into [-pi, pi)."""
    return (np.asarray(angle, dtype=float) + np.pi) % (2.0 * np.pi) - np.pi


@dataclass(frozen=True)
class WorldObject:
    """One object in the world.

    id: stable across snapshots of one simulation. cls: semantic class ("car", "van", "bus",
    "truck", "bicycle", "person", "traffic_light", "sign", "robot", "box", "cone", "building",
    "road", ...). shape: mesh key the renderer knows ("car", "box", "cylinder", "person",
    "traffic_light", "sign", "robot", ...). center: (3,) bounding-box centre, world frame, metres.
    yaw: heading, radians CCW from +x. size: (3,) length along heading, width, height, metres.
    color: RGB in [0, 1]. target: True for objects that count as detections (False for
    occluders/context such as buildings and the road surface). variant: free mesh variant key
    (e.g. a robot's marker colour). state: source-specific state (e.g. a signal's "r"/"y"/"G").
    velocity: (3,) world frame, metres per second (0 for static objects; what a message latency
    moves the object by, ``cadsim.sensing.latency``).
    """

    id: str
    cls: str
    shape: str
    center: tuple[float, float, float]
    yaw: float
    size: tuple[float, float, float]
    color: tuple[float, float, float]
    target: bool = True
    variant: str = ""
    state: str = ""
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def pose(self) -> np.ndarray:
        """4x4 homogeneous transform from the object's frame (x forward, z up) to world."""
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        T = np.eye(4)
        T[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
        T[:3, 3] = self.center
        return T

    def as_dict(self) -> dict:
        return {
            "id": self.id,
            "cls": self.cls,
            "shape": self.shape,
            "center": [float(v) for v in self.center],
            "yaw": float(self.yaw),
            "size": [float(v) for v in self.size],
            "color": [float(v) for v in self.color],
            "target": bool(self.target),
            "variant": self.variant,
            "state": self.state,
            "velocity": [float(v) for v in self.velocity],
        }

    @classmethod
    def from_dict(cls, d: dict) -> WorldObject:
        return cls(
            id=d["id"],
            cls=d["cls"],
            shape=d["shape"],
            center=tuple(d["center"]),
            yaw=float(d["yaw"]),
            size=tuple(d["size"]),
            color=tuple(d["color"]),
            target=bool(d.get("target", True)),
            variant=d.get("variant", ""),
            state=d.get("state", ""),
            velocity=tuple(d.get("velocity", (0.0, 0.0, 0.0))),
        )


@dataclass
class Snapshot:
    """All objects at one instant. time: simulation seconds. objects: every object, targets and
    static context alike (the renderer draws all; detection keeps only ``target`` ones)."""

    time: float
    objects: list[WorldObject] = field(default_factory=list)
    meta: dict = field(default_factory=dict)

    def by_id(self) -> dict[str, WorldObject]:
        return {o.id: o for o in self.objects}
