"""One side of a DAIR-V2X-family frame (DAIR-V2X-C, V2X-Seq-SPD): its label file's boxes and the
box view they make. Shared by :mod:`.v2x_seq` and :mod:`.dair_v2x`; imports neither.

A side's label file is a JSON list of objects: ``type``, ``3d_dimensions`` {h, w, l} (metres),
``3d_location`` {x, y, z} (box centre in that side's LiDAR frame: x forward, y left, z up),
``rotation`` (yaw about z, radians), and where the dataset has them ``track_id`` (V2X-Seq-SPD;
absent, empty or "-1" for objects without a track, such as traffic cones) and ``token``
(V2X-Seq-SPD's per-label identity, which the cooperative label names). DAIR-V2X-C's labels have
neither.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from cadsim import portable_math as pm
from cadsim.dataset.box_record import BoxView, box_detections
from cadsim.importers import ImportFormatError
from cadsim.importers.safe_read import field, number, read_json, shown
from cadsim.importers.sensor_frame import (
    apply,
    boxes_in_view,
    heading_of,
    sensor_camera,
    yaw_directions,
)
from cadsim.observer_pose import ObserverPose
from cadsim.world import WorldObject

NO_TRACK = "-1"
MAX_BOXES = 1000
"""Most boxes one side's label file may hold (checked before anything is built from them): the
ground truth's assignment is a boxes × boxes matrix per frame (1000² float64: 8 MB). The real
DAIR-V2X-C pair checked (docs/external-data.md) holds 23 and 8 boxes."""
MAX_LABEL_BYTES = 4 * 2**20
"""Largest label file read (bytes), so that parsing it stays small too: a box is about 300
bytes of JSON in DAIR-V2X-C, 450 with V2X-Seq's track id and token (1,000 boxes: < 0.5 MiB)."""


def _optional_id(obj: dict, key: str, path: Path, where: str) -> str | None:
    """``obj[key]`` as a string, None when absent, empty or "-1"; a number or string only."""
    value = obj.get(key)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | str) or len(str(value)) > 64:
        raise ImportFormatError(
            path, f"{where}.{key}: expected an id string, got {shown(value, 30)}"
        )
    text = str(value)
    return None if text in ("", NO_TRACK) else text


def read_boxes(path: Path) -> list[dict]:
    """A side's objects: ``track`` and ``token`` (str or None), ``cls`` (``type`` lower-cased),
    ``centre`` (x, y, z, sensor frame, metres), ``yaw`` (radians), ``size`` (l, w, h, metres),
    ``where`` (the object's index, for errors)."""
    objects = read_json(path, MAX_LABEL_BYTES)
    if not isinstance(objects, list):
        raise ImportFormatError(path, "top level: expected a list of objects")
    if len(objects) > MAX_BOXES:
        raise ImportFormatError(
            path, f"{len(objects)} boxes, more than {MAX_BOXES} in one side's label file"
        )
    out = []
    for k, obj in enumerate(objects):
        where = f"[{k}]"
        dims = field(obj, "3d_dimensions", path, where)
        loc = field(obj, "3d_location", path, where)
        size = [number(field(dims, a, path, f"{where}.3d_dimensions"), path, f"{where}.3d_dimensions.{a}", 1e3) for a in "lwh"]  # fmt: skip
        if min(size) <= 0:
            raise ImportFormatError(path, f"{where}.3d_dimensions: sizes must be > 0, got {size}")
        centre = [number(field(loc, a, path, f"{where}.3d_location"), path, f"{where}.3d_location.{a}") for a in "xyz"]  # fmt: skip
        kind = field(obj, "type", path, where)
        if not isinstance(kind, str) or not kind:
            raise ImportFormatError(
                path, f"{where}.type: expected a class name, got {shown(kind, 30)}"
            )
        out.append(
            {
                "track": _optional_id(obj, "track_id", path, where),
                "token": _optional_id(obj, "token", path, where),
                "cls": kind.lower()[:40],
                "centre": centre,
                "yaw": number(field(obj, "rotation", path, where), path, f"{where}.rotation", 1e3),
                "size": size,
                "where": where,
            }
        )
    return out


def side_view(
    observer: str, kind: str, sensor: np.ndarray, body: np.ndarray, boxes: list[dict]
) -> tuple[BoxView, list[WorldObject]]:
    """A side's box view (``sensor``: 4×4 LiDAR → world; ``body``: 4×4 body → world; each box
    with an ``id``) and its boxes as world objects."""
    camera = sensor_camera(sensor)
    k = len(boxes)
    centres = np.array([b["centre"] for b in boxes], dtype=float).reshape(k, 3)
    yaws = np.array([b["yaw"] for b in boxes], dtype=float)
    world = apply(sensor, centres)
    directions = pm.matmul(yaw_directions(yaws), sensor[:3, :3].T)
    positions, headings = boxes_in_view(camera, world, directions)
    sizes = np.array([b["size"] for b in boxes], dtype=float).reshape(k, 3)
    ids, classes = [b["id"] for b in boxes], [b["cls"] for b in boxes]
    forward = body[:3, 0]
    pose = ObserverPose(
        tuple(float(v) for v in body[:3, 3]), float(pm.arctan2(forward[1], forward[0]))
    )
    det = box_detections(positions, sizes, headings, ids, classes)
    view = BoxView(observer, kind, camera, pose, det, sizes)
    world_yaw = heading_of(directions)
    objects = [
        WorldObject(i, c, "box", tuple(w), float(y), tuple(s), (0.5, 0.5, 0.5))
        for i, c, w, y, s in zip(
            ids, classes, world.tolist(), world_yaw, sizes.tolist(), strict=True
        )
    ]
    return view, objects


__all__ = ["MAX_BOXES", "MAX_LABEL_BYTES", "NO_TRACK", "read_boxes", "side_view"]
