"""Detection adapter (DESIGN §6): rendered view + noisy depth -> detections a matcher can use.

Oracle instance masks with realistic filtering. For each ``target`` object in the instance map:

1. visible pixels ≥ ``min_pixels``;
2. median *clean* depth of its mask ≤ ``max_depth_m`` (filters use clean depth so that the set of
   detections does not change with the noise rate; only positions do);
3. truncation: if its mask's box comes within ``border_margin_px`` of the image border, the part
   of its projected 3-D bounding box inside the image must be ≥ 1 - ``max_truncation``;
4. occlusion: visible pixels / in-image area of the projected 3-D bounding box (an upper bound of
   the unoccluded silhouette, so this ratio is conservative) must be ≥ ``min_visible_fraction``.

Position: the ray through the mask's centroid pixel at the median *noisy* depth of the mask, in the
camera frame (OpenCV, metres). That point lies on the visible surface, in front of the object's
centre; with ``surface_to_center`` it is pushed along the ray by ``centre_offset_along`` (the mean
depth of a box's visible surface in front of its centre) of the box the detector *estimated* —
its reported size and heading, never the object's true ones. Features:
``cadsim.sensing.features``, whose attribute block (class, size) is what the view's detector
reports: with ``attribute_rng`` given, class, size and heading are measured from the view
(``cadsim.sensing.attribute_noise``: the mask's silhouette and depth, completed from the reported
class by how much of the object is seen, scatter and class confusion growing as the visible
pixels fall); without it, the simulator's truth. The ground-truth object id and class are kept
beside the features, never in them.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from cadsim import portable_math as pm
from cadsim.camera import Camera
from cadsim.config_tables import check_number, config_from_table
from cadsim.render.view import RenderedView
from cadsim.sensing.attribute_noise import FULL_FILL, Observation, measured_attributes
from cadsim.sensing.box_projection import projected_box_areas
from cadsim.sensing.detector_errors import clutter_boxes, error_stream, jittered, miss_probability
from cadsim.sensing.features import FEATURE_DIM, object_features
from cadsim.world import WorldObject


@dataclass(frozen=True)
class DetectionConfig:
    """The ``[detection]`` table of a scenario file (see the module docstring for each filter).

    class_confusion: probability that a view's detector reports another class of the object's
    confusion group, for an object of 32² visible pixels (more for fewer pixels; 0.0075 makes
    two views disagree on ≈ 1.5 % of such covisible objects, the rate of the paper group's CAD
    data). size_noise: relative (log-normal) error of each reported size dimension at 32² pixels
    and above, growing below (:mod:`cadsim.sensing.attribute_noise`). miss_near, miss_far,
    miss_occluded, false_positives,
    centre_jitter: the detector errors of :mod:`cadsim.sensing.detector_errors` (all 0: off)."""

    min_pixels: int = 40
    border_margin_px: int = 2
    max_truncation: float = 0.5
    min_visible_fraction: float = 0.15
    max_depth_m: float = 80.0
    surface_to_center: bool = True
    class_confusion: float = 0.0075
    size_noise: float = 0.1
    miss_near: float = 0.0
    miss_far: float = 0.0
    miss_occluded: float = 0.0
    false_positives: float = 0.0
    centre_jitter: float = 0.0

    def __post_init__(self) -> None:
        check_number("[detection]", "min_pixels", self.min_pixels, minimum=1, integer=True)
        check_number(
            "[detection]", "border_margin_px", self.border_margin_px, minimum=0, integer=True
        )
        check_number("[detection]", "max_truncation", self.max_truncation, minimum=0.0, maximum=1.0)
        check_number(
            "[detection]",
            "min_visible_fraction",
            self.min_visible_fraction,
            minimum=0.0,
            maximum=1.0,
        )
        check_number("[detection]", "max_depth_m", self.max_depth_m, minimum=0.0)
        check_number(
            "[detection]", "class_confusion", self.class_confusion, minimum=0.0, maximum=1.0
        )
        check_number("[detection]", "size_noise", self.size_noise, minimum=0.0, maximum=2.0)
        for key in ("miss_near", "miss_far", "miss_occluded"):
            check_number("[detection]", key, getattr(self, key), minimum=0.0, maximum=1.0)
        check_number(
            "[detection]", "false_positives", self.false_positives, minimum=0.0, maximum=50.0
        )
        check_number("[detection]", "centre_jitter", self.centre_jitter, minimum=0.0, maximum=1.0)
        if not isinstance(self.surface_to_center, bool):
            raise TypeError(
                f"[detection] surface_to_center must be true or false, got {self.surface_to_center!r}"
            )

    @property
    def has_errors(self) -> bool:
        """Whether any detector error (misses, false positives, jitter) is switched on."""
        return any(
            getattr(self, k) > 0
            for k in ("miss_near", "miss_far", "miss_occluded", "false_positives", "centre_jitter")
        )

    @classmethod
    def from_table(cls, table: Mapping, where: str = "[detection]") -> DetectionConfig:
        """Build from a scenario-file table; unknown keys/bad values raise naming ``where``."""
        return config_from_table(cls, table, where, "[detection]")


@dataclass
class Detections:
    """k detections of one view. positions: (k, 3) camera frame (OpenCV: x right, y down, z
    forward), metres, from the noisy depth. boxes: (k, 4) pixel box x0, y0, x1, y1 (pixel edges).
    features: (k, FEATURE_DIM) float32, non-negative. object_ids, true_classes: ground truth, k
    each (for metrics only: never part of the features, never given to a matcher).
    reported_classes: the class the view's detector reported for each detection (after its class
    confusion), what matchers may see. pixels: (k,) visible pixel counts."""

    positions: np.ndarray
    boxes: np.ndarray
    features: np.ndarray
    object_ids: list[str] = field(default_factory=list)
    true_classes: list[str] = field(default_factory=list)
    reported_classes: list[str] = field(default_factory=list)
    pixels: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))

    def __len__(self) -> int:
        return len(self.object_ids)

    @classmethod
    def empty(cls) -> Detections:
        return cls(
            positions=np.zeros((0, 3)),
            boxes=np.zeros((0, 4)),
            features=np.zeros((0, FEATURE_DIM), dtype=np.float32),
        )


def centre_offset_along(size: Sequence[float], yaw: float, ray_world: np.ndarray) -> float:
    """How far (metres) the centre of an upright box of ``size`` (length, width, height, metres)
    and heading ``yaw`` (world radians) lies behind its visible surface along a unit viewing
    direction ``ray_world``: the area-weighted mean over the visible faces, which for a box is
    volume / (2 · area projected along the ray), i.e. L·W·H / (2 (W·H|r_x| + L·H|r_y| + L·W|r_z|))
    with r in the box's axes (L/2 seen end-on, W/2 seen side-on). The detector passes its own
    size and heading estimates, never the object's true ones."""
    c, s = np.cos(yaw), np.sin(yaw)
    r0, r1, r2 = (float(v) for v in ray_world)
    r = np.abs([c * r0 + s * r1, -s * r0 + c * r1, r2])  # |components| in the box's axes
    L, W, Hh = (max(float(v), 1e-6) for v in size)
    projected = W * Hh * r[0] + L * Hh * r[1] + L * W * r[2]
    return 0.5 * L * W * Hh / projected


