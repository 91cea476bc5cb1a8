"""Odometry between the frames of a sequence: what a vehicle's wheel/IMU dead reckoning reports.

Each observer of a sequence reports, at frame k, its pose relative to its own pose at frame 0 (x
forward, y left of its frame-0 heading, metres; heading change, radians) as dead reckoning
integrates it: the true motion between consecutive frames plus errors (docs/localisation.md,
"Odometry", gives the model's source and magnitudes):

* a distance *scale* error ``s ~ N(0, scale_sigma²)``, drawn once per observer and sequence
  (wheel-radius / calibration error: a systematic error, Borenstein & Feng 1996);
* a heading drift ``b ~ N(0, heading_sigma²)`` rad per metre travelled, drawn once per observer
  and sequence (gyro bias / wheel-base error, expressed per metre as KITTI's rotation error is);
* random-walk noise per increment of length d: ``N(0, position_walk² · d)`` on each of the
  increment's x and y, ``N(0, heading_walk² · d)`` on its heading (the non-systematic part).

Increment k (frame k-1 → k, in the true frame-(k-1) body frame: dx, dy, dψ, d = |(dx, dy)|) is
reported as ((1+s)·dx + n_x, (1+s)·dy + n_y, dψ + b·d + n_ψ) and composed onto the reported
pose of frame k-1. A standing vehicle (d = 0) accumulates no error, as wheel odometry does not.
On a straight path of length D the reported along-track error has standard deviation
``sqrt((scale_sigma·D)² + position_walk²·D)`` and the heading error
``sqrt((heading_sigma·D)² + heading_walk²·D)`` (:func:`error_sigmas`; the test checks them).

Draws come from one generator per observer and sequence (seed stream 6, ``odometry_seed``), in
this order: s, b, then (n_x, n_y, n_ψ) for each increment k = 1 … frames-1, always drawn (so a
frame's value never depends on how long the sequence turns out). Imports only numpy.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from cadsim.observer_pose import ObserverPose


@dataclass(frozen=True)
class OdometryModel:
    """The drift model (module docstring). Angles in degrees, as the scenario gives them."""

    scale_sigma: float = 0.01
    heading_sigma_deg_per_m: float = 0.01
    position_walk: float = 0.02
    heading_walk_deg: float = 0.005

    @classmethod
    def from_sequence(cls, table: dict | None) -> OdometryModel:
        """From a validated ``[sequence]`` table (its ``odometry_*`` keys)."""
        t = table or {}
        d = cls()
        return cls(
            float(t.get("odometry_scale_sigma", d.scale_sigma)),
            float(t.get("odometry_heading_sigma_deg_per_m", d.heading_sigma_deg_per_m)),
            float(t.get("odometry_position_walk", d.position_walk)),
            float(t.get("odometry_heading_walk_deg", d.heading_walk_deg)),
        )

    def as_record(self) -> dict:
        return {"kind": "scale-heading-drift+random-walk", **asdict(self)}


@dataclass(frozen=True)
class OdometryPose:
    """A reported pose relative to frame 0: x forward, y left (metres, frame-0 body frame), yaw
    (radians); distance_m: the true distance travelled since frame 0."""

    x: float
    y: float
    yaw: float
    distance_m: float = 0.0

    def as_dict(self) -> dict:
        return {
            "position": [float(self.x), float(self.y)],
            "yaw": float(self.yaw),
            "distance_m": float(self.distance_m),
        }

    @classmethod
    def from_dict(cls, d: dict) -> OdometryPose:
        x, y = d["position"]
        return cls(float(x), float(y), float(d["yaw"]), float(d.get("distance_m", 0.0)))

    def matrix(self) -> np.ndarray:
        """3×3 homogeneous 2-D transform of this pose (frame k body → frame 0 body)."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return np.array([[c, -s, self.x], [s, c, self.y], [0.0, 0.0, 1.0]])


def relative_pose(origin: ObserverPose, pose: ObserverPose) -> tuple[float, float, float]:
    """``pose`` in the body frame of ``origin`` (x forward, y left, metres; yaw change, rad)."""
    dx = pose.position[0] - origin.position[0]
    dy = pose.position[1] - origin.position[1]
    c, s = math.cos(origin.yaw), math.sin(origin.yaw)
    dyaw = (pose.yaw - origin.yaw + math.pi) % (2 * math.pi) - math.pi
    return c * dx + s * dy, -s * dx + c * dy, dyaw


class Odometer:
    """Dead reckoning of one observer over one sequence: ``step(true_pose)`` per frame (the first
    call is frame 0, reported as the origin) returns the frame's :class:`OdometryPose`."""

    def __init__(self, model: OdometryModel, seed: int, frames: int) -> None:
        rng = np.random.default_rng(seed)
        self.scale = float(rng.normal(0.0, model.scale_sigma))
        self.heading_drift = float(rng.normal(0.0, math.radians(model.heading_sigma_deg_per_m)))
        self._noise = rng.standard_normal((max(frames - 1, 0), 3))
        self._walk = (model.position_walk, math.radians(model.heading_walk_deg))
        self._previous: ObserverPose | None = None
        self._reported = (0.0, 0.0, 0.0)
        self._distance = 0.0
        self._k = 0

    def step(self, pose: ObserverPose) -> OdometryPose:
        if self._previous is None:
            self._previous = pose
            self._k = 1
            return OdometryPose(0.0, 0.0, 0.0, 0.0)
        if self._k > len(self._noise):
            raise ValueError(
                f"odometer: more frames than the {len(self._noise) + 1} it was made for"
            )
        dx, dy, dyaw = relative_pose(self._previous, pose)
        d = math.hypot(dx, dy)
        n = self._noise[self._k - 1]
        walk, heading_walk = self._walk
        root = math.sqrt(d)
        rx = (1.0 + self.scale) * dx + walk * root * float(n[0])
        ry = (1.0 + self.scale) * dy + walk * root * float(n[1])
        ryaw = dyaw + self.heading_drift * d + heading_walk * root * float(n[2])
        x, y, yaw = self._reported
        c, s = math.cos(yaw), math.sin(yaw)
        self._reported = (x + c * rx - s * ry, y + s * rx + c * ry, yaw + ryaw)
        self._distance += d
        self._previous = pose
        self._k += 1
        return OdometryPose(*self._reported, self._distance)


def error_sigmas(model: OdometryModel, distance_m: float) -> tuple[float, float]:
    """(along-track metres, heading radians) 1-sigma error after ``distance_m`` on a straight
    path (module docstring)."""
    d = float(distance_m)
    along = math.hypot(model.scale_sigma * d, model.position_walk * math.sqrt(d))
    heading = math.hypot(
        math.radians(model.heading_sigma_deg_per_m) * d,
        math.radians(model.heading_walk_deg) * math.sqrt(d),
    )
    return along, heading
