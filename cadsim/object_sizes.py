"""Per-object dimensions: each object's (length, width, height) drawn from a published spread for
its class, so that a size does not name a class (docs/scenarios.md, "Object sizes").

A class's spread is a mean and a standard deviation per dimension (metres); a drawn size is
``mean + sd · ε``, ε ~ N(0, 1) per dimension, with ε clipped to ±:data:`CLIP_SD` (the plausible
bounds: no 7 m hatchback, no 1 m adult), rounded to centimetres. Where a source states its own mean size for an object
(a SUMO vType's length/width/height), that is the mean and the class gives the spread. Draws
use only +, × and clipping, so the bytes are the same on any CPU.

Every object draws from its own stream: ``SeedSequence(root, spawn_key=(SIZE_STREAM, h1, h2))``
with (h1, h2) two CRC-32s of the object id, so an object's size depends on the root seed and its
id only — not on which other objects exist or in which order they are met.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass

import numpy as np

SIZE_MODEL = 2
"""Version of the object-size model, stated in a SUMO dataset's manifest (``generation.object_sizes``):
1 (datasets without the key) one size per vType and fixed street furniture; 2 per-object draws
(this module), roadside clutter (``[traffic.scene] clutter_spacing``), reported sizes in clutter
detections. Datasets of another model cannot be resumed by this one (their records differ)."""
SIZE_STREAM = 7
"""Spawn-key head of the per-object size streams (beside ``cadsim.dataset.seeds``' streams)."""
CLIP_SD = 2.5
"""Drawn dimensions stay within mean ± CLIP_SD standard deviations."""


@dataclass(frozen=True)
class SizeSpread:
    """Mean and standard deviation (length, width, height), metres, of one class's objects."""

    mean: tuple[float, float, float]
    sd: tuple[float, float, float]

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) (3,) metres: mean ∓ CLIP_SD · sd."""
        m, s = np.asarray(self.mean, float), np.asarray(self.sd, float)
        return m - CLIP_SD * s, m + CLIP_SD * s


SIZE_SPREADS: dict[str, SizeSpread] = {
    # European passenger cars (new-car fleet ~2020-2023: length 4.4-4.5 m, width 1.8 m, height
    # 1.5-1.55 m; the length spread covers city cars 3.6 m to executive/SUV 5.2 m).
    "car": SizeSpread((4.5, 1.8, 1.52), (0.35, 0.07, 0.10)),
    # Light commercial vans (3.5 t class, short to long wheelbase, low to high roof).
    "van": SizeSpread((5.4, 2.0, 2.3), (0.55, 0.08, 0.25)),
    # Rigid trucks (EU limits: width 2.55 m, length 12 m, height 4 m in practice).
    "truck": SizeSpread((9.0, 2.5, 3.4), (1.2, 0.04, 0.22)),
    # City buses (10.5-13.5 m two-axle, 2.55 m wide, ~3.0-3.3 m high).
    "bus": SizeSpread((12.0, 2.52, 3.1), (0.8, 0.03, 0.12)),
    # Bicycle with rider: frame length, handlebar width, rider's height on the saddle.
    "bicycle": SizeSpread((1.75, 0.6, 1.7), (0.08, 0.05, 0.08)),
    "motorcycle": SizeSpread((2.1, 0.8, 1.45), (0.15, 0.06, 0.08)),
    # Adults: body depth, shoulder breadth, stature (pooled men and women: 1.71 m, sd 0.095 m).
    "person": SizeSpread((0.28, 0.48, 1.71), (0.03, 0.04, 0.095)),
    # Street furniture (plates and poles vary by road class and maker).
    "sign": SizeSpread((0.08, 0.75, 2.6), (0.01, 0.12, 0.25)),
    "traffic_light": SizeSpread((0.4, 0.4, 3.5), (0.04, 0.04, 0.35)),
    "box": SizeSpread((0.5, 0.5, 0.5), (0.08, 0.08, 0.08)),
    "cone": SizeSpread((0.36, 0.36, 0.6), (0.04, 0.04, 0.12)),
    # Roadside clutter the LiDAR meets (cadsim.sources.roadside_clutter).
    "tree": SizeSpread((2.5, 2.5, 5.5), (0.7, 0.7, 1.3)),
    "pole": SizeSpread((0.25, 0.25, 4.5), (0.05, 0.05, 1.0)),
    "bin": SizeSpread((0.65, 0.6, 1.05), (0.1, 0.08, 0.1)),
    "trailer": SizeSpread((4.0, 2.05, 2.2), (0.8, 0.15, 0.35)),
}
"""Class -> spread (docs/scenarios.md cites the sources of each figure)."""


def object_size_stream(root: int, object_id: str) -> np.random.Generator:
    """The size stream of object ``object_id`` under root seed ``root`` (module docstring)."""
    data = object_id.encode()
    key = (SIZE_STREAM, zlib.crc32(data), zlib.crc32(data[::-1] + b"#"))
    return np.random.default_rng(np.random.SeedSequence(int(root), spawn_key=key))


def draw_size(
    root: int,
    object_id: str,
    cls: str,
    mean: tuple[float, float, float] | None = None,
) -> tuple[float, float, float]:
    """(length, width, height) metres of object ``object_id`` of class ``cls``: the class's spread
    around ``mean`` (default: the class's own mean). A class without a spread keeps ``mean``."""
    spread = SIZE_SPREADS.get(cls)
    if spread is None:
        if mean is None:
            raise ValueError(f"object size: no spread for class {cls!r} and no mean size given")
        return tuple(float(v) for v in mean)
    centre = np.asarray(spread.mean if mean is None else mean, dtype=float)
    eps = np.clip(object_size_stream(root, object_id).standard_normal(3), -CLIP_SD, CLIP_SD)
    size = np.round(centre + np.asarray(spread.sd, dtype=float) * eps, 2)  # centimetres
    return tuple(float(v) for v in np.maximum(size, 0.02))


__all__ = [
    "CLIP_SD",
    "SIZE_MODEL",
    "SIZE_SPREADS",
    "SIZE_STREAM",
    "SizeSpread",
    "draw_size",
    "object_size_stream",
]
