"""A sequence of frame pairs to match over time (issue 41): the per-frame two-view
:class:`~matchers.core.problem.Problem` in time order, plus what each agent knows about its own
past — the track id its own tracker gave each of its detections (never a true id) and its
odometry (its planar pose relative to its own pose at frame 0).

Frames: each agent's *frame-0 ground plane* is its body frame at frame 0 (x forward, y left, z up;
metres); its odometry at frame t is (x, y, yaw) of its body at t in that plane, so a body-frame
point p at t sits at R(yaw) p_xy + (x, y) there (:func:`ground_positions`). Detections
(``Problem.points1/points2``) are in each agent's camera frame; ``mount1/mount2`` (4 x 4,
camera -> body) put them into the body frame. Without a mount the points are taken as body-frame
positions already (2-D points: ground-plane positions).

Imports nothing from ``cadsim`` or ``eval``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from matchers.core.problem import Problem


def _track_ids(name: str, value, count: int) -> np.ndarray:
    arr = np.asarray(value)
    if arr.size == 0:
        arr = arr.reshape(0).astype(np.int64)
    if arr.ndim != 1 or arr.shape[0] != count:
        raise ValueError(f"{name}: expected {count} track ids, got shape {arr.shape}")
    if arr.size and not np.issubdtype(arr.dtype, np.integer):
        raise ValueError(f"{name}: track ids must be integers, got dtype {arr.dtype}")
    arr = arr.astype(np.int64)
    if len(np.unique(arr)) != len(arr):
        raise ValueError(f"{name}: a track id repeats within one frame")
    return arr


def _odometry(name: str, value, frames: int) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.size == 0:
        arr = arr.reshape(0, 3)
    if arr.shape != (frames, 3):
        raise ValueError(f"{name}: expected shape ({frames}, 3) (x, y, yaw), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: contains NaN or inf")
    return arr


def _mount(name: str, value) -> np.ndarray | None:
    if value is None:
        return None
    arr = np.asarray(value, dtype=float)
    if arr.shape != (4, 4) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: expected a finite 4 x 4 camera-to-body transform")
    return arr


@dataclass(frozen=True)
class SequenceProblem:
    """Frames to match over time, each agent with its own tracks and odometry.

    frames: T :class:`Problem` in time order. tracks1 / tracks2: per frame, the (n_t,) / (m_t,)
    integer track id that agent's own tracker gave each detection (unique within a frame; the
    same id in two frames is the same track). odometry1 / odometry2: (T, 3) each agent's pose
    (x, y, yaw: metres, radians) in its frame-0 ground plane (row 0 is normally (0, 0, 0)).
    mount1 / mount2: optional 4 x 4 camera -> body transforms (3-D points only).

    Validated on construction; T = 0 and empty frames are allowed.

    >>> p = Problem(np.zeros((1, 2)), np.zeros((2, 2)))
    >>> s = SequenceProblem([p], [[7]], [[0, 1]], [[0, 0, 0]], [[0, 0, 0]])
    >>> s.num_frames, s.tracks2[0].tolist()
    (1, [0, 1])
    """

    frames: tuple[Problem, ...]
    tracks1: tuple[np.ndarray, ...]
    tracks2: tuple[np.ndarray, ...]
    odometry1: np.ndarray
    odometry2: np.ndarray
    mount1: np.ndarray | None = None
    mount2: np.ndarray | None = None
    meta: dict = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        frames = tuple(self.frames)
        for t, frame in enumerate(frames):
            if not isinstance(frame, Problem):
                raise TypeError(
                    f"frames[{t}]: expected a matchers.Problem, got {type(frame).__name__}"
                )
        count = len(frames)
        for name in ("tracks1", "tracks2"):
            value = tuple(getattr(self, name))
            if len(value) != count:
                raise ValueError(f"{name}: {len(value)} frames of track ids for {count} frames")
            sizes = [f.n1 if name == "tracks1" else f.n2 for f in frames]
            checked = tuple(
                _track_ids(f"{name}[{t}]", v, n)
                for t, (v, n) in enumerate(zip(value, sizes, strict=True))
            )
            object.__setattr__(self, name, checked)
        object.__setattr__(self, "frames", frames)
        object.__setattr__(self, "odometry1", _odometry("odometry1", self.odometry1, count))
        object.__setattr__(self, "odometry2", _odometry("odometry2", self.odometry2, count))
        for name, view in (("mount1", "points1"), ("mount2", "points2")):
            mount = _mount(name, getattr(self, name))
            if mount is not None and any(
                getattr(f, view).shape[1] != 3 for f in frames if f.n1 + f.n2
            ):
                raise ValueError(f"{name}: a camera mount needs 3-D {view}")
            object.__setattr__(self, name, mount)

    @property
    def num_frames(self) -> int:
        return len(self.frames)

    def with_tracks(self, tracks1, tracks2) -> SequenceProblem:
        """The same sequence with other per-frame track ids (an own tracker's)."""
        return SequenceProblem(
            self.frames, tracks1, tracks2, self.odometry1, self.odometry2,
            self.mount1, self.mount2, dict(self.meta),
        )  # fmt: skip

    def window(self, start: int, stop: int) -> SequenceProblem:
        """Frames [start, stop) as a sequence of their own (odometry kept as it is)."""
        part = slice(max(start, 0), max(stop, 0))
        return SequenceProblem(
            self.frames[part],
            self.tracks1[part],
            self.tracks2[part],
            self.odometry1[part],
            self.odometry2[part],
            self.mount1,
            self.mount2,
            dict(self.meta),
        )


def body_positions(points: np.ndarray, mount: np.ndarray | None) -> np.ndarray:
    """(k, 2) ground-plane (x, y) body-frame positions of (k, D) detections: through the 4 x 4
    camera -> body ``mount``, or the first two coordinates as they are without one."""
    points = np.asarray(points, dtype=float)
    if mount is None:
        return points[:, :2].reshape(-1, 2)
    return (points @ mount[:3, :3].T + mount[:3, 3])[:, :2].reshape(-1, 2)


def to_frame0(xy: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """(k, 2) body-frame positions at a frame whose odometry is ``pose`` (x, y, yaw) -> the
    agent's frame-0 ground plane."""
    c, s = np.cos(pose[2]), np.sin(pose[2])
    return np.asarray(xy, dtype=float).reshape(-1, 2) @ np.array([[c, s], [-s, c]]) + pose[:2]


def ground_positions(seq: SequenceProblem, view: int) -> list[np.ndarray]:
    """Per frame, the (n_t, 2) positions of view ``view``'s (1 or 2) detections in that agent's
    frame-0 ground plane (mount, then odometry)."""
    field_name, mount, odometry = (
        ("points1", seq.mount1, seq.odometry1)
        if view == 1
        else ("points2", seq.mount2, seq.odometry2)
    )
    return [
        to_frame0(body_positions(getattr(frame, field_name), mount), odometry[t])
        for t, frame in enumerate(seq.frames)
    ]


def sensor_positions(seq: SequenceProblem, view: int) -> np.ndarray:
    """(T, 2) where view ``view``'s (1 or 2) sensor sits in that agent's frame-0 ground plane at
    each frame (the mount's origin, then odometry; the body origin without a mount)."""
    mount, odometry = (seq.mount1, seq.odometry1) if view == 1 else (seq.mount2, seq.odometry2)
    origin = np.zeros(2) if mount is None else mount[:2, 3]
    return np.array([to_frame0(origin, pose)[0] for pose in odometry]).reshape(-1, 2)
