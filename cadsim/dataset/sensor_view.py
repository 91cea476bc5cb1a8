"""Reading one sensor of a two-sensor dataset (``sensor = "both"``): the same records, frames and
ground truth, with either the camera's detections or the LiDAR detector's boxes as the views.

A ``"both"`` record keeps the camera detections in ``detections.npz`` (what a plain read gives)
and the LiDAR boxes beside the points in ``lidar.npz`` (``view{k}_box_*``, LiDAR frame:
x forward, y left, z up, metres; :mod:`cadsim.dataset.lidar_points`). :func:`lidar_pair` turns a
record's pair into the pair a ``sensor = "lidar"`` record of the same frame would be: the
boxes as box-only detections (positions in the camera-frame convention with the LiDAR at the
origin, the 48-d box feature vector of the fitted sizes, headings, the reported classes), the
record's ``cues`` the box cues, each observer's ``camera`` entry the LiDAR's pose — so the true
relative pose, the pose fit, the oracle row and the localisation prior are the LiDAR's, exactly
as for a LiDAR-only record. Ground truth: the box ids (the object most of a box's points hit;
``clutter:lidar:…`` for false positives); a true class is that object's class, a false
positive's its reported one (:mod:`cadsim.sensing.lidar.box_truth`). Point counts are not kept
in a ``"both"`` record, so ``pixels`` is 0 (unknown). Imports neither SUMO nor pyrender.
"""

from __future__ import annotations

import numpy as np

from cadsim.dataset import layout
from cadsim.dataset.detections import ViewDetections
from cadsim.dataset.encoding import load_npz
from cadsim.dataset.manifest import DatasetError
from cadsim.sensing.box_features import (
    BOX_CUES,
    box_feature_vector,
    heading_from_lidar_yaw,
    lidar_to_camera_convention,
)

SENSORS = ("camera", "lidar", "camera-common", "lidar-common")
"""What :class:`cadsim.dataset.reader.Dataset` can read a ``"both"`` dataset as: either sensor
whole, or either sensor's detections in the region both cover (``-common``:
:mod:`cadsim.sensing.lidar.camera_coverage`; every detection of a view whose reported centre lies
in its camera's frustum and range and in its LiDAR's range, false positives included)."""


def dataset_sensor(manifest: dict) -> str:
    """What a dataset's records carry: "camera", "lidar" or "both" (its manifest's generation
    configuration; imported and older datasets: "camera")."""
    return str((manifest.get("generation") or {}).get("sensor", "camera"))


def check_sensor(sensor: str | None, stored: str, where: str) -> str | None:
    """The sensor to read a dataset of ``stored`` records as: None for the records' own
    detections (``sensor`` None, or the one sensor the records have), "lidar" for the boxes of a
    ``"both"`` dataset. ``ValueError`` naming ``where`` for a sensor the records do not have."""
    if sensor is None:
        return None
    if sensor not in SENSORS:
        raise ValueError(f"{where}: sensor: expected one of {', '.join(SENSORS)}, got {sensor!r}")
    if stored == "both":
        return None if sensor == "camera" else sensor
    if stored != sensor:
        raise ValueError(
            f"{where}: sensor {sensor!r}: the records carry {stored} detections only (a "
            'scenario with sensor = "both" gives both)'
        )
    return None


def lidar_detections(boxes: dict, objects: list[dict]) -> ViewDetections:
    """One view's LiDAR boxes (a :class:`~cadsim.dataset.lidar_points.LidarView`'s ``boxes``:
    ``centres``, ``sizes`` (k, 3) metres LiDAR frame, ``yaws`` (k,) radians, ``classes``,
    ``ids``) as box-only detections; ``objects``: the record's ``objects`` (for true classes)."""
    ids = [str(v) for v in np.asarray(boxes["ids"]).reshape(-1)]
    reported = [str(v) for v in np.asarray(boxes["classes"]).reshape(-1)]
    sizes = np.asarray(boxes["sizes"], dtype=np.float64).reshape(-1, 3)
    by_id = {str(o["id"]): str(o["cls"]) for o in objects}
    k = len(ids)
    return ViewDetections(
        positions=lidar_to_camera_convention(boxes["centres"]),
        boxes=np.zeros((k, 4)),
        features=box_feature_vector(sizes) if k else np.zeros((0, 48), np.float32),
        object_ids=ids,
        true_classes=[by_id.get(i, r) for i, r in zip(ids, reported, strict=True)],
        pixels=np.zeros(k, dtype=np.int64),
        reported_classes=reported,
        headings=heading_from_lidar_yaw(boxes["yaws"]),
    )


