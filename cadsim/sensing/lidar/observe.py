"""One observer's LiDAR view of a snapshot: mount, sweep, boxes, their ground truth.

A vehicle observer carries a roof unit of the ``[lidar]`` table's pattern; an observer on no
object (a roadside unit's pole camera) a level unit of ``roadside_preset`` at the camera's
position and heading. The sweep's random draws come from the view's seed (the frame's identity,
``cadsim.dataset.seeds``) on a stream of its own (:data:`LIDAR_STREAM`), so a scenario with both
sensors draws its depth noise and its LiDAR noise independently; the box detector's size
scatter on a sub-stream of it (:data:`SIZE_STREAM`). The carrier itself is not drawn.
The detector's nominal mounting height is the sensor's height above the renderer's ground plane
(what a calibrated mount knows).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cadsim.camera import Camera
from cadsim.dataset.detections import ViewDetections
from cadsim.render.scene import GROUND_Z
from cadsim.sensing.lidar.beam_pattern import LidarConfig
from cadsim.sensing.lidar.box_detector import LidarBoxes, detect_boxes
from cadsim.sensing.lidar.box_truth import box_ground_truth
from cadsim.sensing.lidar.mount import level_pose, roof_pose
from cadsim.sensing.lidar.raycast import LidarScan, scan
from cadsim.world import Snapshot

LIDAR_STREAM = 0x11DA4
SIZE_STREAM = 0x512E
"""Sub-stream (under :data:`LIDAR_STREAM`) of the box detector's size scatter."""


@dataclass(frozen=True, eq=False)
class LidarObservation:
    """pose: (4, 4) LiDAR → world. scan: the sweep. boxes: the detector's boxes (LiDAR frame).
    ids, true_classes: their ground truth. detections: what matchers see."""

    pose: np.ndarray
    scan: LidarScan
    boxes: LidarBoxes
    ids: list[str]
    true_classes: list[str]
    detections: ViewDetections


def observe(
    snapshot: Snapshot,
    camera: Camera,
    observer_id: str,
    config: LidarConfig,
    seed: int,
    view_tag: str,
) -> LidarObservation:
    """The LiDAR view of the observer carrying ``camera`` (``observer_id`` "" for none)."""
    carrier = snapshot.by_id().get(observer_id) if observer_id else None
    if carrier is not None:
        pose, pattern = roof_pose(carrier), config.pattern()
    else:
        pose, pattern = level_pose(camera.position, camera.yaw), config.pattern(roadside=True)
    rng = np.random.default_rng([int(seed), LIDAR_STREAM])
    sweep = scan(snapshot, pose, pattern, rng, {observer_id} if observer_id else ())
    height = float(pose[2, 3]) - GROUND_Z
    size_rng = np.random.default_rng([int(seed), LIDAR_STREAM, SIZE_STREAM])
    boxes = detect_boxes(sweep.points, height, max(pattern.elevations_deg), size_rng=size_rng)
    objects = snapshot.objects
    ids, true = box_ground_truth(
        boxes, sweep.object_index, [o.id for o in objects], [o.cls for o in objects],
        [o.target for o in objects], view_tag,
    )  # fmt: skip
    return LidarObservation(pose, sweep, boxes, ids, true, boxes.to_view_detections(ids, true))
