"""Imported frames kept as sequences: the records of one source sequence (a V2X-Seq sequence,
an OPV2V scenario) as consecutive frames of one episode (format 7, read by
``Dataset.sequence``), with each view's odometry taken from the source's true poses.

A sequence of frames 0 … F−1 is episode E, slots S … S+F−1; ``sequence.id`` is the record name
of its frame 0; ``interval_s`` the median time step (``DEFAULT_INTERVAL_S`` when the source
gives no time); each observer's odometry is its body pose relative to frame 0 (x forward, y
left, metres; yaw, radians) and the distance its body travelled, exact (the odometry model's
sigmas are 0). Datasets whose every sequence has one frame are written without sequences.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from cadsim.dataset import layout
from cadsim.dataset.box_record import BoxRecord, BoxView
from cadsim.sensing.odometry import OdometryPose, relative_pose
from cadsim.world import WorldObject

DEFAULT_INTERVAL_S = 0.1  # the field's 10 Hz


@dataclass(frozen=True, eq=False)
class ImportedFrame:
    """One source frame before it has a record identity. time: seconds or None."""

    time: float | None
    views: tuple[BoxView, ...]
    objects: list[WorldObject] = field(default_factory=list)
    meta: dict = field(default_factory=dict)
    prior_sigma_m: float | None = None
    prior_frame: str = ""


def sequence_records(
    episode: int,
    first_slot: int,
    sim_seed: int,
    frames: Sequence[ImportedFrame],
    sequential: bool,
    interval_s: float | None = None,
) -> list[BoxRecord]:
    """The records of one source sequence (module docstring); ``sequential`` False: each frame
    a record of no sequence (slots still consecutive). ``interval_s``: the time step when the
    frames' times do not give it."""
    times = [f.time for f in frames]
    known = [t for t in times if t is not None]
    steps = np.diff(known) if len(known) == len(times) else np.zeros(0)
    step = float(np.median(steps)) if steps.size and np.median(steps) > 0 else None
    step = step or interval_s or DEFAULT_INTERVAL_S
    start = times[0] if times and times[0] is not None else 0.0
    first_name = layout.record_name(episode, first_slot)
    travelled = np.zeros(len(frames[0].views)) if frames else np.zeros(0)
    records = []
    for k, frame in enumerate(frames):
        views = frame.views
        sequence = None
        if sequential:
            origin = frames[0].views
            if k:
                before = frames[k - 1].views
                travelled = travelled + [
                    math.dist(a.body.position[:2], b.body.position[:2])
                    for a, b in zip(before, views, strict=True)
                ]
            views = tuple(
                replace(v, odometry=_odometry(o, v, d) if k else OdometryPose(0.0, 0.0, 0.0))
                for o, v, d in zip(origin, views, travelled, strict=True)
            )
            sequence = {
                "id": first_name,
                "frame": k,
                "frames": len(frames),
                "interval_s": step,
                "start_time": float(start),
            }
        records.append(
            BoxRecord(
                episode,
                first_slot + k,
                sim_seed,
                frame.time,
                views,
                frame.objects,
                frame.meta,
                frame.prior_sigma_m,
                frame.prior_frame,
                sequence,
            )  # fmt: skip
        )
    return records


def _odometry(origin: BoxView, view: BoxView, distance: float) -> OdometryPose:
    x, y, yaw = relative_pose(origin.body, view.body)
    return OdometryPose(x, y, yaw, float(distance))


__all__ = ["DEFAULT_INTERVAL_S", "ImportedFrame", "sequence_records"]
