"""The LiDAR box detector: points in, 3-D boxes with a class out — never the ground truth.

Pipeline (each step its own module): road plane fitted and ground points dropped
(``ground_removal``), the rest clustered on a bird's-eye grid (``clustering``), each cluster's
minimum-area rectangle fitted (``box_fit``), a class given by its size and the box completed to
that class's size away from the sensor (``size_classes``), its size scattered as a box
regressor's is, more for fewer points (``size_noise``); clusters no class fits (walls,
buildings, curbs) are dropped. So are clusters *cut by the field of view* — a point within
``FOV_MARGIN_DEG`` of the top channel, so their true height is unknown — that would be a pole,
a truck, a bus, or a van shorter than ``CUT_MIN_LENGTH_M`` on the ground: such clusters are
mostly pieces of building walls seen between occluders or at grazing angles, and the real poles,
buses and trucks near the sensor (whose tops the field of view cuts) are lost with them — a
detector that sizes objects by their points must see their tops. Input: points (n, 3) in the LiDAR frame (x forward, y left, z up,
metres) — a :class:`~cadsim.sensing.lidar.raycast.LidarScan`'s ``points``, never its object
tags. Output: :class:`LidarBoxes`, in the LiDAR frame; :meth:`LidarBoxes.to_view_detections`
turns them into what matchers see (camera-frame convention, box feature vector, headings,
reported classes), once ground-truth ids are attached (``cadsim.sensing.lidar.box_truth``).

Misses, splits, merges and the centre bias at range and under occlusion are what these rules
give; docs/lidar.md reports them measured, they are not tuned to a target.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cadsim.dataset.detections import ViewDetections
from cadsim.sensing.box_features import (
    box_feature_vector,
    heading_from_lidar_yaw,
    lidar_to_camera_convention,
)
from cadsim.sensing.lidar.box_fit import fit_box
from cadsim.sensing.lidar.clustering import CELL_M, MIN_POINTS, cluster_points
from cadsim.sensing.lidar.ground_removal import remove_ground
from cadsim.sensing.lidar.size_classes import class_from_size, complete_box
from cadsim.sensing.lidar.size_noise import noisy_sizes

MIN_HEIGHT_ABOVE_ROAD_M = 0.2
FOV_MARGIN_DEG = 0.25
CUT_MIN_LENGTH_M = 7.0


@dataclass(frozen=True, eq=False)
class LidarBoxes:
    """k boxes in the LiDAR frame.

    centres: (k, 3) metres. sizes: (k, 3) length, width, height, metres. yaws: (k,) radians
    counter-clockwise about z from +x, folded into (−π/2, π/2]. classes: k reported classes.
    point_counts: (k,) points in each box's cluster. point_box: (n,) int64 box of each input
    point (−1: ground, noise or a dropped cluster), input order.
    """

    centres: np.ndarray
    sizes: np.ndarray
    yaws: np.ndarray
    classes: list[str]
    point_counts: np.ndarray
    point_box: np.ndarray

    def __len__(self) -> int:
        return len(self.classes)

    def to_view_detections(self, object_ids: list[str], true_classes: list[str]) -> ViewDetections:
        """What matchers see: positions in the camera-frame convention (sensor at the origin),
        the box feature vector of the sizes, headings, the reported classes; ``object_ids`` and
        ``true_classes`` are the ground truth (``box_truth.box_ground_truth``). Pixel boxes are
        zero (a LiDAR box has none); ``pixels`` holds each box's point count."""
        k = len(self)
        return ViewDetections(
            positions=lidar_to_camera_convention(self.centres),
            boxes=np.zeros((k, 4)),
            features=box_feature_vector(self.sizes) if k else np.zeros((0, 48), np.float32),
            object_ids=list(object_ids),
            true_classes=list(true_classes),
            pixels=self.point_counts,
            reported_classes=list(self.classes),
            headings=heading_from_lidar_yaw(self.yaws),
        )


def detect_boxes(
    points: np.ndarray,
    sensor_height_m: float,
    top_elevation_deg: float | None = None,
    cell_m: float = CELL_M,
    min_points: int = MIN_POINTS,
    size_rng: np.random.Generator | None = None,
) -> LidarBoxes:
    """Boxes in ``points`` (n, 3) LiDAR frame, metres; ``sensor_height_m``: the mount's nominal
    height above the road; ``top_elevation_deg``: the sensor's highest channel (None: no
    field-of-view cut is applied), both from the sensor's specification (module docstring).
    ``size_rng``: the stream of the box regressor's size scatter
    (:mod:`cadsim.sensing.lidar.size_noise`); None: the completed boxes' sizes as fitted.

    >>> import numpy as np
    >>> detect_boxes(np.zeros((0, 3)), 1.75).classes
    []
    """
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"points: expected (n, 3) metres, got shape {p.shape}")
    if not np.isfinite(p).all():
        raise ValueError("points: non-finite coordinates")
    point_box = np.full(len(p), -1, dtype=np.int64)
    centres, sizes, yaws, classes, counts = [], [], [], [], []
    if len(p):
        above, plane = remove_ground(p, sensor_height_m, MIN_HEIGHT_ABOVE_ROAD_M)
        rows = np.flatnonzero(above)
        cut = np.zeros(len(p), dtype=bool)
        if top_elevation_deg is not None:
            slope = math.tan(math.radians(float(top_elevation_deg) - FOV_MARGIN_DEG))
            cut = p[:, 2] >= slope * np.sqrt(p[:, 0] * p[:, 0] + p[:, 1] * p[:, 1])
        labels = cluster_points(p[rows], cell_m, min_points)
        order = np.argsort(labels, kind="stable")
        labels_sorted = labels[order]
        starts = np.searchsorted(labels_sorted, np.arange(int(labels.max(initial=-1)) + 2))
        for k in range(len(starts) - 1):  # per cluster, not per point
            members = rows[order[starts[k] : starts[k + 1]]]
            fitted = fit_box(p[members], plane)
            cls = class_from_size(fitted.size)
            if cls is None:
                continue
            if cut[members].any() and (cls in ("pole", "truck", "bus") or (cls == "van" and fitted.size[0] < CUT_MIN_LENGTH_M)):  # fmt: skip
                continue
            box = complete_box(fitted, cls)
            point_box[members] = len(classes)
            centres.append(box.centre)
            sizes.append(box.size)
            yaws.append(box.yaw)
            classes.append(cls)
            counts.append(len(members))
    sizes = np.asarray(sizes, dtype=np.float64).reshape(-1, 3)
    if size_rng is not None and len(sizes):
        sizes = noisy_sizes(sizes, np.asarray(counts), size_rng)
    return LidarBoxes(
        centres=np.asarray(centres, dtype=np.float64).reshape(-1, 3),
        sizes=sizes,
        yaws=np.asarray(yaws, dtype=np.float64).reshape(-1),
        classes=classes,
        point_counts=np.asarray(counts, dtype=np.int64).reshape(-1),
        point_box=point_box,
    )
