"""The box-only record: views that are 3-D boxes and nothing else (imported LiDAR labels, a LiDAR
detector), encoded in the dataset format without images.

Each view is a sensor (the agent's LiDAR) with a pose and its boxes. The detections follow every
cadsim detection's convention with the sensor as origin (``cadsim.sensing.box_features``):
``positions`` the box centres in the camera-frame convention (x right, y down, z forward,
metres), ``features`` the 48-d box feature vector of the size, ``headings`` (radians), the
reported class, no pixel box (zeros) and no pixel count (0); beside them ``view{k}_sizes``
(k, 3) the boxes' length, width, height in metres (what the features encode; the exporters
read it, :func:`read_box_sizes`). ``record.json`` says so:
``cues`` = ``BOX_CUES`` (``cadsim.dataset.cues``), and each observer entry holds ``sensor:
"lidar"``, a ``camera`` entry that is the sensor's pose (its position, heading and pitch; no
image is behind it) and ``pose``, the body the sensor is mounted on — so ``camera_extrinsics``
is the LiDAR's mount and the true relative pose, the oracle row, the planar pose fit and the
localisation presets run unchanged. Seeds are 0 (nothing was drawn).

Two views without a sequence: format 5; two views of a sequence frame: format 7 (odometry from
the true poses, an odometry model of zero sigmas); more views: format 6. Imports neither SUMO,
pyrender, matchers nor eval.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cadsim.camera import Camera
from cadsim.dataset import layout
from cadsim.dataset.detections import ViewDetections, ground_truth_pairs
from cadsim.dataset.encoding import json_bytes, npz_bytes
from cadsim.dataset.record_format import (
    FORMAT_VERSION,
    MULTI_VIEW_FORMAT,
    SEQUENCE_FORMAT,
    jsonable,
)
from cadsim.observer_pose import ObserverPose
from cadsim.sensing.box_features import BOX_CUES
from cadsim.sensing.odometry import OdometryPose
from cadsim.world import WorldObject

RECORD_FILES = (layout.DETECTIONS_NPZ, layout.RECORD_JSON)
EXACT_ODOMETRY = {
    "scale_sigma": 0.0,
    "heading_sigma_deg_per_m": 0.0,
    "position_walk": 0.0,
    "heading_walk_deg": 0.0,
}
"""The odometry model of imported sequences: the source's true poses, no error drawn."""


@dataclass(frozen=True, eq=False)
class BoxView:
    """One sensor's boxes. observer_id: the agent's id; kind: "vehicle" or "roadside"; sensor:
    the LiDAR's world pose as a :class:`~cadsim.camera.Camera` (camera-frame convention, no
    image); body: the pose of what carries it (a roadside unit: the sensor itself);
    detections: positions, features, headings as the module docstring says; sizes: (k, 3)
    length, width, height, metres; odometry: the
    body's pose relative to its sequence's frame 0 (sequence frames only)."""

    observer_id: str
    kind: str
    sensor: Camera
    body: ObserverPose
    detections: ViewDetections
    sizes: np.ndarray
    odometry: OdometryPose | None = None


@dataclass(frozen=True, eq=False)
class BoxRecord:
    """One imported frame (two views: a frame pair; more: an N-view snapshot). time: seconds
    (None: unknown); objects: the boxes as world objects (for velocities and ``cadsim show``);
    prior_sigma_m: the stored prior's stated uncertainty (metres) when the views carry
    ``world`` positions, else None (no prior: a preset may draw one); sequence: ``id``
    (record name of frame 0), ``frame``, ``frames``, ``interval_s``, ``start_time`` or None."""

    episode: int
    slot: int
    sim_seed: int
    time: float | None
    views: tuple[BoxView, ...]
    objects: list[WorldObject] = field(default_factory=list)
    meta: dict = field(default_factory=dict)
    prior_sigma_m: float | None = None
    prior_frame: str = ""
    sequence: dict | None = None


def record_version(views: int, sequential: bool) -> int:
    """The format version of a box-only record of ``views`` views."""
    if views > 2:
        if sequential:
            raise ValueError("box records: sequences of more than two views are not a format")
        return MULTI_VIEW_FORMAT
    return SEQUENCE_FORMAT if sequential else FORMAT_VERSION


