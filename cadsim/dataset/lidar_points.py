"""A record's LiDAR points: ``lidar.npz``, compact and bounded, and the view it decodes to.

Per view k (1-based), the sweep's beam pattern and pose and its returns:

- ``view{k}_elevations_deg`` (c,) float64 and ``view{k}_azimuth_steps`` (1,) int64: the pattern
  (``cadsim.sensing.lidar.beam_pattern``: ray ``channel · azimuth_steps + azimuth``);
- ``view{k}_pose`` (4, 4) float64: LiDAR frame → world;
- ``view{k}_hits`` (⌈c · azimuth_steps / 8⌉,) uint8: which rays returned, one bit per ray
  (``np.packbits``, ray order);
- ``view{k}_range`` (n,) uint16: each return's range in 4 mm steps (``RANGE_STEP_M``);
- ``view{k}_object`` (n,) int16: the index in ``record.json``'s ``objects`` of the object each
  return hit, −1 for the ground — ground truth, for metrics and figures only;
- with ``sensor = "both"`` also the LiDAR detector's boxes, which matchers do not get there:
  ``view{k}_box_centres`` (b, 3) and ``view{k}_box_sizes`` (b, 3) metres in the LiDAR frame,
  ``view{k}_box_yaws`` (b,) radians, ``view{k}_box_classes`` and ``view{k}_box_ids`` (b,) str.

Points are ``range · direction`` in the LiDAR frame (x forward, y left, z up, metres). Bound: at
most :data:`MAX_POINTS_PER_VIEW` returns per view — a sweep with more keeps every ⌈n / cap⌉-th
return (ray order), which only a roadside 128-channel unit over a dense scene reaches; ≈ 4 bytes
per return before compression.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cadsim.limits import MAX_POSITION_M, MAX_SIZE_M
from cadsim.sensing.lidar.beam_pattern import (
    MAX_AZIMUTH_STEPS,
    MAX_CHANNELS,
    RANGE_STEP_M,
    BeamPattern,
)

MAX_POINTS_PER_VIEW = 1 << 18
_POINT_KEYS = ("elevations_deg", "azimuth_steps", "pose", "hits", "range", "object")
_BOX_KEYS = ("box_centres", "box_sizes", "box_yaws", "box_classes", "box_ids")


@dataclass(frozen=True, eq=False)
class LidarView:
    """One view's stored sweep. points: (n, 3) float64 LiDAR frame, metres. ray_index: (n,)
    int64. object_index: (n,) int64 (−1: ground; ground truth only). pose: (4, 4) LiDAR → world.
    boxes: the detector's boxes when the record keeps them beside camera detections, else None
    (a dict of the ``box_*`` arrays without the prefix)."""

    pattern: BeamPattern
    pose: np.ndarray
    ray_index: np.ndarray
    range_steps: np.ndarray
    object_index: np.ndarray
    boxes: dict | None = None

    @property
    def points(self) -> np.ndarray:
        r = self.range_steps.astype(np.float64) * RANGE_STEP_M
        return r[:, None] * self.pattern.directions()[self.ray_index]


def bounded(scan):
    """A :class:`~cadsim.sensing.lidar.raycast.LidarScan` with at most
    :data:`MAX_POINTS_PER_VIEW` returns (every ⌈n / cap⌉-th)."""
    n = len(scan)
    if n <= MAX_POINTS_PER_VIEW:
        return scan
    keep = np.arange(0, n, math.ceil(n / MAX_POINTS_PER_VIEW))
    return type(scan)(
        scan.pattern, scan.ray_index[keep], scan.range_steps[keep], scan.object_index[keep],
        scan.object_ids,
    )  # fmt: skip


def view_arrays(k: int, scan, pose: np.ndarray, boxes=None) -> dict[str, np.ndarray]:
    """The ``view{k}_…`` arrays of a bounded ``scan`` taken at ``pose``; ``boxes`` a
    :class:`~cadsim.sensing.lidar.box_detector.LidarBoxes` with ``ids`` to keep them too."""
    scan = bounded(scan)
    hits = np.zeros(scan.pattern.ray_count, dtype=bool)
    hits[scan.ray_index] = True
    out = {
        f"view{k}_elevations_deg": np.asarray(scan.pattern.elevations_deg, dtype=np.float64),
        f"view{k}_azimuth_steps": np.array([scan.pattern.azimuth_steps], dtype=np.int64),
        f"view{k}_pose": np.asarray(pose, dtype=np.float64).reshape(4, 4),
        f"view{k}_hits": np.packbits(hits),
        f"view{k}_range": scan.range_steps.astype(np.uint16),
        f"view{k}_object": scan.object_index.astype(np.int16),
    }
    if boxes is not None:
        found, ids = boxes
        out |= {
            f"view{k}_box_centres": found.centres,
            f"view{k}_box_sizes": found.sizes,
            f"view{k}_box_yaws": found.yaws,
            f"view{k}_box_classes": np.array(found.classes, dtype=str).reshape(-1),
            f"view{k}_box_ids": np.array(ids, dtype=str).reshape(-1),
        }
    return out


def check_lidar_arrays(arrays: dict[str, np.ndarray], views: int, objects: int, what: str) -> None:
    """``ValueError`` naming ``what`` and the array unless ``arrays`` are the ``lidar.npz`` of a
    ``views``-view record whose ``record.json`` lists ``objects`` objects (module docstring)."""
    allowed = {f"view{k}_{name}" for k in range(1, views + 1) for name in _POINT_KEYS + _BOX_KEYS}
    stray = sorted(set(arrays) - allowed)
    if stray:
        raise ValueError(f"{what}: {stray[0]}: not an array of a {views}-view lidar.npz")
    for k in range(1, views + 1):
        p = f"view{k}_"
        missing = [p + n for n in _POINT_KEYS if p + n not in arrays]
        if missing:
            raise ValueError(f"{what}: missing arrays {missing}")
        el, steps = arrays[p + "elevations_deg"], arrays[p + "azimuth_steps"]
        if el.dtype != np.float64 or el.ndim != 1 or not 1 <= len(el) <= MAX_CHANNELS:
            raise ValueError(f"{what}: {p}elevations_deg: expected 1..{MAX_CHANNELS} float64 angles")  # fmt: skip
        if not (np.all(np.abs(el) <= 90.0) and np.all(np.diff(el) >= 0)):  # NaN fails both
            raise ValueError(f"{what}: {p}elevations_deg: expected ascending angles in [-90, 90] degrees")  # fmt: skip
        if steps.shape != (1,) or steps.dtype != np.int64 or not 1 <= int(steps[0]) <= MAX_AZIMUTH_STEPS:  # fmt: skip
            raise ValueError(f"{what}: {p}azimuth_steps: expected one int64 in 1..{MAX_AZIMUTH_STEPS}")  # fmt: skip
        if not is_rigid(arrays[p + "pose"]):
            raise ValueError(
                f"{what}: {p}pose: expected a rigid (4, 4) float64 transform (rotation, "
                f"translation within ±{MAX_POSITION_M:g} m, last row 0 0 0 1)"
            )
        rays = len(el) * int(steps[0])
        hits = arrays[p + "hits"]
        if hits.dtype != np.uint8 or hits.shape != ((rays + 7) // 8,):
            raise ValueError(f"{what}: {p}hits: expected ({(rays + 7) // 8},) uint8 bits")
        n = int(np.unpackbits(hits, count=rays).sum())
        if n > MAX_POINTS_PER_VIEW:
            raise ValueError(f"{what}: {p}hits: {n} returns, more than {MAX_POINTS_PER_VIEW}")
        for name, dtype in (("range", np.uint16), ("object", np.int16)):
            arr = arrays[p + name]
            if arr.dtype != dtype or arr.shape != (n,):
                raise ValueError(f"{what}: {p}{name}: expected ({n},) {np.dtype(dtype)}")
        obj = arrays[p + "object"]
        if n and (obj.min() < -1 or obj.max() >= objects):
            raise ValueError(f"{what}: {p}object: index outside -1..{objects - 1}")
        present = [p + b in arrays for b in _BOX_KEYS]
        if any(present) and not all(present):
            raise ValueError(f"{what}: {p}box_*: expected all of {list(_BOX_KEYS)} or none")
        if all(present):
            _check_boxes({b: arrays[p + b] for b in _BOX_KEYS}, f"{what}: {p}")


def is_rigid(pose: np.ndarray) -> bool:
    """Whether ``pose`` is a (4, 4) float64 rigid transform: orthonormal rotation of
    determinant +1 (±1e-6), translation within :data:`MAX_POSITION_M`, last row 0 0 0 1."""
    if pose.shape != (4, 4) or pose.dtype != np.float64 or not np.isfinite(pose).all():
        return False
    r = pose[:3, :3]
    return bool(
        np.allclose(r @ r.T, np.eye(3), atol=1e-6)
        and np.linalg.det(r) > 0
        and np.array_equal(pose[3], [0.0, 0.0, 0.0, 1.0])
        and np.all(np.abs(pose[:3, 3]) <= MAX_POSITION_M)
    )


def _check_boxes(boxes: dict[str, np.ndarray], where: str) -> None:
    """The detector's boxes of one view: (b, 3) centres and sizes (metres, sizes > 0), (b,)
    yaws (radians), classes and ids (strings), all finite and of one b."""
    b = len(boxes["box_ids"]) if boxes["box_ids"].ndim == 1 else -1
    shapes = {"box_centres": (b, 3), "box_sizes": (b, 3), "box_yaws": (b,)}
    for name, shape in shapes.items():
        arr = boxes[name]
        if arr.dtype != np.float64 or arr.shape != shape or not np.isfinite(arr).all():
            raise ValueError(f"{where}{name}: expected {shape} finite float64 (b = len(box_ids))")
    for name in ("box_classes", "box_ids"):
        if boxes[name].dtype.kind != "U" or boxes[name].shape != (b,):
            raise ValueError(f"{where}{name}: expected ({b},) strings")
    if not (np.all(boxes["box_sizes"] > 0) and np.all(boxes["box_sizes"] <= MAX_SIZE_M)):
        raise ValueError(f"{where}box_sizes: expected sizes in (0, {MAX_SIZE_M:g}] metres")
    if not np.all(np.abs(boxes["box_centres"]) <= MAX_POSITION_M):
        raise ValueError(f"{where}box_centres: expected within ±{MAX_POSITION_M:g} m")


def read_lidar_view(arrays: dict[str, np.ndarray], k: int) -> LidarView:
    """View ``k`` of a checked ``lidar.npz`` (:func:`check_lidar_arrays`)."""
    p = f"view{k}_"
    steps = int(arrays[p + "azimuth_steps"][0])
    el = tuple(float(v) for v in arrays[p + "elevations_deg"])
    pattern = BeamPattern("stored", el, steps, 0.0, 262.0, 0.0, 0.0)
    rays = np.flatnonzero(np.unpackbits(arrays[p + "hits"], count=len(el) * steps))
    boxes = None
    if p + "box_ids" in arrays:
        boxes = {b[4:]: arrays[p + b] for b in _BOX_KEYS}
    return LidarView(
        pattern, arrays[p + "pose"], rays.astype(np.int64), arrays[p + "range"],
        arrays[p + "object"].astype(np.int64), boxes,
    )  # fmt: skip
