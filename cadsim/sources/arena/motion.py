"""Seeded motion model of the robot arena: random-waypoint movers and a patrolling ground observer.

Everything lives in the arena's plane (world x east, y north, metres; yaw radians CCW from +x).
Every mover and obstacle is a disc of a given radius. One ``step`` advances all movers together,
vectorised: each mover proposes a new position from its controller, then every proposal that would
bring two discs closer than their radii plus ``clearance`` (or leave the arena) is rejected and that
mover stays where it was. Rotation is always allowed (a disc turning in place hits nothing), so
the configuration stays collision-free at every step by construction.

Controllers:
- waypoint (robots, people): a differential-drive unicycle that turns towards its waypoint at a
  bounded yaw rate and drives forward at ``speed · max(cos(heading error), 0)``. A new waypoint is
  drawn (away from static obstacles) when it is reached or after ``max_blocked_steps`` blocked steps.
- ring (the ground observer): drives along an ellipse inside the arena while facing the arena
  centre plus a look offset that is redrawn at random times; it reverses when blocked too long.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cadsim import portable_math as pm
from cadsim.world import wrap_angle


@dataclass(frozen=True)
class MotionParams:
    """dt: step, seconds. clearance: minimum gap between discs, metres. waypoint_tolerance: metres.
    max_blocked_steps: blocked steps before a new waypoint / a reversed ring direction.
    yaw_rate: radians/s for robots and the observer; person_yaw_rate: radians/s for people.
    look_jitter: radians, the observer's look offset range (±). look_hold: mean seconds between
    look-offset redraws."""

    dt: float = 0.1
    clearance: float = 0.15
    waypoint_tolerance: float = 0.1
    max_blocked_steps: int = 20
    yaw_rate: float = np.pi / 2.0
    person_yaw_rate: float = 2.0 * np.pi
    look_jitter: float = np.radians(20.0)
    look_hold: float = 6.0


def sample_free_positions(
    rng: np.random.Generator,
    radii: np.ndarray,
    half_extent: np.ndarray,
    clearance: float,
    fixed_xy: np.ndarray | None = None,
    fixed_radii: np.ndarray | None = None,
    tries: int = 512,
) -> np.ndarray:
    """Place discs of ``radii`` (k,) one after the other, uniformly inside the box
    [-half_extent, half_extent] (2,) shrunk by each radius, so that no two discs (nor a disc and a
    ``fixed`` one) come closer than ``clearance``. Returns (k, 2) metres; raises ValueError when the
    arena is too crowded to place a disc in ``tries`` draws."""
    placed_xy = np.zeros((0, 2)) if fixed_xy is None else np.asarray(fixed_xy, float).reshape(-1, 2)
    placed_r = np.zeros(0) if fixed_radii is None else np.asarray(fixed_radii, float).reshape(-1)
    out = np.empty((len(radii), 2))
    for k, r in enumerate(np.asarray(radii, float)):
        lim = np.asarray(half_extent, float) - r
        if np.any(lim <= 0):
            raise ValueError(f"an object of radius {r:.2f} m does not fit in the arena")
        cand = rng.uniform(-lim, lim, size=(tries, 2))
        gap = np.linalg.norm(cand[:, None, :] - placed_xy[None, :, :], axis=2) - placed_r - r
        ok = np.all(gap >= clearance, axis=1)
        if not ok.any():
            raise ValueError(
                f"arena too crowded: could not place object {k} (radius {r:.2f} m) "
                f"after {tries} draws; enlarge [traffic] size or lower the counts"
            )
        out[k] = cand[np.argmax(ok)]
        placed_xy = np.vstack([placed_xy, out[k]])
        placed_r = np.append(placed_r, r)
    return out


class ArenaMotion:
    """State and stepping of all movers. Mover order is fixed at construction; ``ring`` marks the
    movers driven by the ring controller (the others follow waypoints).

    pos (n, 2) metres, yaw (n,) radians, radius (n,) metres, speed (n,) m/s (for ring movers the
    speed along the ellipse), yaw_rate (n,) radians/s. Static obstacles: static_xy (s, 2),
    static_radius (s,). The arena is the box [-half_extent, half_extent] around the origin.
    ring_axes (2,): semi-axes of the observer's ellipse, metres.
    """

    def __init__(
        self,
        rng: np.random.Generator,
        params: MotionParams,
        half_extent: np.ndarray,
        pos: np.ndarray,
        yaw: np.ndarray,
        radius: np.ndarray,
        speed: np.ndarray,
        yaw_rate: np.ndarray,
        ring: np.ndarray,
        ring_axes: np.ndarray,
        static_xy: np.ndarray,
        static_radius: np.ndarray,
    ) -> None:
        self.rng = rng
        self.p = params
        self.half = np.asarray(half_extent, float)
        self.pos = np.array(pos, float).reshape(-1, 2)
        self.yaw = np.array(yaw, float)
        self.radius = np.asarray(radius, float)
        self.speed = np.asarray(speed, float)
        self.yaw_rate = np.asarray(yaw_rate, float)
        self.ring = np.asarray(ring, bool)
        self.ring_axes = np.asarray(ring_axes, float)
        self.static_xy = np.asarray(static_xy, float).reshape(-1, 2)
        self.static_radius = np.asarray(static_radius, float)
        n = len(self.pos)
        self.blocked = np.zeros(n, int)
        self.velocity = np.zeros((n, 2))  # m/s over the last step (a backward difference)
        self.waypoint = self.pos.copy()
        self.time = 0.0
        # Ring movers: parameter angle on the ellipse, direction of travel, look offset.
        self.ring_phase = pm.arctan2(
            self.pos[:, 1] / max(self.ring_axes[1], 1e-9),
            self.pos[:, 0] / max(self.ring_axes[0], 1e-9),
        )
        self.ring_dir = np.where(rng.random(n) < 0.5, -1.0, 1.0)
        self.look_offset = rng.uniform(-params.look_jitter, params.look_jitter, n)
        self._new_waypoints(~self.ring)
        self.yaw[self.ring] = self._ring_facing()[self.ring]

    # -- waypoints -------------------------------------------------------------------------------
    def _new_waypoints(self, which: np.ndarray, tries: int = 64) -> None:
        """Draw a waypoint for every mover in the boolean mask ``which``: uniform in the arena,
        clear of static obstacles, and with the first stretch of the straight path towards it
        (probes at 1, 2 and 3 radii ahead) clear of the other movers' current discs, so a blocked
        mover turns away from whatever blocks it. A mover with no valid draw waits in place."""
        idx = np.flatnonzero(which)
        if idx.size == 0:
            return
        r = self.radius[idx]
        lim = self.half[None, :] - r[:, None]
        cand = self.rng.uniform(-1.0, 1.0, size=(idx.size, tries, 2)) * lim[:, None, :]
        gap = (
            np.linalg.norm(cand[:, :, None, :] - self.static_xy[None, None, :, :], axis=3)
            - self.static_radius[None, None, :]
            - r[:, None, None]
        )
        ok = np.all(gap >= self.p.clearance, axis=2)
        # Probe points along the path: (mover, try, probe, 2).
        delta = cand - self.pos[idx, None, :]
        dist = np.linalg.norm(delta, axis=2, keepdims=True)
        unit = delta / np.maximum(dist, 1e-9)
        ahead = np.minimum(r[:, None, None] * np.array([1.0, 2.0, 3.0])[None, None, :], dist)
        probes = self.pos[idx, None, None, :] + ahead[..., None] * unit[:, :, None, :]
        d = np.linalg.norm(probes[:, :, :, None, :] - self.pos[None, None, None, :, :], axis=4)
        need = r[:, None] + self.radius[None, :] + self.p.clearance  # (mover, other)
        others = idx[:, None] != np.arange(len(self.pos))[None, :]
        hit = (d < need[:, None, None, :]) & others[:, None, None, :]
        ok &= ~hit.any(axis=(2, 3))
        first = np.argmax(ok, axis=1)
        chosen = cand[np.arange(idx.size), first]
        self.waypoint[idx] = np.where(ok.any(axis=1)[:, None], chosen, self.pos[idx])

    # -- ring controller -------------------------------------------------------------------------
    def _ring_point(self, phase: np.ndarray) -> np.ndarray:
        return np.column_stack(
            [self.ring_axes[0] * np.cos(phase), self.ring_axes[1] * np.sin(phase)]
        )

    def _ring_facing(self) -> np.ndarray:
        """Yaw that points a ring mover at the arena centre, plus its look offset."""
        return wrap_angle(pm.arctan2(-self.pos[:, 1], -self.pos[:, 0]) + self.look_offset)

    def _ring_phase_rate(self) -> np.ndarray:
        """dphase/dt that moves a ring mover at ``speed`` m/s along the ellipse."""
        a, b = self.ring_axes
        ds = np.hypot(a * np.sin(self.ring_phase), b * np.cos(self.ring_phase))
        return self.ring_dir * self.speed / np.maximum(ds, 1e-6)

    # -- stepping --------------------------------------------------------------------------------
    def step(self) -> None:
        """Advance every mover by ``dt`` seconds."""
        dt, p = self.p.dt, self.p
        wp = ~self.ring
        proposal = self.pos.copy()

        # Waypoint movers: turn at a bounded rate, drive forward when roughly facing the waypoint.
        to_wp = self.waypoint - self.pos
        dist = np.linalg.norm(to_wp, axis=1)
        err = wrap_angle(pm.arctan2(to_wp[:, 1], to_wp[:, 0]) - self.yaw)
        err = np.where(dist > 1e-9, err, 0.0)
        turn = np.clip(err, -self.yaw_rate * dt, self.yaw_rate * dt)
        new_yaw = np.where(wp, wrap_angle(self.yaw + turn), self.yaw)
        stride = np.minimum(self.speed * dt * np.maximum(np.cos(err - turn), 0.0), dist)
        step_xy = stride[:, None] * np.column_stack([np.cos(new_yaw), np.sin(new_yaw)])
        proposal[wp] = self.pos[wp] + step_xy[wp]

        # Ring movers: advance along the ellipse, keep facing the centre (plus look offset).
        new_phase = self.ring_phase + self._ring_phase_rate() * dt
        proposal[self.ring] = self._ring_point(new_phase)[self.ring]

        moved = self._accept(proposal)
        before = self.pos
        self.pos = np.where(moved[:, None], proposal, self.pos)
        self.velocity = (self.pos - before) / dt
        self.yaw = new_yaw
        self.ring_phase = np.where(self.ring & moved, new_phase, self.ring_phase)
        redraw = self.rng.random(len(self.pos)) < dt / p.look_hold
        self.look_offset = np.where(
            redraw, self.rng.uniform(-p.look_jitter, p.look_jitter, len(self.pos)), self.look_offset
        )
        ring_yaw = self._ring_facing()
        turn_r = np.clip(wrap_angle(ring_yaw - self.yaw), -self.yaw_rate * dt, self.yaw_rate * dt)
        self.yaw = np.where(self.ring, wrap_angle(self.yaw + turn_r), self.yaw)

        self.blocked = np.where(moved, 0, self.blocked + 1)
        stuck = self.blocked >= p.max_blocked_steps
        self.ring_dir = np.where(self.ring & stuck, -self.ring_dir, self.ring_dir)
        arrived = np.linalg.norm(self.waypoint - self.pos, axis=1) <= p.waypoint_tolerance
        self._new_waypoints(wp & (arrived | stuck))
        self.blocked[stuck] = 0
        self.time += dt

    def _accept(self, proposal: np.ndarray) -> np.ndarray:
        """Which proposals keep every pair of discs ``clearance`` apart. A proposal is checked
        against the other movers' current AND proposed positions (whichever they end up at), the
        static obstacles and the arena bounds; staying put is always safe."""
        n = len(self.pos)
        need = self.radius[:, None] + self.radius[None, :] + self.p.clearance
        off_diag = ~np.eye(n, dtype=bool)
        d_prop = np.linalg.norm(proposal[:, None] - proposal[None, :], axis=2)
        d_cur = np.linalg.norm(proposal[:, None] - self.pos[None, :], axis=2)
        hit = ((d_prop < need) | (d_cur < need)) & off_diag
        d_static = np.linalg.norm(proposal[:, None] - self.static_xy[None, :], axis=2)
        hit_static = (
            d_static < self.radius[:, None] + self.static_radius[None, :] + self.p.clearance
        )
        inside = np.all(np.abs(proposal) <= self.half - self.radius[:, None], axis=1)
        return ~hit.any(axis=1) & ~hit_static.any(axis=1) & inside

    def advance(self, seconds: float) -> None:
        """Step until ``seconds`` more simulated time has passed."""
        for _ in range(int(round(seconds / self.p.dt))):
            self.step()