def sensor_pair(pair, sensor: str, lidar_range_m: float):
    """``pair`` (of a ``"both"`` record) read as ``sensor`` (one of :data:`SENSORS` but
    "camera"); ``lidar_range_m``: the LiDAR's specified range (metres)."""
    if sensor == "lidar":
        return lidar_pair(pair)
    camera_rows, lidar_rows = common_rows(pair, lidar_range_m)
    base, rows = (lidar_pair(pair), lidar_rows) if sensor == "lidar-common" else (pair, camera_rows)
    views = tuple(v.take(r) for v, r in zip((base.view1, base.view2), rows, strict=True))
    out = type(pair)(
        base.path, base.index, base._entry, base._noise, base._detection, views,
        record_files=base._record_files, view_numbers=base.view_numbers,
    )  # fmt: skip
    out.__dict__["record"] = base.record
    return out


def common_rows(pair, lidar_range_m: float) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Per view of ``pair`` (a ``"both"`` record read as stored): the rows of its camera
    detections and of its LiDAR boxes that lie in the region both sensors cover (the camera's
    frustum up to its detector's ``max_depth_m``, within ``lidar_range_m`` of the LiDAR)."""
    from cadsim.sensing.lidar.camera_coverage import covered, lidar_box_world

    poses, boxes = _lidar_boxes(pair)
    depth = float(pair._detection.get("max_depth_m", 80.0))
    camera_rows, lidar_rows = [], []
    for view, camera, pose, found in zip((pair.view1, pair.view2), pair.cameras, poses, boxes, strict=True):  # fmt: skip
        world = camera.camera_to_world(view.positions) if len(view) else np.zeros((0, 3))
        camera_rows.append(np.flatnonzero(covered(world, camera, pose, depth, lidar_range_m)))
        centres = lidar_box_world(found["centres"], pose)
        lidar_rows.append(np.flatnonzero(covered(centres, camera, pose, depth, lidar_range_m)))
    return camera_rows, lidar_rows


def lidar_pair(pair):
    """``pair`` (a :class:`~cadsim.dataset.frame_pair.FramePair` of a ``"both"`` record) read
    as its LiDAR: the boxes as the views, the LiDAR poses as the observers' sensors, the box cues
    (module docstring). ``DatasetError`` for a record without LiDAR boxes."""
    from cadsim.dataset.record_format import lidar_camera

    poses, boxes = _lidar_boxes(pair)
    record = dict(pair.record)
    observers = [dict(o) for o in record["observers"]]
    for v, pose in zip(pair.view_numbers, poses, strict=True):
        observers[v - 1]["camera"] = lidar_camera(pose).as_dict()
        observers[v - 1]["sensor"] = "lidar"
    record |= {"observers": observers, "cues": list(BOX_CUES)}
    views = tuple(lidar_detections(b, record["objects"]) for b in boxes)
    out = type(pair)(
        pair.path, pair.index, pair._entry, pair._noise, pair._detection, views,
        record_files=layout.record_files(2, "lidar"), view_numbers=pair.view_numbers,
    )  # fmt: skip
    out.__dict__["record"] = record
    return out


_BOX_ARRAYS = ("centres", "sizes", "yaws", "classes", "ids")


def _lidar_boxes(pair) -> tuple[list[np.ndarray], list[dict]]:
    """Per view of ``pair``: its LiDAR's pose (4 × 4, LiDAR → world) and its boxes, read from
    ``lidar.npz`` without decoding the points (the pose and ``box_*`` arrays only); a one-line
    ``DatasetError`` naming the file when they are missing or malformed."""
    path = pair.path / layout.LIDAR_NPZ
    names = [f"view{v}_{n}" for v in pair.view_numbers for n in ("pose", *(f"box_{b}" for b in _BOX_ARRAYS))]  # fmt: skip
    try:
        if layout.LIDAR_NPZ not in pair._record_files or not path.is_file():
            raise ValueError('no LiDAR boxes to read the pair with (not a sensor = "both" record)')
        arrays = load_npz(str(path), str(path), keys=names)
        poses, boxes = [], []
        for v in pair.view_numbers:
            pose = np.asarray(arrays[f"view{v}_pose"], dtype=np.float64)
            if pose.shape != (4, 4) or not np.isfinite(pose).all():
                raise ValueError(f"view{v}_pose: expected a finite (4, 4) transform")
            found = {b: arrays[f"view{v}_box_{b}"] for b in _BOX_ARRAYS}
            k = len(found["ids"])
            shapes = {"centres": (k, 3), "sizes": (k, 3), "yaws": (k,), "classes": (k,)}
            for b, shape in shapes.items():
                if np.shape(found[b]) != shape:
                    raise ValueError(f"view{v}_box_{b}: expected shape {shape}")
            poses.append(pose)
            boxes.append(found)
    except ValueError as exc:
        message = str(exc).splitlines()[0]
        raise DatasetError(
            message if message.startswith(str(path)) else f"{path}: {message}"
        ) from None
    return poses, boxes


__all__ = [
    "SENSORS",
    "check_sensor",
    "common_rows",
    "dataset_sensor",
    "lidar_detections",
    "lidar_pair",
    "sensor_pair",
]
