"""Box-only frames built in memory (for the box-record, importer and exporter tests): a few
world boxes seen by two sensors, written through the importers' writer."""

from __future__ import annotations

import numpy as np

from cadsim.dataset.box_record import BoxRecord, BoxView, box_detections
from cadsim.importers.sensor_frame import boxes_in_view, sensor_camera, yaw_directions
from cadsim.observer_pose import ObserverPose
from cadsim.world import WorldObject

BOXES = {  # id: (centre x, y, z; yaw; length, width, height; class)
    "a": (10.0, 2.0, 0.8, 0.3, 4.5, 1.9, 1.6, "car"),
    "b": (14.0, -3.0, 0.9, -1.2, 10.0, 2.5, 3.2, "bus"),
    "c": (8.0, 6.0, 0.9, 2.0, 0.6, 0.6, 1.8, "person"),
    "d": (20.0, 1.0, 0.8, 0.0, 4.2, 1.8, 1.5, "car"),
    "e": (-4.0, 0.0, 0.8, 0.1, 4.0, 1.8, 1.5, "car"),
}


def sensor(x: float, y: float, z: float, yaw: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    t = np.eye(4)
    t[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    t[:3, 3] = (x, y, z)
    return t


def box_view(observer: str, kind: str, pose: np.ndarray, ids: list[str]) -> BoxView:
    camera = sensor_camera(pose)
    rows = np.array([BOXES[i][:7] for i in ids], dtype=float).reshape(-1, 7)
    positions, headings = boxes_in_view(camera, rows[:, :3], yaw_directions(rows[:, 3]))
    det = box_detections(positions, rows[:, 4:7], headings, ids, [BOXES[i][7] for i in ids])
    body = ObserverPose((float(pose[0, 3]), float(pose[1, 3]), 0.75), camera.yaw)
    return BoxView(observer, kind, camera, body, det, rows[:, 4:7])


def objects() -> list[WorldObject]:
    return [
        WorldObject(i, b[7], "box", b[:3], b[3], b[4:7], (0.5, 0.5, 0.5)) for i, b in BOXES.items()
    ]


def two_view_record(episode: int = 0, slot: int = 0) -> BoxRecord:
    v1 = box_view("1", "vehicle", sensor(0.0, 0.0, 1.8, 0.1), ["a", "b", "c", "d"])
    v2 = box_view("-1", "roadside", sensor(18.0, 8.0, 5.0, -2.5), ["b", "c", "a", "e"])
    return BoxRecord(episode, slot, episode, 1.5, (v1, v2), objects(), {"source": "test"})