def _observer(view: BoxView, sequential: bool) -> dict:
    entry = {
        "id": view.observer_id,
        "kind": view.kind,
        "sensor": "lidar",
        "camera": view.sensor.as_dict(),
        "pose": view.body.as_dict(),
        "noise_seed": 0,
        "attribute_seed": 0,
        "localisation_seed": 0,
    }
    if sequential:
        entry |= {"odometry": (view.odometry or OdometryPose(0.0, 0.0, 0.0)).as_dict()}
        entry |= {"odometry_seed": 0}
    return entry


def _prior_views(views: tuple[BoxView, ...]) -> dict:
    """``{"views": [k, ...]}`` (1-based) when only some views carry a stored prior, else {}."""
    having = [k for k, v in enumerate(views, start=1) if v.detections.world is not None]
    return {} if len(having) == len(views) else {"views": having}


def encode_box_record(rec: BoxRecord) -> dict[str, bytes]:
    """{file name: bytes} of a box-only record (deterministic: same record ⇒ same bytes)."""
    views = rec.views
    sequential = rec.sequence is not None
    version = record_version(len(views), sequential)
    record = {
        "format_version": version,
        "episode": int(rec.episode),
        "slot": int(rec.slot),
        "sim_seed": int(rec.sim_seed),
        "time": None if rec.time is None else float(rec.time),
    }
    if sequential:
        record["sequence"] = jsonable(rec.sequence) | {"model": dict(EXACT_ODOMETRY)}
    if len(views) > 2:
        record["views"] = len(views)
    record |= {
        "cues": list(BOX_CUES),
        "observers": [_observer(v, sequential) for v in views],
        "prior": (
            None
            if rec.prior_sigma_m is None
            else {"kind": "stored", "world_sigma_m": float(rec.prior_sigma_m)}
            | {"frame": rec.prior_frame}
            | _prior_views(views)
        ),
        "objects": [o.as_dict() for o in rec.objects],
    }
    if len(views) == 2:
        gt = ground_truth_pairs(views[0].detections, views[1].detections)
        ids1 = views[0].detections.object_ids
        record["ground_truth"] = [{"object_id": ids1[i], "i": int(i), "j": int(j)} for i, j in gt]
        record["counts"] = {
            "n1": len(views[0].detections),
            "n2": len(views[1].detections),
            "covisible": len(gt),
        }
    else:
        record["counts"] = {
            "detections": [len(v.detections) for v in views],
            "covisible": {
                f"{i + 1}-{j + 1}": len(
                    ground_truth_pairs(views[i].detections, views[j].detections)
                )
                for i in range(len(views))
                for j in range(i + 1, len(views))
            },
        }
    record["meta"] = jsonable(rec.meta)
    arrays = {}
    for k, view in enumerate(views, start=1):
        arrays |= view.detections.to_arrays(f"view{k}")
        sizes = np.asarray(view.sizes, dtype=np.float64).reshape(len(view.detections), 3)
        arrays[f"view{k}_sizes"] = sizes
    return {layout.DETECTIONS_NPZ: npz_bytes(arrays), layout.RECORD_JSON: json_bytes(record)}


def box_detections(
    positions: np.ndarray,
    sizes_lwh: np.ndarray,
    headings: np.ndarray,
    object_ids: list[str],
    classes: list[str],
    world: np.ndarray | None = None,
) -> ViewDetections:
    """The detections of k boxes: ``positions`` (k, 3) camera-frame convention, sensor origin,
    metres; ``sizes_lwh`` (k, 3) metres; ``headings`` (k,) radians; the class as both the true
    and the reported one (labels are all a matcher gets); ``world`` a stored prior or None."""
    from cadsim.sensing.box_features import box_feature_vector

    k = len(object_ids)
    return ViewDetections(
        positions=positions,
        boxes=np.zeros((k, 4)),
        features=box_feature_vector(np.asarray(sizes_lwh, dtype=np.float64).reshape(k, 3)),
        object_ids=list(object_ids),
        true_classes=list(classes),
        reported_classes=list(classes),
        pixels=np.zeros(k, dtype=np.int64),
        world=world,
        headings=headings,
    )


def read_box_sizes(record_dir, view: int) -> np.ndarray | None:
    """(k, 3) box sizes (metres) of view ``view`` of a record, None for a record without."""
    from pathlib import Path

    from cadsim.dataset.encoding import load_npz

    what = Path(record_dir) / layout.DETECTIONS_NPZ
    arrays = load_npz(str(what), str(what))
    return arrays.get(f"view{int(view)}_sizes")


__all__ = [
    "read_box_sizes",
    "BoxRecord",
    "BoxView",
    "box_detections",
    "encode_box_record",
    "record_version",
]
