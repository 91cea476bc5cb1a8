"""The frame-pair record: what one accepted observer pair leaves on disk, and its encoding.

Files of ``pairs/eEEEEE_sSS/`` (see docs/dataset.md for every field):
``view1.png``/``view2.png`` colour (RGB as PNG); ``depth.npz`` clean depth ``depth1``/``depth2``
(H, W) float32 metres along the optical axis, 0 = no hit; ``instance.npz`` ``instance1``/
``instance2`` (H, W) int32 index into ``record.json``'s ``objects``, -1 = none; ``detections.npz``
``view{1,2}_{positions,boxes,features,object_ids,true_classes,reported_classes,pixels}`` at the scenario's noise
config; ``record.json`` cameras, observers (with their true world poses), seeds, snapshot time and
objects, ground truth, and the localisation prior's parameters (``prior``; the pose error itself is
drawn at read time from ``observers[].localisation_seed``).

Records of imported data (``cadsim import``) have no images: ``detections.npz`` and ``record.json``
only (the manifest's ``record_files``), the prior's world positions stored as ``view{1,2}_world``.

Format versions: 1, the first; 2 adds ``observers[].pose``, ``observers[].attribute_seed``
(features carry detector-like attributes from then on), the localisation prior (``prior``,
``observers[].localisation_seed``) and image-less imported records; 3 adds each object's
``velocity`` (m/s, world frame), which message latency needs (``cadsim.sensing.latency``).
Version 4 is the N-view snapshot record (:class:`SnapshotRecord`, DESIGN §12): ``view1.png …
viewN.png``, ``depth1 … depthN``, ``instance1 … instanceN``, ``view{k}_…`` detections, one
observer entry per view with its ``kind`` ("vehicle" or "roadside": a roadside unit's pose is
known exactly), per-view detection counts and per-pair covisible counts; frame-pair datasets are
still written as version 3, byte for byte as before. Versions 5 (frame pairs) and 6 (N-view
snapshots) store each detection's true class as ``view{k}_true_classes`` (ground truth, for
metrics only) and the class the view's detector reported as ``view{k}_reported_classes`` (what a
matcher sees, ``Problem.classes1/2``); earlier versions stored only the true class, as
``view{k}_classes``, and are read with no reported class (``Problem.classes1/2`` None).
Version 7 is a version-5 frame pair that is one frame of a sequence (a ``[sequence]`` scenario):
``record.json`` adds ``sequence`` (``id``: the record name of its frame 0, ``frame``: 0-based
index, ``frames``: the sequence's length, ``interval_s``, ``start_time`` and the odometry
``model``) and each ``observers[]`` entry an ``odometry`` (the observer's pose relative to its
frame-0 pose as dead reckoning reports it: ``position`` [x, y], ``yaw``, ``distance_m``) and its
``odometry_seed``; the manifest's records carry ``sequence`` and ``frame``. Datasets without a
``[sequence]`` are written as version 5 (or 6), byte for byte as before. A change of the record layout bumps
``FORMAT_VERSION``; the reader reads
:data:`READABLE_VERSIONS` and refuses others with a message naming them (a version-2 dataset is
read with every velocity 0, and the latency presets refuse it).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cadsim import portable_math as pm
from cadsim.camera import Camera
from cadsim.dataset import layout
from cadsim.dataset.detections import ViewDetections, ground_truth_pairs
from cadsim.dataset.difficulty import difficulty_factors
from cadsim.dataset.encoding import json_bytes, npz_bytes, png_bytes
from cadsim.dataset.lidar_points import view_arrays as lidar_view_arrays
from cadsim.observer_pose import ObserverPose, camera_to_world
from cadsim.sensing.localisation import LocalisationConfig
from cadsim.world import WorldObject

FORMAT_VERSION = 5
MULTI_VIEW_FORMAT = 6
SEQUENCE_FORMAT = 7  # frame pairs that are frames of sequences ([sequence] scenarios)
READABLE_VERSIONS = (2, 3, 4, 5, 6, SEQUENCE_FORMAT)
MULTI_VIEW_VERSIONS = (4, MULTI_VIEW_FORMAT)  # N-view snapshots; the other versions: frame pairs
TRUE_CLASS_VERSION = 5  # from 5 on: view{k}_true_classes (+ reported_classes), not view{k}_classes
OBSERVER_KINDS = ("vehicle", "roadside")  # an N-view record's observers[].kind


@dataclass(frozen=True, eq=False)
class ViewCapture:
    """One observer's view: camera, the id of the object carrying it ("" for none), the rendered
    colour (H, W, 3) uint8 RGB, clean depth (H, W) float32 metres, instance ids (H, W) int32, the
    detections at the scenario's noise config, the seed of that noise, the seed of the detector's
    attribute errors, the observer's true world pose, and the seed of its localisation error
    (drawn at read time, ``cadsim.sensing.localisation``)."""

    camera: Camera
    observer_id: str
    color: np.ndarray
    depth: np.ndarray
    instance: np.ndarray
    detections: ViewDetections
    noise_seed: int
    attribute_seed: int
    pose: ObserverPose
    localisation_seed: int = 0
    lidar: Any = None
    """A :class:`~cadsim.sensing.lidar.observe.LidarObservation` when the scenario has a LiDAR
    (``sensor`` "lidar": ``color``, ``depth``, ``instance`` are None and ``detections`` are its
    boxes; "both": the camera's as always, the LiDAR's points and boxes go to ``lidar.npz``)."""


@dataclass(frozen=True, eq=False)
class PairRecord:
    """One accepted frame pair. Identity: (episode, slot). time: simulation seconds.
    localisation: the scenario's ``[localisation]`` table (``position_sigma_m``,
    ``yaw_sigma_deg``; missing keys take ``LocalisationConfig``'s defaults)."""

    episode: int
    slot: int
    sim_seed: int
    time: float
    objects: list[WorldObject]
    view1: ViewCapture
    view2: ViewCapture
    meta: dict = field(default_factory=dict)
    localisation: dict = field(default_factory=dict)
    sequence: dict | None = None  # a sequence frame (format 7): id, frame, frames, ..., odometry


