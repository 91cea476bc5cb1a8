"""Detector errors: what a real object detector gets wrong beyond depth noise (DESIGN §6).

Three errors, per view, seeded, all off by default (the ``[detection]`` keys of
:class:`cadsim.sensing.detection.DetectionConfig`):

- **missed detections**: an object that passes every visibility filter is still dropped with
  probability ``miss_near + miss_far · d / max_depth_m + miss_occluded · (1 − f)`` (clipped to
  [0, 1]), d its median depth (metres), f its visible fraction — detectors miss far and occluded
  objects first;
- **false positives**: Poisson(``false_positives``) clutter detections per view — a box the
  size a car, person or sign would have at that depth, placed on a random pixel with a depth
  (a wall, the road, a parked car's flank), whose features are computed from the image there
  like any detection's, so they look plausible; its size is drawn from its class's spread
  (``cadsim.object_sizes``) and reported with the detector's size noise, like a real object's;
  each has an id of its own (``clutter:…``) that no other view can share, so it is never a true
  pair;
- **centre jitter**: every detection's centroid moves by N(0, ``centre_jitter``²) times its
  box's width and height (pixels), so its position moves along the image plane.

Draw order (fixed, so one seed gives one outcome): one uniform per candidate detection (misses),
two normals per kept detection (jitter), then the clutter count, the id tag and, per clutter
box, its pixel, class, three normals (its size) and three normals (its size noise). The stream is a child of the view's attribute stream (:func:`error_stream`): the
dataset's records keep their seeds, and the reader's re-detection draws the same errors.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cadsim import portable_math as pm
from cadsim.camera import Camera
from cadsim.object_sizes import CLIP_SD, SIZE_SPREADS

_ERROR_CHILD = 9  # spawn-key suffix of the detector-error stream under the attribute stream

CLUTTER_KINDS: tuple[str, ...] = ("car", "person", "sign")
"""Classes a clutter detection is reported as (its size: the class's spread, module docstring)."""


def error_stream(attribute_rng: np.random.Generator) -> np.random.Generator:
    """The view's detector-error stream: a child of its attribute stream's seed sequence (the
    attribute stream itself is not advanced)."""
    seq = attribute_rng.bit_generator.seed_seq
    child = np.random.SeedSequence(seq.entropy, spawn_key=(*seq.spawn_key, _ERROR_CHILD))
    return np.random.default_rng(child)


def miss_probability(
    depth_m: np.ndarray, visible_fraction: np.ndarray, near: float, far: float, occluded: float,
    max_depth_m: float,
) -> np.ndarray:  # fmt: skip
    """(k,) probability that the detector misses each object (module docstring)."""
    d = np.asarray(depth_m, dtype=float) / max(float(max_depth_m), 1e-9)
    hidden = 1.0 - np.clip(np.asarray(visible_fraction, dtype=float), 0.0, 1.0)
    return np.clip(near + far * d + occluded * hidden, 0.0, 1.0)


@dataclass(frozen=True)
class ClutterBox:
    """One false positive: id, reported class and size (metres), its integer pixel box
    (x0, y0, x1, y1; x1, y1 exclusive) and the flat indices of its pixels with a depth."""

    id: str
    cls: str
    size: tuple[float, float, float]
    box: tuple[int, int, int, int]
    pixels: np.ndarray


def clutter_boxes(
    count: int, clean_depth: np.ndarray, camera: Camera, rng: np.random.Generator,
    min_pixels: int, size_noise: float = 0.0,
) -> list[ClutterBox]:  # fmt: skip
    """``count`` clutter detections on pixels that have a depth (fewer if a box would hold under
    ``min_pixels`` such pixels: it is dropped, its draws still made). A box's ``size`` is the one
    the detector reports: drawn from its class's spread, times exp(``size_noise`` · ε) per
    dimension (``cadsim.sensing.attribute_noise``'s size noise)."""
    depth = np.asarray(clean_depth, dtype=float)
    h, w = depth.shape
    hit = np.flatnonzero(depth.ravel() > 0)
    tag = int(rng.integers(2**32))
    out: list[ClutterBox] = []
    for k in range(int(count)):
        pick, kind = rng.random(), int(rng.integers(len(CLUTTER_KINDS)))
        cls = CLUTTER_KINDS[kind]
        spread = SIZE_SPREADS[cls]
        eps = np.clip(rng.standard_normal(3), -CLIP_SD, CLIP_SD)
        noise = pm.exp(size_noise * rng.standard_normal(3))
        drawn = (np.asarray(spread.mean) + np.asarray(spread.sd) * eps) * noise
        size = tuple(float(v) for v in drawn)
        if not hit.size:
            continue
        centre = int(hit[min(int(pick * hit.size), hit.size - 1)])
        v, u = divmod(centre, w)
        scale = camera.fx / max(depth[v, u], 1e-3)  # pixels per metre at that depth
        half_w = max(2, int(round(0.5 * max(size[0], size[1]) * scale)))
        half_h = max(2, int(round(0.5 * size[2] * scale)))
        x0, x1 = max(0, u - half_w), min(w, u + half_w)
        y0, y1 = max(0, v - half_h), min(h, v + half_h)
        rows, cols = np.mgrid[y0:y1, x0:x1]
        flat = (rows * w + cols).ravel()
        flat = flat[depth.ravel()[flat] > 0]
        if flat.size < min_pixels:
            continue
        out.append(ClutterBox(f"clutter:{tag:08x}:{k}", cls, size, (x0, y0, x1, y1), flat))
    return out


def jittered(centres: np.ndarray, boxes: Sequence, jitter: float, rng: np.random.Generator):
    """(k, 2) centroids (pixels) moved by N(0, jitter²) times each box's (width, height)."""
    centres = np.asarray(centres, dtype=float).reshape(-1, 2)
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    extent = boxes[:, 2:] - boxes[:, :2]
    return centres + rng.standard_normal(centres.shape) * jitter * extent
