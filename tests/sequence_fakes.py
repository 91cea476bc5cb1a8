"""Planted sequences for the temporal matchers, tracker and metrics (issue 41): two agents
driving past objects (some moving), each seeing its own subset, with clutter, detection noise,
odometry and a GNSS prior, and the truth to score against."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from matchers import Problem
from matchers.core.sequence_problem import SequenceProblem


def pose_matrix(x: float, y: float, yaw: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, x], [s, c, y], [0.0, 0.0, 1.0]])


def apply(pose: np.ndarray, xy: np.ndarray) -> np.ndarray:
    return xy @ pose[:2, :2].T + pose[:2, 2]


def as_xyyaw(pose: np.ndarray) -> np.ndarray:
    return np.array([pose[0, 2], pose[1, 2], np.arctan2(pose[1, 0], pose[0, 0])])


# camera (x right, y down, z forward) -> body (x forward, y left, z up), camera 1.5 m up, 1 m ahead
MOUNT = np.array(
    [[0.0, 0.0, 1.0, 1.0], [-1.0, 0.0, 0.0, 0.0], [0.0, -1.0, 0.0, 1.5], [0.0, 0.0, 0.0, 1.0]]
)


@dataclass
class Planted:
    seq: SequenceProblem
    true1: list[np.ndarray]  # per frame, true object id of each view-1 detection (-1 clutter)
    true2: list[np.ndarray]
    relative: np.ndarray  # 3x3: agent 2's frame-0 plane -> agent 1's frame-0 plane


def planted_sequence(
    seed: int = 0,
    frames: int = 6,
    covisible: int = 8,
    only: int = 3,
    clutter: int = 2,
    noise: float = 0.1,
    gnss_sigma: float = 1.2,
    gnss_yaw_deg: float = 2.0,
    camera: bool = False,
    latency: float = 0.0,
    moving: float = 0.3,
    speed_sigma: float = 3.0,
) -> Planted:
    """Frames 0.1 s apart (``seq.meta["interval_s"]``); a share ``moving`` of the objects moves
    (N(0, speed_sigma²) m/s per axis); agent 2's detections are ``latency`` seconds old (the
    objects where they were then; its own pose current)."""
    rng = np.random.default_rng(seed)
    count = covisible + 2 * only
    objects = rng.uniform([-10, -25], [60, 25], size=(count, 2))
    speed = np.where(
        rng.random(count)[:, None] < moving, rng.normal(0, speed_sigma, (count, 2)), 0.0
    )
    # agent 1 drives along +x from the origin; agent 2 comes the other way, 40 m ahead, 8 m left
    start1, start2 = pose_matrix(0, 0, 0.0), pose_matrix(45, 8, np.pi - 0.3)
    view1 = np.r_[np.arange(covisible), covisible + np.arange(only)]
    view2 = np.r_[np.arange(covisible), covisible + only + np.arange(only)]
    perm1, perm2 = rng.permutation(1000)[:count] + 10, rng.permutation(1000)[:count] + 10
    problems, tracks1, tracks2, odo1, odo2, true1, true2 = [], [], [], [], [], [], []
    next_clutter = 5000
    for t in range(frames):
        at = objects + speed * t * 0.1
        sent = objects + speed * (t * 0.1 - latency)  # what agent 2's message shows
        poses = [
            start1 @ pose_matrix(1.5 * t, 0, 0.01 * t),
            start2 @ pose_matrix(1.2 * t, 0, -0.02 * t),
        ]
        odo1.append(as_xyyaw(np.linalg.inv(start1) @ poses[0]))
        odo2.append(as_xyyaw(np.linalg.inv(start2) @ poses[1]))
        per_view = []
        for k, (seen, perm) in enumerate(((view1, perm1), (view2, perm2))):
            where = at if k == 0 else sent
            body = apply(np.linalg.inv(poses[k]), where[seen])
            body = body + rng.normal(0, noise, (len(seen), 2))
            junk = rng.uniform([0, -20], [40, 20], size=(clutter, 2))
            xy = np.r_[body, junk]
            truth = np.r_[seen, np.full(clutter, -1)]
            tracks = np.r_[perm[seen], next_clutter + np.arange(clutter)]
            next_clutter += clutter
            order = rng.permutation(len(xy))
            xy, truth, tracks = xy[order], truth[order], tracks[order]
            err = rng.normal(0, gnss_sigma, 2)
            noisy = poses[k] @ pose_matrix(*err, np.radians(rng.normal(0, gnss_yaw_deg)))
            world = np.c_[apply(noisy, xy), np.zeros(len(xy))]
            if camera:
                body3 = np.c_[xy, np.zeros(len(xy))]
                points = (body3 - MOUNT[:3, 3]) @ MOUNT[:3, :3]  # inverse mount
            else:
                points = xy
            per_view.append((points, world, truth, tracks))
        (p1, w1, tr1, id1), (p2, w2, tr2, id2) = per_view
        problems.append(Problem(p1, p2, world1=w1, world2=w2, world_sigma=gnss_sigma))
        tracks1.append(id1)
        tracks2.append(id2)
        true1.append(tr1)
        true2.append(tr2)
    mount = MOUNT if camera else None
    seq = SequenceProblem(
        problems, tracks1, tracks2, np.array(odo1), np.array(odo2), mount, mount,
        {"interval_s": 0.1},
    )  # fmt: skip
    return Planted(seq, true1, true2, np.linalg.inv(start1) @ start2)


def true_pairs(true1: np.ndarray, true2: np.ndarray) -> set[tuple[int, int]]:
    """The covisible (i, j) of one frame: the same object id >= 0 in both views."""
    same = (true1[:, None] == true2[None, :]) & (true1[:, None] >= 0)
    return {(int(i), int(j)) for i, j in zip(*np.nonzero(same), strict=True)}