@dataclass
class DetectionPlan:
    """Everything a view's detector decides without looking at the noisy depth: which objects are
    detected, their pixels, boxes and features (:func:`plan_detections`). :meth:`locate` adds the
    positions from a noisy depth, so one plan serves every noise rate and seed of a view.

    pixels: flat indices (row · W + column) of every detection's mask, concatenated in detection
    order; ``starts[i]:starts[i + 1]`` are detection i's. centres: (k, 2) mask centroids (u, v),
    pixels. reported_classes: the class the detector reported for each detected object (a
    clutter detection: the class it was drawn as). The other fields are those of
    :class:`Detections`, and the detected objects."""

    pixels: np.ndarray
    starts: np.ndarray
    centres: np.ndarray
    boxes: np.ndarray
    features: np.ndarray
    objects: list[WorldObject]
    camera: Camera
    surface_to_center: bool
    shape: tuple[int, int]
    reported_classes: list[str] = field(default_factory=list)
    estimates: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))

    def __len__(self) -> int:
        return len(self.objects)

    def locate(self, noisy: np.ndarray) -> Detections:
        """The detections with positions from the noisy depth: ``noisy`` is the (H, W) noisy depth
        image (metres), or its values at :attr:`pixels` (same order), as from
        :func:`cadsim.sensing.depth_noise.noisy_depth_values`."""
        values = np.asarray(noisy)
        if values.shape == self.shape:
            values = values.ravel()[self.pixels]
        if values.shape != self.pixels.shape:
            raise ValueError(
                f"noisy depth must be the view's (H, W) = {self.shape} image or its "
                f"{len(self.pixels)} values at the plan's pixels, got shape {values.shape}"
            )
        if not self.objects:
            return Detections.empty()
        R = self.camera.rotation_cam_to_world()
        positions = []
        for i in range(len(self.objects)):
            z = float(np.median(values[self.starts[i] : self.starts[i + 1]]))
            p = self.camera.back_project(self.centres[i : i + 1], np.array([z]))[0]
            if self.surface_to_center:
                ray = p / np.sqrt(np.sum(p * p))  # not BLAS (see features._l2)
                size, yaw = self.estimates[i, :3], float(self.estimates[i, 3])
                p = p + centre_offset_along(size, yaw, pm.matmul(R, ray)) * ray
            positions.append(p)
        return Detections(
            positions=np.array(positions, dtype=float),
            boxes=self.boxes.copy(),
            features=self.features.copy(),
            object_ids=[o.id for o in self.objects],
            true_classes=[o.cls for o in self.objects],
            reported_classes=list(self.reported_classes),
            pixels=np.diff(self.starts),
        )


