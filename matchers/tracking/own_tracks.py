"""Each agent's own tracks for a whole :class:`~matchers.core.sequence_problem.SequenceProblem`:
the constant-velocity tracker (:mod:`matchers.tracking.constant_velocity`) on each view's
frame-0 ground-plane positions, its gate stretched along the ray from that agent's own sensor.
What a vehicle can build itself: its detections, its mount and its odometry, never a true id."""

from __future__ import annotations

import numpy as np

from matchers.core.sequence_problem import SequenceProblem, ground_positions, sensor_positions
from matchers.tracking.constant_velocity import link

DEFAULT_INTERVAL_S = 0.2


def track_views(seq: SequenceProblem, **options) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """(per-frame own track ids of view 1, of view 2) for ``seq``'s detections (its
    ``tracks1/tracks2`` are ignored); frames ``seq.meta["interval_s"]`` apart (else 0.2 s);
    ``options``: :func:`~matchers.tracking.constant_velocity.link`'s."""
    options.setdefault("interval_s", float(seq.meta.get("interval_s", DEFAULT_INTERVAL_S)))
    return (
        link(ground_positions(seq, 1), origins=sensor_positions(seq, 1), **options),
        link(ground_positions(seq, 2), origins=sensor_positions(seq, 2), **options),
    )


def with_own_tracks(seq: SequenceProblem, **options) -> SequenceProblem:
    """``seq`` with its track ids replaced by :func:`track_views`'s."""
    return seq.with_tracks(*track_views(seq, **options))


def tracked_sequence(
    frames: list,
    odometry1: np.ndarray,
    odometry2: np.ndarray,
    mount1: np.ndarray | None = None,
    mount2: np.ndarray | None = None,
    meta: dict | None = None,
    **options,
) -> SequenceProblem:
    """The :class:`SequenceProblem` of per-frame ``frames`` (time order) with each agent's own
    tracks (:func:`track_views`); ``meta`` (e.g. ``interval_s``) kept on it. The detection
    indices only fill the contract's track fields until :func:`with_own_tracks` replaces them."""
    indices1 = [np.arange(f.n1) for f in frames]
    indices2 = [np.arange(f.n2) for f in frames]
    untracked = SequenceProblem(
        frames, indices1, indices2, odometry1, odometry2, mount1, mount2, dict(meta or {})
    )
    return with_own_tracks(untracked, **options)