def jsonable(value):
    """``value`` with numpy scalars/arrays and tuples turned into plain JSON types."""
    return json.loads(json.dumps(value, default=_json_default))


def _json_default(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, set | frozenset):
        return sorted(value)
    raise TypeError(f"record metadata: {type(value).__name__} is not JSON-serialisable")


def _check_image(name: str, arr: np.ndarray, shape: tuple[int, int], dtype) -> np.ndarray:
    arr = np.asarray(arr)
    if arr.shape[:2] != shape or arr.dtype != dtype:
        raise ValueError(f"{name}: expected {shape} {np.dtype(dtype)}, got {arr.shape} {arr.dtype}")
    return arr


@dataclass(frozen=True, eq=False)
class SnapshotRecord:
    """One accepted N-view snapshot (format version 6): the views of every observer of the
    snapshot, in observer order (vehicles first, then roadside units). kinds: per view
    "vehicle" or "roadside". Other fields as :class:`PairRecord`."""

    episode: int
    slot: int
    sim_seed: int
    time: float
    objects: list[WorldObject]
    views: tuple[ViewCapture, ...]
    kinds: tuple[str, ...]
    meta: dict = field(default_factory=dict)
    localisation: dict = field(default_factory=dict)


def lidar_camera(pose: np.ndarray) -> Camera:
    """A level LiDAR (4×4 LiDAR → world) as a camera pose: its optical axis the LiDAR's x."""
    return Camera(tuple(float(v) for v in pose[:3, 3]), float(pm.arctan2(pose[1, 0], pose[0, 0])))


def _observer_entry(view: ViewCapture) -> dict:
    lidar_only = view.lidar is not None and view.color is None
    entry = {
        "id": view.observer_id,
        "camera": (lidar_camera(view.lidar.pose) if lidar_only else view.camera).as_dict(),
        "pose": view.pose.as_dict(),
        "noise_seed": int(view.noise_seed),
        "attribute_seed": int(view.attribute_seed),
        "localisation_seed": int(view.localisation_seed),
    }
    if view.lidar is not None:
        entry["sensor"] = "lidar" if lidar_only else "camera+lidar"
        entry["lidar"] = {"pattern": view.lidar.scan.pattern.name}
    return entry


def _files(views: tuple[ViewCapture, ...], record: dict) -> dict[str, bytes]:
    """The record's files: colour, depth, instance maps and detections of ``views`` (numbered
    from 1) and ``record.json``, after checking every image's shape and type."""
    numbered = list(enumerate(views, start=1))
    if all(v.lidar is not None and v.color is None for v in views):
        return _lidar_files(numbered, record)
    for k, v in numbered:
        hw = (v.camera.height, v.camera.width)
        _check_image(f"view{k} colour", v.color, hw, np.uint8)
        _check_image(f"view{k} depth", v.depth, hw, np.float32)
        _check_image(f"view{k} instance", v.instance, hw, np.int32)
    detections = {}
    for k, v in numbered:
        detections |= v.detections.to_arrays(f"view{k}")
    files = {
        **{layout.view_png(k): png_bytes(v.color) for k, v in numbered},
        layout.DEPTH_NPZ: npz_bytes({f"depth{k}": v.depth for k, v in numbered}),
        layout.INSTANCE_NPZ: npz_bytes({f"instance{k}": v.instance for k, v in numbered}),
        layout.DETECTIONS_NPZ: npz_bytes(detections),
        layout.RECORD_JSON: json_bytes(record),
    }
    if any(v.lidar is not None for v in views):  # sensor = "both": the points and boxes beside
        points = {}
        for k, v in numbered:
            obs = v.lidar
            points |= lidar_view_arrays(k, obs.scan, obs.pose, (obs.boxes, obs.ids))
        files[layout.LIDAR_NPZ] = npz_bytes(points)
    return files