def plan_detections(
    instance: np.ndarray,
    clean_depth: np.ndarray,
    objects: Sequence[WorldObject],
    camera: Camera,
    config: DetectionConfig,
    color: Callable[[], np.ndarray],
    attribute_rng: np.random.Generator | None = None,
    known_features: Mapping[str, np.ndarray] | None = None,
) -> DetectionPlan:
    """Which ``target`` objects of a view are detected, and what they look like (see the module
    docstring): everything but their positions, which :meth:`DetectionPlan.locate` adds.

    instance, clean_depth: the view's (H, W) instance map and clean depth (metres). color: returns
    the view's (H, W, 3) uint8 colour image; called only if some detected object is missing from
    ``known_features`` (object id -> its feature row from an earlier detection of this view).
    attribute_rng: the view's attribute stream (class confusion, size noise); None: features carry
    the true class and size. Which objects are detected and what they look like depend only on
    colour, instance map, clean depth and the attribute stream, never on the noisy depth."""
    instance = np.asarray(instance, dtype=np.int32)  # the dtypes of a RenderedView
    clean_depth = np.asarray(clean_depth, dtype=np.float32)
    h, w = instance.shape
    if clean_depth.shape != (h, w):
        raise ValueError(
            f"clean depth must have the instance map's shape {(h, w)}, got {clean_depth.shape}"
        )
    if (camera.width, camera.height) != (w, h):
        raise ValueError(f"camera is {camera.width}x{camera.height} but the view is {w}x{h}")
    n = len(objects)
    inst = instance.ravel()
    if inst.size and int(inst.max()) >= n:
        raise ValueError(
            f"view.instance refers to object index {int(inst.max())} but only {n} objects were given"
        )
    counts = np.bincount(inst + 1, minlength=n + 1)  # [0] = background
    candidates = [i for i in range(n) if objects[i].target and counts[i + 1] >= config.min_pixels]
    # Pixels of every object, grouped: a stable sort by label, split at the cumulative counts.
    order = np.argsort(inst, kind="stable")
    starts = np.concatenate([[0], np.cumsum(counts)])
    boxes_px = ndimage.find_objects(instance + 1, max_label=n)
    clean = clean_depth.ravel()
    m = config.border_margin_px
    R = camera.rotation_cam_to_world()
    kept_index, masks, centres, boxes, depths, visible, complete, azimuths = ([] for _ in range(8))
    for i in candidates:
        obj = objects[i]
        pix = order[starts[i + 1] : starts[i + 2]]
        depth = float(np.median(clean[pix]))
        if depth > config.max_depth_m:
            continue
        rows, cols = boxes_px[i]
        x0, y0, x1, y1 = cols.start, rows.start, cols.stop, rows.stop
        full_area, in_image = projected_box_areas(obj, camera)
        touches_border = x0 <= m or y0 <= m or x1 >= w - m or y1 >= h - m
        if touches_border and full_area > 0 and in_image / full_area < 1.0 - config.max_truncation:
            continue
        if in_image > 0 and len(pix) / in_image < config.min_visible_fraction:
            continue
        v, u = np.divmod(pix, w)
        centre = (u.mean() + 0.5, v.mean() + 0.5)
        sight = pm.matmul(R, camera.back_project(np.array([centre]), np.array([depth]))[0])
        kept_index.append(i)
        masks.append(pix)
        centres.append(centre)
        boxes.append((x0, y0, x1, y1))
        depths.append(depth)
        visible.append(len(pix) / in_image if in_image > 0 else 1.0)
        complete.append(len(pix) / (full_area * FULL_FILL) if full_area > 0 else 1.0)
        azimuths.append(pm.arctan2(sight[1], sight[0]))
    kept = [objects[i] for i in kept_index]
    if attribute_rng is None:
        seen_cls = [o.cls for o in kept]
        seen_size = [tuple(float(x) for x in o.size) for o in kept]
        seen_yaw = [float(o.yaw) for o in kept]
    else:
        extent = np.array([(b[2] - b[0], b[3] - b[1]) for b in boxes], dtype=float)
        observed = Observation(
            np.array(kept_index, dtype=np.int64), np.array([len(p) for p in masks]),
            extent.reshape(-1, 2), np.array(depths), np.array(complete), np.array(azimuths),
            (camera.fx, camera.fx),
        )  # fmt: skip
        measured = measured_attributes(
            objects, observed, config.class_confusion, config.size_noise, attribute_rng
        )
        seen_cls = measured.classes
        seen_size = [tuple(float(x) for x in s) for s in measured.sizes]
        seen_yaw = [float(y) for y in measured.yaws]
    features = []
    for k, obj in enumerate(kept):
        if known_features is not None and obj.id in known_features:
            features.append(known_features[obj.id])
            continue
        x0, y0, x1, y1 = boxes[k]
        v, u = np.divmod(masks[k], w)
        mask_crop = np.zeros((y1 - y0, x1 - x0), dtype=np.uint8)
        mask_crop[v - y0, u - x0] = 255
        features.append(object_features(color(), boxes[k], mask_crop, seen_cls[k], seen_size[k]))
    estimates = [(*s, y) for s, y in zip(seen_size, seen_yaw, strict=True)]
    reported = list(seen_cls)
    if config.has_errors and attribute_rng is not None:
        kept, masks, centres, boxes, features, estimates, reported = _with_detector_errors(
            (kept, masks, centres, boxes, features, estimates, reported), depths, visible,
            clean_depth, camera, config, color, error_stream(attribute_rng), known_features,
        )  # fmt: skip
    empty = Detections.empty()  # its shapes, for a view without detections
    return DetectionPlan(
        pixels=np.concatenate(masks) if masks else np.zeros(0, dtype=np.int64),
        starts=np.concatenate([[0], np.cumsum([len(p) for p in masks], dtype=np.int64)]),
        centres=np.array(centres, dtype=float).reshape(-1, 2),
        boxes=np.array(boxes, dtype=float).reshape(-1, 4),
        features=np.array(features, dtype=np.float32) if features else empty.features,
        objects=kept,
        camera=camera,
        surface_to_center=config.surface_to_center,
        shape=(h, w),
        reported_classes=reported,  # clutter: its drawn class
        estimates=np.array(estimates, dtype=float).reshape(-1, 4),
    )


