"""Attributes as a camera detector measures them: the class, 3-D size and heading one view's
detector reports for each detected object, estimated from what the view shows of it — its
visible mask, its depth, how much of it is in the image and unoccluded — never copied from the
simulator's truth (docs/detection.md, "Sizes and classes measured from the image").

Per detected object, with p its visible pixels, z the median depth of its mask (metres), (Δu, Δv)
its mask's pixel box and c its *completeness* (visible pixels over the pixel area its whole 3-D
box would cover, image border and occluders ignored, over :data:`FULL_FILL`, clipped to [0, 1]:
truncation and occlusion both lower it), and q = √(:data:`REFERENCE_PIXELS` / p) (how much worse
than a 32 × 32-pixel object, COCO's small/medium boundary, it is resolved):

- **class**: reported as another class of its confusion group with probability
  ``class_confusion`` · q (clipped to [0, :data:`MAX_CONFUSION`], or to the rate itself when it
  is higher; uniformly among the group's other members: a van for a truck, a cyclist for a
  pedestrian, a sign for a traffic light — never a bus for a pedestrian); classes outside every
  group are never confused. Small, far, truncated and occluded objects (few pixels) are confused
  more often.
- **heading**: the true yaw plus N(0, (:data:`HEADING_SD` · q)²) radians (an orientation
  regressor is worse on small objects).
- **size**: σ = ``size_noise`` · max(q, 1) (log units, at most :data:`MAX_SIZE_SIGMA`; an
  object resolved better than the reference is sized no better: the regressor's error floor).
  The depth the detector reads is ẑ = z · exp(σ/2 · ε) (one draw per object). The image measures the visible
  silhouette: height Δv · ẑ / f_y and width Δu · ẑ / f_x; the width is split into length and
  width with the estimated heading and the reported class's mean aspect ratio L₀ / W₀
  (a box L × W seen at angle α between its length axis and the line of sight has silhouette
  width L |sin α| + W |cos α|). That measurement m covers only the visible part, so the estimate
  is the class's mean size s₀ (``cadsim.object_sizes``) where nothing is seen and m where all is
  seen: log ŝ = c · log m + (1 − c) · log s₀, then times exp(σ · ε) per dimension (the
  regressor's own error). A class without a mean size (robots) is its measurement alone.

So a near, fully visible object's size is the measurement of its silhouette, within about
``size_noise``; a truncated or occluded one's is pulled towards its (reported) class's mean and its
measured part is too small; a distant one's error grows as 1/√p. The true size and heading enter
only through what the image shows (the silhouette's pixel extent) and the heading regressor's
target. Draws (fixed order, whatever the rates, for every object of the snapshot so that an
object's attributes do not depend on which others are detected): n uniforms (confused?), n
uniforms (into which class), n × 3 normals (size), n normals (heading), n normals (depth).
Imports numpy, ``cadsim.object_sizes`` and ``cadsim.world`` only.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cadsim import portable_math as pm
from cadsim.object_sizes import SIZE_SPREADS
from cadsim.world import WorldObject

CONFUSION_GROUPS: tuple[tuple[str, ...], ...] = (
    ("car", "van", "bus", "truck"),
    ("bicycle", "person"),
    ("traffic_light", "sign"),
    ("robot", "box", "cone"),
)
REFERENCE_PIXELS = 1024.0
"""Visible pixels (32 × 32: COCO's small/medium boundary) at which class confusion and size
noise are the ``[detection]`` table's rates; both scale with √(REFERENCE_PIXELS / pixels)."""
MAX_CONFUSION = 0.9
MAX_SIZE_SIGMA = 1.0
HEADING_SD = 0.15
"""Heading error (radians, ≈ 9°) at :data:`REFERENCE_PIXELS` (docs/detection.md)."""
FULL_FILL = 0.7
"""Share of its 3-D box's projected area an unoccluded, untruncated object's mask covers
(the median for the car mesh seen from 10–35 m at four headings: docs/detection.md);
completeness is relative to it."""


@dataclass(frozen=True)
class Observation:
    """What one view shows of k detected objects. index: (k,) their indices in the snapshot's
    object list. pixels: (k,) visible pixel counts. extent_px: (k, 2) their mask boxes' width
    and height (pixels). depth_m: (k,) median depth of each mask (metres). completeness: (k,)
    visible pixels over the pixel area of the whole projected 3-D box (unclipped).
    azimuth: (k,) direction of the line of sight to each object in the world's ground plane
    (radians, counter-clockwise from +x). focal_px: (f_x, f_y)."""

    index: np.ndarray
    pixels: np.ndarray
    extent_px: np.ndarray
    depth_m: np.ndarray
    completeness: np.ndarray
    azimuth: np.ndarray
    focal_px: tuple[float, float]


@dataclass(frozen=True)
class MeasuredAttributes:
    """What the detector reports for the observed objects: classes (k), sizes (k, 3) length,
    width, height in metres, yaws (k,) world heading estimates (radians)."""

    classes: list[str]
    sizes: np.ndarray
    yaws: np.ndarray


def confused_classes(names: np.ndarray, confused: np.ndarray, choice: np.ndarray) -> np.ndarray:
    """``names`` with each ``confused`` entry replaced by another member of its confusion group
    (``choice`` ∈ [0, 1) picks which, uniformly)."""
    reported = names.copy()
    for group in CONFUSION_GROUPS:
        members = np.array(group, dtype=object)
        own = np.flatnonzero(confused & np.isin(names, members))
        if not own.size:
            continue
        k = np.argmax(names[own][:, None] == members[None, :], axis=1)  # index in the group
        step = 1 + np.floor(choice[own] * (len(group) - 1)).astype(int)
        reported[own] = members[(k + step) % len(group)]
    return reported


def resolution_factor(pixels: np.ndarray) -> np.ndarray:
    """(k,) √(REFERENCE_PIXELS / pixels): 1 at a 32 × 32-pixel object, larger below."""
    return np.sqrt(REFERENCE_PIXELS / np.maximum(np.asarray(pixels, dtype=float), 1.0))


def measured_attributes(
    objects: Sequence[WorldObject],
    seen: Observation,
    class_confusion: float,
    size_noise: float,
    rng: np.random.Generator,
) -> MeasuredAttributes:
    """The class, size and heading one view's detector reports for the objects ``seen`` shows
    (module docstring); ``objects``: the snapshot's whole list (the draws are made for each).

    A car 20 m away seen side-on, 180 × 61 pixels at f = 800 px, fully visible, no size noise
    (its heading error alone splits the silhouette a little differently):

    >>> from cadsim.world import WorldObject
    >>> car = WorldObject("c", "car", "car", (0, 20, 0.76), 0.0, (4.6, 1.8, 1.52), (1, 1, 1))
    >>> seen = Observation(np.array([0]), np.array([9000]), np.array([[180.0, 61.0]]),
    ...                    np.array([20.0]), np.array([1.0]), np.array([np.pi / 2]), (800.0, 800.0))
    >>> out = measured_attributes([car], seen, 0.0, 0.0, np.random.default_rng(0))
    >>> out.classes, np.round(out.sizes, 2).tolist()
    (['car'], [[4.47, 1.79, 1.52]])
    """
    n = len(objects)
    confused_u = rng.random(n)
    choice = rng.random(n)
    eps = rng.standard_normal((n, 3))
    eps_heading = rng.standard_normal(n)
    eps_depth = rng.standard_normal(n)
    idx = np.asarray(seen.index, dtype=np.int64).reshape(-1)
    q = resolution_factor(seen.pixels)
    names = np.array([objects[i].cls for i in idx], dtype=object)
    p_confused = np.clip(class_confusion * q, 0.0, max(MAX_CONFUSION, class_confusion))
    reported = confused_classes(names, confused_u[idx] < p_confused, choice[idx])
    yaws = np.array([objects[i].yaw for i in idx], dtype=float) + HEADING_SD * q * eps_heading[idx]
    sigma = np.minimum(size_noise * np.maximum(q, 1.0), MAX_SIZE_SIGMA)
    depth = np.asarray(seen.depth_m, dtype=float) * pm.exp(0.5 * sigma * eps_depth[idx])
    extent = np.asarray(seen.extent_px, dtype=float).reshape(-1, 2)
    fx, fy = seen.focal_px
    silhouette = np.maximum(extent[:, 0] * depth / fx, 1e-3)
    height = np.maximum(extent[:, 1] * depth / fy, 1e-3)
    prior = np.array([_mean_size(c) for c in reported], dtype=float).reshape(-1, 3)
    known = np.isfinite(prior[:, 0])
    aspect = np.where(known, prior[:, 0] / np.where(known, prior[:, 1], 1.0), 1.0)
    alpha = yaws - np.asarray(seen.azimuth, dtype=float)
    across = np.abs(np.sin(alpha)) + np.abs(np.cos(alpha)) / aspect
    length = silhouette / np.maximum(across, 1e-3)
    measured = np.stack([length, length / aspect, height], axis=1)
    c = np.where(known, np.clip(np.asarray(seen.completeness, dtype=float), 0.0, 1.0), 1.0)
    log_size = c[:, None] * pm.log(measured).reshape(-1, 3)
    log_size = log_size + (1.0 - c[:, None]) * pm.log(np.where(known[:, None], prior, 1.0))
    sizes = pm.exp(log_size + sigma[:, None] * eps[idx]).reshape(-1, 3)
    return MeasuredAttributes([str(v) for v in reported], sizes, yaws)


def _mean_size(cls: str) -> tuple[float, float, float]:
    spread = SIZE_SPREADS.get(cls)
    return tuple(spread.mean) if spread is not None else (np.nan, np.nan, np.nan)


__all__ = [
    "CONFUSION_GROUPS",
    "MeasuredAttributes",
    "Observation",
    "confused_classes",
    "measured_attributes",
    "resolution_factor",
]
