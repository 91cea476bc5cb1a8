"""One view's detections as stored in a record, and the ground truth between two views.

Positions are in that view's camera frame (OpenCV: x right, y down, z forward, metres), computed
from the noisy depth; boxes are pixel rectangles (u0, v0, u1, v1); features are the detection
adapter's appearance vectors; ``object_ids`` are ground truth and never part of a matcher's input.
``world`` (imported data only) is each detection's position in a shared world frame as the
observer's own noisy localisation put it — the localisation prior stored with the data; simulated
records leave it None and the reader derives the prior from the camera pose.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse.csgraph import connected_components

_FIELDS = ("positions", "boxes", "features", "object_ids", "true_classes", "pixels")
_REPORTED = "reported_classes"
_HEADINGS = "headings"
_LEGACY_TRUE = "classes"  # formats 2-4 stored only the true class, under this name


@dataclass(frozen=True, eq=False)
class ViewDetections:
    """k detections of one view.

    positions: (k, 3) float64 metres, camera frame. boxes: (k, 4) float64 pixels (u0, v0, u1, v1).
    features: (k, d) float32. object_ids, true_classes: k strings of ground truth, for metrics
    only (never part of a matcher's input). pixels: (k,) int64 visible pixels (0 = unknown).
    world: (k, 3) float64 metres (x, y horizontal, z up) or None — a stored prior.
    reported_classes: k strings, the class the view's detector reported (what a matcher may
    see), or None where the record does not say (formats before 5).
    headings: (k,) float64 radians or None — box-only detections' headings in the view's frame
    (``cadsim.sensing.box_features`` states the convention); camera detections leave it None.
    """

    positions: np.ndarray
    boxes: np.ndarray
    features: np.ndarray
    object_ids: list[str]
    true_classes: list[str]
    pixels: np.ndarray
    world: np.ndarray | None = None
    reported_classes: list[str] | None = None
    headings: np.ndarray | None = None

    def __post_init__(self) -> None:
        k = len(self.object_ids)
        positions = np.asarray(self.positions, dtype=np.float64).reshape(-1, 3)
        boxes = np.asarray(self.boxes, dtype=np.float64).reshape(-1, 4)
        features = np.asarray(self.features, dtype=np.float32)
        features = features.reshape(k, -1) if features.size or k else features.reshape(0, 0)
        pixels = np.asarray(self.pixels, dtype=np.int64).reshape(-1)
        for name, arr in (("positions", positions), ("boxes", boxes), ("features", features),
                          ("pixels", pixels), ("true_classes", self.true_classes),
                          ("reported_classes", [None] * k if self.reported_classes is None else self.reported_classes)):  # fmt: skip
            if len(arr) != k:
                raise ValueError(f"detections.{name}: {len(arr)} rows for {k} object ids")
        if self.world is not None:
            world = np.asarray(self.world, dtype=np.float64).reshape(-1, 3)
            if len(world) != k:
                raise ValueError(f"detections.world: {len(world)} rows for {k} object ids")
            if not np.isfinite(world).all():
                raise ValueError("detections.world: non-finite values")
            object.__setattr__(self, "world", world)
        if self.headings is not None:
            headings = np.asarray(self.headings, dtype=np.float64).reshape(-1)
            if len(headings) != k:
                raise ValueError(f"detections.headings: {len(headings)} rows for {k} object ids")
            if not np.isfinite(headings).all():
                raise ValueError("detections.headings: non-finite values")
            object.__setattr__(self, "headings", headings)
        if len(set(self.object_ids)) != k:
            raise ValueError("detections.object_ids: an object is detected twice in one view")
        object.__setattr__(self, "positions", positions)
        object.__setattr__(self, "boxes", boxes)
        object.__setattr__(self, "features", features)
        object.__setattr__(self, "pixels", pixels)
        object.__setattr__(self, "object_ids", [str(v) for v in self.object_ids])
        object.__setattr__(self, "true_classes", [str(v) for v in self.true_classes])
        if self.reported_classes is not None:
            object.__setattr__(self, "reported_classes", [str(v) for v in self.reported_classes])

    def __len__(self) -> int:
        return len(self.object_ids)

    @classmethod
    def from_detections(cls, det) -> ViewDetections:
        """From any object with the detection adapter's fields (``cadsim.sensing.detection.Detections``);
        a detector that reports no ``reported_classes`` gives matchers no class."""
        fields = {f: getattr(det, f) for f in _FIELDS}
        return cls(
            **fields,
            reported_classes=getattr(det, _REPORTED, None),
            headings=getattr(det, _HEADINGS, None),
        )

    def to_arrays(self, prefix: str) -> dict[str, np.ndarray]:
        """Arrays for an npz, keys ``PREFIX_FIELD``; strings as fixed-width unicode arrays;
        ``PREFIX_world`` only when a prior is stored, ``PREFIX_headings`` only for boxes."""
        world = {} if self.world is None else {f"{prefix}_world": self.world}
        if self.reported_classes is not None:
            world[f"{prefix}_{_REPORTED}"] = np.array(self.reported_classes, dtype=str)
        if self.headings is not None:
            world[f"{prefix}_{_HEADINGS}"] = self.headings
        return world | {
            f"{prefix}_positions": self.positions,
            f"{prefix}_boxes": self.boxes,
            f"{prefix}_features": self.features,
            f"{prefix}_object_ids": np.array(self.object_ids, dtype=str),
            f"{prefix}_true_classes": np.array(self.true_classes, dtype=str),
            f"{prefix}_pixels": self.pixels,
        }

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray], prefix: str, what: str) -> ViewDetections:
        """Inverse of ``to_arrays``; ``what`` names the file in errors. Features stored as
        uint8 with a scalar ``PREFIX_features_scale`` (compact imported data) are returned as
        float32 ``q · scale``."""
        if f"{prefix}_true_classes" not in arrays and f"{prefix}_{_LEGACY_TRUE}" in arrays:
            arrays = dict(arrays) | {f"{prefix}_true_classes": arrays[f"{prefix}_{_LEGACY_TRUE}"]}
        missing = [f"{prefix}_{f}" for f in _FIELDS if f"{prefix}_{f}" not in arrays]
        if missing:
            raise ValueError(f"{what}: missing arrays {missing}")
        features = arrays[f"{prefix}_features"]
        scale = arrays.get(f"{prefix}_features_scale")
        if scale is not None:
            if features.dtype != np.uint8 or np.size(scale) != 1:
                raise ValueError(f"{what}: {prefix}_features_scale needs uint8 features, one scale")
            features = features.astype(np.float32) * np.float32(np.ravel(scale)[0])
        reported = arrays.get(f"{prefix}_{_REPORTED}")
        return cls(
            positions=arrays[f"{prefix}_positions"],
            boxes=arrays[f"{prefix}_boxes"],
            features=features,
            object_ids=arrays[f"{prefix}_object_ids"].tolist(),
            true_classes=arrays[f"{prefix}_true_classes"].tolist(),
            pixels=arrays[f"{prefix}_pixels"],
            world=arrays.get(f"{prefix}_world"),
            reported_classes=(
                None if reported is None else np.asarray(reported).reshape(-1).tolist()
            ),
            headings=arrays.get(f"{prefix}_{_HEADINGS}"),
        )

    def take(self, rows) -> ViewDetections:
        """The detections at `rows` (integer indices, in that order) as a new ``ViewDetections``."""
        rows = np.asarray(rows, dtype=np.int64).reshape(-1)
        if rows.size and (rows.min() < 0 or rows.max() >= len(self)):
            raise ValueError(f"rows: index out of range for {len(self)} detections")
        return ViewDetections(
            positions=self.positions[rows],
            boxes=self.boxes[rows],
            features=self.features[rows] if len(self) else self.features,
            object_ids=[self.object_ids[r] for r in rows],
            true_classes=[self.true_classes[r] for r in rows],
            pixels=self.pixels[rows],
            world=None if self.world is None else self.world[rows],
            reported_classes=(
                None if self.reported_classes is None else [self.reported_classes[r] for r in rows]
            ),
            headings=None if self.headings is None else self.headings[rows],
        )

    def equals(self, other: ViewDetections) -> bool:
        """Exact equality of every field."""
        if (self.world is None) != (other.world is None):
            return False
        if (self.headings is None) != (other.headings is None):
            return False
        return (
            self.object_ids == other.object_ids
            and self.true_classes == other.true_classes
            and self.reported_classes == other.reported_classes
            and (self.world is None or np.array_equal(self.world, other.world))
            and (self.headings is None or np.array_equal(self.headings, other.headings))
            and all(
                np.array_equal(getattr(self, f), getattr(other, f))
                for f in ("positions", "boxes", "features", "pixels")
            )
        )


def ground_truth_pairs(view1: ViewDetections, view2: ViewDetections) -> np.ndarray:
    """(k, 2) int64 index pairs (i, j), i ascending, of detections of the same object."""
    index2 = {oid: j for j, oid in enumerate(view2.object_ids)}
    pairs = [(i, index2[oid]) for i, oid in enumerate(view1.object_ids) if oid in index2]
    return np.array(pairs, dtype=np.int64).reshape(-1, 2)


def is_acceptable_pair(
    view1: ViewDetections, view2: ViewDetections, min_covisible: int = 3, min_exclusive: int = 1
) -> bool:
    """DESIGN §5: at least ``min_covisible`` objects detected in both views, and at least
    ``min_exclusive`` objects in each view that the other view does not detect."""
    covisible = len(ground_truth_pairs(view1, view2))
    return (
        covisible >= min_covisible
        and len(view1) - covisible >= min_exclusive
        and len(view2) - covisible >= min_exclusive
    )


def is_acceptable_set(views: list[ViewDetections], min_covisible: int = 3) -> bool:
    """DESIGN §12's acceptance of an N-view snapshot: link two views when they detect at least
    ``min_covisible`` objects in common; every view must be linked to another and the links
    must join all views into one group (so each view shares objects with the rest and no
    subset of views sees a scene apart)."""
    count = len(views)
    if count < 2:
        return False
    ids = [set(v.object_ids) for v in views]
    linked = np.array(
        [[len(ids[i] & ids[j]) >= min_covisible for j in range(count)] for i in range(count)]
    )
    np.fill_diagonal(linked, False)
    groups, _ = connected_components(linked, directed=False)
    return groups == 1 and bool(linked.any(axis=1).all())
