"""One LiDAR sweep over a world snapshot: rays of a beam pattern cast against the renderer's
meshes, ranges made noisy and quantised, returns dropped — a :class:`LidarScan`.

Measurement model, per ray of :meth:`BeamPattern.directions`: the first surface hit (Embree,
``cadsim.sensing.lidar.ray_engine``) at true range r; a return only if ``min_range_m ≤ r ≤
max_range_m`` and the ray is not dropped (probability ``dropout``); the measured range is
``r + N(0, range_sigma_m²)``, kept ≥ ``min_range_m``, rounded to :data:`RANGE_STEP_M` (4 mm, the
distance unit of Hesai's packets and what a uint16 stores up to 262 m). Random draws: one uniform
then one normal per ray of the sweep, hit or not, from the generator the caller passes (seeded
from the frame's identity), so one seed gives one sweep on every machine. Points are in the
LiDAR frame (x forward, y left, z up, metres) and are exactly ``range · direction``.

Each return keeps the index of the object it hit (``object_index`` into ``object_ids``, −1 for
the ground): ground truth for metrics and figures only — the box detector takes points alone.
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass

import numpy as np

from cadsim.sensing.lidar.beam_pattern import RANGE_STEP_M, BeamPattern
from cadsim.sensing.lidar.ray_engine import first_hits
from cadsim.sensing.lidar.scene_triangles import scene_triangles
from cadsim.world import Snapshot

MAX_RANGE_STEPS = np.iinfo(np.uint16).max


@dataclass(frozen=True, eq=False)
class LidarScan:
    """The returns of one sweep, in ray order.

    ray_index: (n,) int64 ray of each return (``channel · azimuth_steps + azimuth``).
    range_steps: (n,) uint16 measured range in :data:`RANGE_STEP_M` units. object_index: (n,)
    int32 index into ``object_ids`` of the object hit (−1: ground) — ground truth only.
    object_ids: the ids of the snapshot's objects, in snapshot order.
    """

    pattern: BeamPattern
    ray_index: np.ndarray
    range_steps: np.ndarray
    object_index: np.ndarray
    object_ids: tuple[str, ...]

    def __len__(self) -> int:
        return len(self.ray_index)

    @property
    def range_m(self) -> np.ndarray:
        """(n,) float64 measured ranges, metres."""
        return self.range_steps.astype(np.float64) * RANGE_STEP_M

    @property
    def points(self) -> np.ndarray:
        """(n, 3) float64 points in the LiDAR frame, metres."""
        return self.range_m[:, None] * self.pattern.directions()[self.ray_index]

    @property
    def channel(self) -> np.ndarray:
        """(n,) int64 channel of each return (0 = lowest elevation)."""
        return self.ray_index // self.pattern.azimuth_steps

    def point_object_ids(self) -> list[str]:
        """The id of the object each return hit ("" for the ground) — ground truth only."""
        ids = np.array([*self.object_ids, ""], dtype=object)
        return ids[self.object_index].tolist()


def quantise_range(range_m: np.ndarray) -> np.ndarray:
    """(n,) uint16 ranges in :data:`RANGE_STEP_M` steps (round half to even; clipped)."""
    return np.clip(np.rint(np.asarray(range_m, dtype=np.float64) / RANGE_STEP_M), 0, MAX_RANGE_STEPS).astype(np.uint16)  # fmt: skip


def scan(
    snapshot: Snapshot,
    sensor_to_world: np.ndarray,
    pattern: BeamPattern,
    rng: np.random.Generator,
    exclude_ids: Collection[str] = (),
) -> LidarScan:
    """One sweep of ``pattern`` from the sensor at ``sensor_to_world`` (4×4, LiDAR frame → world)
    over ``snapshot``; ``exclude_ids``: objects not drawn (the vehicle carrying the sensor).

    >>> from cadsim.world import WorldObject
    >>> from cadsim.sensing.lidar.beam_pattern import PRESETS
    >>> from cadsim.sensing.lidar.mount import level_pose
    >>> box = WorldObject("b", "box", "box", (10.0, 0.0, 1.0), 0.0, (2.0, 2.0, 2.0), (0.5, 0.5, 0.5))
    >>> s = scan(Snapshot(0.0, [box]), level_pose((0, 0, 1.0), 0.0), PRESETS["hdl-64e"],
    ...          np.random.default_rng(0))
    >>> bool((np.asarray(s.point_object_ids()) == "b").any())
    True
    """
    directions = pattern.directions()
    dropped = rng.random(pattern.ray_count) < pattern.dropout
    noise = rng.standard_normal(pattern.ray_count) * pattern.range_sigma_m
    triangles, owner = scene_triangles(snapshot, sensor_to_world, pattern.max_range_m, exclude_ids)
    face, true_range = first_hits(triangles, directions)
    keep = (face >= 0) & ~dropped & (true_range >= pattern.min_range_m) & (true_range <= pattern.max_range_m)  # fmt: skip
    rays = np.flatnonzero(keep)
    measured = np.maximum(true_range[rays] + noise[rays], pattern.min_range_m)
    return LidarScan(
        pattern=pattern,
        ray_index=rays.astype(np.int64),
        range_steps=quantise_range(measured),
        object_index=owner[face[rays]].astype(np.int32),
        object_ids=tuple(o.id for o in snapshot.objects),
    )
