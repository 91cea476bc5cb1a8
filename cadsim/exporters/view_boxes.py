"""What every exporter writes of one view: its boxes in the world and in the view's frame.

A view of a camera record (``cadsim generate``) is its camera and its detections: the box centre
is the detection's position (the noisy depth estimate, as a matcher sees it) taken to the world
through the true camera pose, the size and heading are the detected object's (``record.json``'s
objects), the size the one the view's detector *reported* (its estimate, with the detector's size
noise; read back from the detection's attribute features, ``cadsim.sensing.features.reported_sizes``
— never the object's true size, which would name its class and tie the two views together).
A view of a box-only record is its sensor and its boxes (stored sizes — for LiDAR the fitted,
completed boxes — and headings).
Either way :class:`ViewBoxes` holds world centres and length directions (cadsim's right-handed
world), the view-frame centres and headings (camera-frame convention), sizes (l, w, h, metres),
the class a matcher sees (the reported one where the record has it), speeds (m/s), the
observer's true body pose and the pose its own localisation reported (the record's prior:
simulated pose errors applied, or fitted to a stored prior's positions; None without a prior).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cadsim import portable_math as pm
from cadsim.camera import Camera
from cadsim.dataset.box_record import read_box_sizes
from cadsim.dataset.detections import ViewDetections
from cadsim.importers.sensor_frame import (
    boxes_in_view,
    world_directions,
    yaw_directions,
)
from cadsim.observer_pose import ObserverPose
from cadsim.sensing.box_features import BOX_CUES
from cadsim.sensing.features import reported_sizes


@dataclass(frozen=True, eq=False)
class ViewBoxes:
    """One view of one record, as the exporters write it (module docstring). ``view``: its
    1-based number in the record; ``pixel_boxes``: (k, 4) image boxes or None (box-only)."""

    view: int
    observer_id: str
    kind: str
    camera: Camera
    body: np.ndarray  # 4×4 body → world
    reported_body: np.ndarray | None  # 4×4 as its localisation reported it (None: no prior)
    detections: ViewDetections
    world: np.ndarray
    directions: np.ndarray
    headings: np.ndarray
    sizes: np.ndarray
    classes: list[str]
    speeds: np.ndarray
    pixel_boxes: np.ndarray | None
    ego_speed: float = 0.0  # the observer's own speed, m/s (its carrier object's)


def _speed(obj: dict | None) -> float:
    """Horizontal speed (m/s) of a ``record.json`` object entry (0 for none)."""
    if not obj:
        return 0.0
    vx, vy = (float(v) for v in obj.get("velocity", (0.0, 0.0, 0.0))[:2])
    return float(np.hypot(vx, vy))


def _reported(body: np.ndarray, error) -> np.ndarray:
    """``body`` with a drawn ``PoseError`` applied about its origin."""
    c, s = np.cos(error.dyaw), np.sin(error.dyaw)
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    out = body.copy()
    out[:3, :3] = pm.matmul(turn, body[:3, :3])
    out[:3, 3] = body[:3, 3] + [error.dx, error.dy, 0.0]
    return out


def _fitted(body: np.ndarray, true_world: np.ndarray, stored: np.ndarray) -> np.ndarray:
    """The reported body pose that moves ``true_world`` onto a stored prior's positions (least
    squares, rigid); ``body`` when fewer than three boxes leave it undetermined."""
    if len(true_world) < 3:
        return body
    a, b = true_world - true_world.mean(0), stored - stored.mean(0)
    u, _, vt = np.linalg.svd(pm.matmul(b.T, a))
    d = np.sign(np.linalg.det(pm.matmul(u, vt)))
    r = pm.matmul(pm.matmul(u, np.diag([1.0, 1.0, d])), vt)
    shift = np.eye(4)
    shift[:3, :3] = r
    shift[:3, 3] = stored.mean(0) - pm.matmul(r, true_world.mean(0))
    return pm.matmul(shift, body)


def record_views(pair, views: list[ViewDetections], errors: list) -> list[ViewBoxes]:
    """Every view of ``pair``'s record (``views``: their detections in view order; ``errors``:
    per view its drawn pose error or None)."""
    record = pair.record
    boxes_only = tuple(record.get("cues") or ()) == BOX_CUES
    objects = {o["id"]: o for o in record["objects"]}
    out = []
    for v, (observer, det, error) in enumerate(zip(record["observers"], views, errors, strict=True), start=1):  # fmt: skip
        camera = Camera.from_dict(observer["camera"])
        body = ObserverPose.from_dict(observer["pose"]).body_to_world()
        world = camera.camera_to_world(det.positions) if len(det) else np.zeros((0, 3))
        found = [objects.get(i) for i in det.object_ids]
        velocity = np.array([o["velocity"] if o else (0.0, 0.0, 0.0) for o in found], dtype=float)
        speeds = np.sqrt((velocity.reshape(-1, 3)[:, :2] ** 2).sum(axis=1))
        if boxes_only:
            sizes = read_box_sizes(pair.path, v)
            headings = det.headings if det.headings is not None else np.zeros(len(det))
            directions = world_directions(camera, headings)
        else:
            sizes = reported_sizes(det.features) if len(det) else np.zeros((0, 3))
            if sizes is None:  # a foreign feature layout: the objects' sizes are all there is
                sizes = np.array([o["size"] if o else (0.5, 0.5, 0.5) for o in found], dtype=float)
            directions = yaw_directions([o["yaw"] if o else 0.0 for o in found])
            _, headings = boxes_in_view(camera, world, directions)
        stored = det.world
        if stored is not None:
            reported = _fitted(body, world, stored)
        else:
            reported = None if error is None else _reported(body, error)
        out.append(
            ViewBoxes(
                v,
                observer["id"],
                observer.get("kind", "vehicle"),
                camera,
                body,
                reported,
                det,
                world,
                directions,
                headings,
                np.asarray(sizes, dtype=float).reshape(-1, 3),
                list(det.reported_classes or det.true_classes),
                speeds,
                None if boxes_only else det.boxes,
                _speed(objects.get(observer["id"])),
            )  # fmt: skip
        )
    return out


def snapshot_views(dataset, k: int) -> list[ViewBoxes]:
    """Every view of record ``k`` of ``dataset`` with the record's own prior."""
    if dataset.n_views == 2:
        pair = dataset[k]
        errors = pair.pose_errors() or (None, None)
        return record_views(pair, [pair.view1, pair.view2], list(errors))
    snap = dataset.snapshot(k)
    errors = [None] * snap.n_views
    for j in range(2, snap.n_views + 1):
        drawn = snap.pair(1, j).pose_errors()
        if drawn is not None:
            errors[0], errors[j - 1] = drawn
    views = [snap.view(i) for i in range(1, snap.n_views + 1)]
    return record_views(snap.pair(1, 2), views, errors)


__all__ = ["ViewBoxes", "record_views", "snapshot_views"]
