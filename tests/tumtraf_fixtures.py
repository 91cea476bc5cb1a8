"""A small TUMTraf-V2X folder written from the ASAM OpenLABEL schema as TUMTraf-V2X uses it
(``openlabel.frames.<k>.objects.<uid>.object_data.cuboid`` with ``val`` = centre, quaternion
scalar last, size; the sensors' coordinate systems and the transform between them), from the
world boxes of :mod:`format_fixtures`: objects seen by both sides share their uid."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from format_fixtures import INFRA_LIDAR, INFRA_SEES, VEHICLE_SEES, WORLD, vehicle_lidar

VEHICLE, INFRA = "vehicle_lidar_robosense", "s110_lidar_ouster_south"
EPOCH_S = 1_688_626_050.0


def _cuboid(sensor: np.ndarray, box, system: str) -> dict:
    x, y, z, yaw, length, w, h = box
    inv = np.linalg.inv(sensor)
    centre = inv @ [x, y, z, 1.0]
    d = inv[:3, :3] @ [np.cos(yaw), np.sin(yaw), 0.0]
    local = float(np.arctan2(d[1], d[0]))
    quaternion = [0.0, 0.0, float(np.sin(local / 2)), float(np.cos(local / 2))]
    return {"name": "shape3D", "coordinate_system": system,
            "val": [*centre[:3].tolist(), *quaternion, length, w, h]}  # fmt: skip


def vehicle_to_infrastructure(frame: int) -> np.ndarray:
    return np.linalg.inv(INFRA_LIDAR) @ vehicle_lidar(frame)


def write_tumtraf(root: Path, transforms: str = "frame", timestamps: bool = True) -> Path:
    """``root/labels/cooperative.json``: the three frames of WORLD. ``transforms``: "frame"
    (each frame's ``frame_properties.transforms``) or "systems" (the coordinate systems'
    ``pose_wrt_parent`` under one root, the vehicle's for frame 0 — so use one frame then)."""
    frames = {}
    count = 1 if transforms == "systems" else len(WORLD)
    for k, boxes in enumerate(WORLD[:count]):
        objects = {}
        for oid, box in sorted(boxes.items()):
            cuboids = []
            if oid in VEHICLE_SEES:
                cuboids.append(_cuboid(vehicle_lidar(k), box, VEHICLE))
            if oid in INFRA_SEES:
                cuboids.append(_cuboid(INFRA_LIDAR, box, INFRA))
            kind = "PEDESTRIAN" if oid == "c" else "CAR"
            objects[f"uuid-{oid}"] = {"object_data": {"name": f"{kind}_{oid}", "type": kind,
                                                      "cuboid": cuboids}}  # fmt: skip
        props = {}
        if timestamps:
            props["timestamp"] = EPOCH_S + 0.1 * k
        if transforms == "frame":
            matrix = vehicle_to_infrastructure(k).reshape(-1).tolist()
            props["transforms"] = {f"{VEHICLE}_to_{INFRA}": {
                "src": VEHICLE, "dst": INFRA, "transform_src_to_dst": {"matrix4x4": matrix}}}  # fmt: skip
        frames[str(k)] = {"frame_properties": props, "objects": objects}
    systems = {
        "s110_base": {"type": "scene_cs", "parent": "", "children": [INFRA, VEHICLE]},
        INFRA: {"type": "sensor_cs", "parent": "s110_base",
                "pose_wrt_parent": {"matrix4x4": INFRA_LIDAR.reshape(-1).tolist()}},
        VEHICLE: {"type": "sensor_cs", "parent": "s110_base",
                  "pose_wrt_parent": {"matrix4x4": vehicle_lidar(0).reshape(-1).tolist()}},
    }  # fmt: skip
    doc = {"openlabel": {"metadata": {"schema_version": "1.0.0"}, "coordinate_systems": systems,
                         "frames": frames}}  # fmt: skip
    path = root / "labels" / "cooperative.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(doc), encoding="utf-8")
    return root