def _with_detector_errors(
    found: tuple[list, ...], depths: list, visible: list,
    clean_depth: np.ndarray, camera: Camera, config: DetectionConfig,
    color: Callable[[], np.ndarray], rng: np.random.Generator,
    known_features: Mapping[str, np.ndarray] | None,
) -> tuple[list, ...]:  # fmt: skip
    """(objects, masks, centres, boxes, features, estimates, reported classes) after the
    detector's misses, centre jitter and false positives (:mod:`cadsim.sensing.detector_errors`,
    in that draw order); a clutter box's estimate is its reported size and heading 0."""
    kept, masks, centres, boxes, features, estimates, reported = found
    p_miss = miss_probability(
        depths, visible, config.miss_near, config.miss_far, config.miss_occluded,
        config.max_depth_m,
    )  # fmt: skip
    stay = rng.random(len(kept)) >= p_miss
    pick = [k for k in range(len(kept)) if stay[k]]
    kept, masks, boxes, features, estimates, reported = (
        [seq[k] for k in pick] for seq in (kept, masks, boxes, features, estimates, reported)
    )
    moved = jittered(
        np.asarray(centres, dtype=float).reshape(-1, 2)[pick], boxes, config.centre_jitter, rng
    )
    centres = [tuple(c) for c in moved]
    h, w = clean_depth.shape
    for clutter in clutter_boxes(rng.poisson(config.false_positives), clean_depth, camera, rng, config.min_pixels, config.size_noise):  # fmt: skip
        x0, y0, x1, y1 = clutter.box
        if known_features is not None and clutter.id in known_features:
            features.append(known_features[clutter.id])
        else:
            mask_crop = np.zeros((y1 - y0, x1 - x0), dtype=np.uint8)
            v, u = np.divmod(clutter.pixels, w)
            mask_crop[v - y0, u - x0] = 255
            features.append(
                object_features(color(), clutter.box, mask_crop, clutter.cls, clutter.size)
            )
        v, u = np.divmod(clutter.pixels, w)
        kept.append(WorldObject(clutter.id, clutter.cls, "box", (0.0, 0.0, 0.0), 0.0, clutter.size, (0.0, 0.0, 0.0)))  # fmt: skip
        masks.append(clutter.pixels)
        centres.append((u.mean() + 0.5, v.mean() + 0.5))
        boxes.append(clutter.box)
        estimates.append((*clutter.size, 0.0))
        reported.append(clutter.cls)
    return kept, masks, centres, boxes, features, estimates, reported


def detect(
    view: RenderedView,
    noisy_depth: np.ndarray,
    objects: Sequence[WorldObject],
    camera: Camera,
    config: DetectionConfig,
    attribute_rng: np.random.Generator | None = None,
    known_features: Mapping[str, np.ndarray] | None = None,
) -> Detections:
    """Detections of the ``target`` objects visible in ``view`` (see the module docstring):
    :func:`plan_detections` then :meth:`DetectionPlan.locate`.

    objects: the snapshot's object list, which ``view.instance`` indexes. noisy_depth: (H, W)
    metres, the view's depth after ``apply_depth_noise``. attribute_rng, known_features: as for
    :func:`plan_detections`; a re-detection at another noise rate may pass the stored features
    and only positions are re-estimated."""
    noisy = np.asarray(noisy_depth)
    if noisy.shape != view.shape:
        raise ValueError(f"noisy_depth must have the view's shape {view.shape}, got {noisy.shape}")
    plan = plan_detections(
        view.instance,
        view.depth,
        objects,
        camera,
        config,
        lambda: view.color,
        attribute_rng=attribute_rng,
        known_features=known_features,
    )
    return plan.locate(noisy)
