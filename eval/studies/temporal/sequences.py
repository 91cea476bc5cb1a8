"""A sequence of the temporal study as its matchers see it (:class:`Sequenced`): the frames'
pairs redrawn under a localisation preset, each agent's own tracks from its own detections and
odometry (never a true id), and the truth kept for the metrics only (true ids, true pairs, the
true relative pose, true speeds in m/s)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass
class Sequenced:
    """One sequence under one preset and run: the problem, the truth per frame, the frames."""

    seq: object  # SequenceProblem
    true1: list[np.ndarray]
    true2: list[np.ndarray]
    gt: list[np.ndarray]
    extrinsics: list[np.ndarray | None]
    truth: list[np.ndarray | None]
    episode: int
    sequence: int
    speed1: list[np.ndarray] | None = None  # per frame, true speed (m/s) per detection; NaN clutter
    speed2: list[np.ndarray] | None = None


def _true_speeds(pair, object_ids: Sequence[str]) -> np.ndarray:
    """The true ground speed (m/s) of each detection's object (NaN: clutter): metrics only."""
    by_id = {
        str(o.id): float(np.hypot(*np.asarray(o.velocity, dtype=float)[:2])) for o in pair.objects
    }
    return np.array([by_id.get(str(oid), np.nan) for oid in object_ids], dtype=float)


def _true_ids(object_ids: Sequence[str], names: dict[str, int]) -> np.ndarray:
    """Integer true id per detection (-1: clutter), consistent over one sequence via ``names``."""
    out = []
    for oid in object_ids:
        if str(oid).startswith("clutter:"):
            out.append(-1)
        else:
            out.append(names.setdefault(str(oid), len(names)))
    return np.array(out, dtype=np.int64)


def sequence_problem(frames, preset: str, seed: int, index: int = 0) -> Sequenced:
    """The :class:`Sequenced` of one sequence's ``frames`` (FramePairs in time order) under
    ``preset``, localisation drawn with ``seed``; own tracks from :func:`with_own_tracks`."""
    from matchers.tracking.own_tracks import tracked_sequence

    pairs = [f.localise_preset(preset, seed=seed) for f in frames]
    problems = [p.problem() for p in pairs]
    odometry = [p.odometry for p in pairs]
    odo = [
        np.array([[o[v].x, o[v].y, o[v].yaw] if o else [0.0, 0.0, 0.0] for o in odometry])
        for v in (0, 1)
    ]
    extrinsics = [p.camera_extrinsics for p in pairs]
    mounts = (None, None)
    if extrinsics[0] is not None and all(
        f.points1.shape[1] == 3 and f.points2.shape[1] == 3 for f in problems
    ):
        mounts = (np.asarray(extrinsics[0][0]), np.asarray(extrinsics[0][1]))
    times = np.array([float(f.time) for f in frames])
    meta = {"interval_s": round(float(np.median(np.diff(times))), 6)} if len(times) > 1 else {}
    seq = tracked_sequence(problems, odo[0], odo[1], *mounts, meta=meta)  # own tracks
    names: dict[str, int] = {}
    true1 = [_true_ids(p.view1.object_ids, names) for p in pairs]
    true2 = [_true_ids(p.view2.object_ids, names) for p in pairs]
    return Sequenced(
        seq,
        true1,
        true2,
        [np.asarray(p.gt_pairs, dtype=np.int64).reshape(-1, 2) for p in pairs],
        [None if e is None else np.stack([np.asarray(e[0]), np.asarray(e[1])]) for e in extrinsics],
        [p.true_relative_pose() for p in pairs],
        int(frames[0].episode),
        index,
        [_true_speeds(p, p.view1.object_ids) for p in pairs],
        [_true_speeds(p, p.view2.object_ids) for p in pairs],
    )


def load_split(folder: Path, preset: str, seeds: Sequence[int]) -> list[tuple[int, Sequenced]]:
    """(run seed, :class:`Sequenced`) for every sequence of the dataset at ``folder``: per run
    seed its odometry redrawn (:func:`cadsim.dataset.sequence_odometry.redraw_odometry`) and its
    prior redrawn under ``preset``, so the splits share no noise."""
    from cadsim.dataset import Dataset
    from cadsim.dataset.sequence_odometry import redraw_odometry

    ds = Dataset(str(folder))
    return [
        (seed, sequence_problem(redraw_odometry(ds.sequence(k), seed), preset, seed, k))
        for seed in seeds
        for k in range(ds.sequences)
    ]
