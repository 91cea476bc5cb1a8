"""A run's redraw of a sequence's odometry: the drift of each vehicle's dead reckoning drawn
again for evaluation run ``seed`` (seed scheme 2, :mod:`cadsim.dataset.seeds`), so that two
splits, and two runs, never share odometry noise.

The redraw replays generation: one :class:`~cadsim.sensing.odometry.Odometer` per view with the
sequence's stored drift model (``record.json`` ``sequence.model``), fed each frame's true
observer pose (``FramePair.observer_poses``) in time order. Its seed is
``redraw_seed(ODOMETRY_STREAM, seed, sim_seed, episode, first_slot, view)``: the run seed with the
sequence's identity, its simulation seed (which carries the dataset's root seed) included.
``seed=None`` keeps the stored odometry (the seeds written at generation, ``odometry_seed``).
Imports no simulator.
"""

from __future__ import annotations

from collections.abc import Sequence

from cadsim.dataset.frame_pair import FramePair
from cadsim.dataset.seeds import ODOMETRY_STREAM, redraw_seed
from cadsim.sensing.odometry import Odometer, OdometryModel


def odometry_redraw_seeds(frames: Sequence[FramePair], seed: int) -> tuple[int, ...]:
    """Per view (frame 0's view order) the seed of run ``seed``'s odometry of the sequence
    whose frame 0 is ``frames[0]``."""
    first = frames[0]
    return tuple(
        redraw_seed(ODOMETRY_STREAM, seed, first.sim_seed, first.episode, first.slot, v)
        for v in first.view_numbers
    )


def replay_odometry(frames: Sequence[FramePair], seeds: Sequence[int]) -> list[FramePair]:
    """``frames`` (one sequence, frame 0 first) with the odometry that odometers seeded by
    ``seeds`` (one per view) report along the frames' true observer poses. With the stored
    ``odometry_seed``s this is the stored odometry, bit for bit (tested)."""
    first = frames[0]
    model = {k: v for k, v in first.record["sequence"]["model"].items() if k != "kind"}
    odometers = [Odometer(OdometryModel(**model), int(s), len(frames)) for s in seeds]
    out = []
    for pair in frames:
        poses = pair.observer_poses
        if poses is None:
            raise ValueError(f"{pair.path}: no true observer poses to replay odometry along")
        out.append(
            pair.with_odometry(tuple(o.step(p) for o, p in zip(odometers, poses, strict=True)))
        )
    return out


def redraw_odometry(frames: Sequence[FramePair], seed: int | None) -> list[FramePair]:
    """The frames of one sequence (``Dataset.sequence(k)``, time order) with run ``seed``'s
    odometry (module docstring); ``seed=None``, or frames of no sequence (a dataset without
    ``[sequence]``, no odometry), unchanged. ValueError when ``frames`` are not one whole
    sequence from its frame 0 on.

    >>> frames = redraw_odometry(Dataset("data/cad-v2x-seq").sequence(0), seed=1)  # doctest: +SKIP
    """
    frames = list(frames)
    if seed is None or not frames or frames[0].odometry is None:
        return frames
    ids = {pair.sequence_id for pair in frames}
    if len(ids) != 1 or [pair.frame for pair in frames] != list(range(len(frames))):
        raise ValueError(
            "frames: expected one sequence's frames 0, 1, … in order, got sequences "
            f"{sorted(map(str, ids))} frames {[pair.frame for pair in frames]}"
        )
    return replay_odometry(frames, odometry_redraw_seeds(frames, seed))