def _lidar_files(numbered: list[tuple[int, ViewCapture]], record: dict) -> dict[str, bytes]:
    """A LiDAR-only record's files: the boxes as box-only detections (``cues`` =
    ``BOX_CUES``, ``view{k}_sizes``; ``cadsim.dataset.box_record``), the points, the record."""
    from cadsim.sensing.box_features import BOX_CUES

    detections, points = {}, {}
    for k, v in numbered:
        detections |= v.detections.to_arrays(f"view{k}")
        detections[f"view{k}_sizes"] = np.asarray(v.lidar.boxes.sizes, dtype=np.float64)
        points |= lidar_view_arrays(k, v.lidar.scan, v.lidar.pose)
    record = {**record, "cues": list(BOX_CUES)}
    return {
        layout.DETECTIONS_NPZ: npz_bytes(detections),
        layout.LIDAR_NPZ: npz_bytes(points),
        layout.RECORD_JSON: json_bytes(record),
    }


def _head(rec: PairRecord | SnapshotRecord, version: int) -> dict:
    return {
        "format_version": version,
        "episode": int(rec.episode),
        "slot": int(rec.slot),
        "sim_seed": int(rec.sim_seed),
        "time": float(rec.time),
    }


def encode_record(rec: PairRecord) -> dict[str, bytes]:
    """{file name: bytes} of a frame-pair record; deterministic (same record ⇒ same bytes)."""
    views = (rec.view1, rec.view2)
    gt = ground_truth_pairs(rec.view1.detections, rec.view2.detections)
    ids1 = rec.view1.detections.object_ids
    observers = [_observer_entry(v) for v in views]
    head = _head(rec, FORMAT_VERSION)
    if rec.sequence is not None:
        sequence = dict(rec.sequence)
        odometry, seeds = sequence.pop("odometry"), sequence.pop("odometry_seeds")
        for entry, pose, seed in zip(observers, odometry, seeds, strict=True):
            entry["odometry"] = pose.as_dict()
            entry["odometry_seed"] = int(seed)
        head = _head(rec, SEQUENCE_FORMAT) | {"sequence": jsonable(sequence)}
    record = head | {
        "observers": observers,
        "prior": {"kind": "pose_error", **LocalisationConfig(**rec.localisation).as_record()},
        "objects": [o.as_dict() for o in rec.objects],
        "ground_truth": [{"object_id": ids1[i], "i": int(i), "j": int(j)} for i, j in gt],
        "counts": {
            "n1": len(rec.view1.detections),
            "n2": len(rec.view2.detections),
            "covisible": len(gt),
        },
        "meta": jsonable(rec.meta),
        "difficulty": _difficulty(rec, observers, gt),
    }
    return _files(views, record)


def _difficulty(rec: PairRecord, observers: list[dict], gt: np.ndarray) -> dict:
    """The pair's difficulty factors (:mod:`cadsim.dataset.difficulty`), with the cameras exactly
    as ``record.json`` stores them (a LiDAR-only view's is its LiDAR's), so a reader computes the
    same."""
    d1, d2 = rec.view1.detections, rec.view2.detections
    to_world = tuple(camera_to_world(Camera.from_dict(o["camera"])) for o in observers)
    return difficulty_factors(
        d1.positions, d2.positions, d1.true_classes, d2.true_classes, gt, to_world
    )


def encode_snapshot(rec: SnapshotRecord) -> dict[str, bytes]:
    """{file name: bytes} of an N-view snapshot record (format version 6); deterministic. Ground
    truth is the detections' object ids (shared across views); ``counts.covisible`` holds each
    pair "i-j" (1-based, i < j) of views' covisible count."""
    views = rec.views
    if len(rec.kinds) != len(views) or len(views) > layout.MAX_VIEWS:
        raise ValueError(f"snapshot record: {len(views)} views, {len(rec.kinds)} kinds")
    covisible = {
        f"{i + 1}-{j + 1}": len(ground_truth_pairs(views[i].detections, views[j].detections))
        for i in range(len(views))
        for j in range(i + 1, len(views))
    }
    record = _head(rec, MULTI_VIEW_FORMAT) | {
        "views": len(views),
        "observers": [
            _observer_entry(v) | {"kind": kind} for v, kind in zip(views, rec.kinds, strict=True)
        ],
        "prior": {"kind": "pose_error", **LocalisationConfig(**rec.localisation).as_record()},
        "objects": [o.as_dict() for o in rec.objects],
        "counts": {"detections": [len(v.detections) for v in views], "covisible": covisible},
        "meta": jsonable(rec.meta),
    }
    return _files(views, record)
