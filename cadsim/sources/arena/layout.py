"""Who is in the robot arena and where everything starts.

World frame as in ``cadsim.world``; the arena's floor is the box [-size/2, size/2] around the
origin at z = 0. Bodies: the ground observer (id "ground-robot", a robot of its configured group),
the team robots ("robot-01", ...), people ("person-1", ...) -- all movers -- and boxes and cones
("box-1", "cone-1", ...), which stand still. Scenery (non-targets): the floor and four walls.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cadsim.sources.arena.config import ArenaConfig
from cadsim.sources.arena.motion import ArenaMotion, MotionParams, sample_free_positions
from cadsim.world import WorldObject

GROUND_ID = "ground-robot"
_RING_SAMPLES = 180  # points standing in for the observer's patrol ellipse when placing props


@dataclass(frozen=True)
class Body:
    """An arena object's fixed attributes. size: length, width, height (m); color: RGB [0, 1];
    speed: m/s (0 for props that stand still)."""

    id: str
    cls: str
    variant: str
    size: tuple[float, float, float]
    color: tuple[float, float, float]
    speed: float = 0.0

    @property
    def radius(self) -> float:
        """Radius (m) of the disc that holds the length × width footprint."""
        return 0.5 * float(np.hypot(self.size[0], self.size[1]))

    def at(self, xy: np.ndarray, yaw: float, velocity: np.ndarray | None = None) -> WorldObject:
        """The body standing on the floor at ``xy`` (m) with heading ``yaw`` (rad), moving at
        ``velocity`` ((2,) m/s in the floor plane; None: standing still)."""
        vx, vy = (0.0, 0.0) if velocity is None else (float(velocity[0]), float(velocity[1]))
        return WorldObject(
            id=self.id,
            cls=self.cls,
            shape=self.cls,  # robot, box, cone, person: the mesh is named after the class
            center=(float(xy[0]), float(xy[1]), self.size[2] / 2.0),
            yaw=float(yaw),
            size=self.size,
            color=self.color,
            variant=self.variant,
            velocity=(vx, vy, 0.0),
        )


def arena_bodies(config: ArenaConfig, rng: np.random.Generator) -> tuple[list[Body], list[Body]]:
    """(movers, props). Movers: [ground observer, team robots..., people...]; speeds drawn."""
    observer = next(g for g in config.robots if g.variant == config.ground.variant)
    movers = [
        Body(
            GROUND_ID,
            "robot",
            observer.variant,
            observer.size,
            observer.body_color,
            config.ground.speed,
        )
    ]
    for g in config.robots:
        for _ in range(g.count):
            movers.append(
                Body(f"robot-{len(movers):02d}", "robot", g.variant, g.size, g.body_color, rng.uniform(*g.speed))
            )  # fmt: skip
    props: list[Body] = []
    for p in config.objects:
        for k in range(p.count):
            body = Body(f"{p.cls}-{k + 1}", p.cls, "", p.size, p.color)
            if p.cls == "person":
                movers.append(Body(body.id, body.cls, "", p.size, p.color, rng.uniform(*p.speed)))
            else:
                props.append(body)
    return movers, props


def initial_motion(
    config: ArenaConfig, movers: list[Body], props: list[Body], rng: np.random.Generator
) -> tuple[ArenaMotion, np.ndarray, np.ndarray]:
    """Place everything without overlap and return (motion state, prop xy (p, 2), prop yaw (p,)).

    The observer starts at a random point of its patrol ellipse; props keep off that ellipse (so
    the observer can always patrol), the other movers keep off the props and the observer."""
    m = config.motion
    half = np.asarray(config.size, float) / 2.0
    radius = np.array([b.radius for b in movers])
    prop_r = np.array([b.radius for b in props])
    ring_axes = half - config.ground.ring_margin
    t = np.linspace(-np.pi, np.pi, _RING_SAMPLES, endpoint=False)
    ring = ring_axes * np.column_stack([np.cos(t), np.sin(t)])
    phase0 = rng.uniform(-np.pi, np.pi)
    observer_xy = ring_axes * np.array([np.cos(phase0), np.sin(phase0)])
    prop_xy = sample_free_positions(
        rng, prop_r, half, m.clearance, fixed_xy=ring, fixed_radii=np.full(len(ring), radius[0])
    )
    others_xy = sample_free_positions(
        rng,
        radius[1:],
        half,
        m.clearance,
        fixed_xy=np.vstack([prop_xy, observer_xy]),
        fixed_radii=np.append(prop_r, radius[0]),
    )
    params = MotionParams(
        dt=m.dt,
        clearance=m.clearance,
        waypoint_tolerance=m.waypoint_tolerance,
        max_blocked_steps=m.max_blocked_steps,
        yaw_rate=np.radians(m.yaw_rate_deg),
        look_jitter=np.radians(config.ground.look_jitter_deg),
        look_hold=config.ground.look_hold,
    )
    is_person = np.array([b.cls == "person" for b in movers])
    prop_yaw = rng.uniform(-np.pi, np.pi, len(props))
    motion = ArenaMotion(
        rng=rng,
        params=params,
        half_extent=half,
        pos=np.vstack([observer_xy, others_xy]),
        yaw=rng.uniform(-np.pi, np.pi, len(movers)),
        radius=radius,
        speed=np.array([b.speed for b in movers]),
        yaw_rate=np.where(is_person, params.person_yaw_rate, params.yaw_rate),
        ring=np.arange(len(movers)) == 0,
        ring_axes=ring_axes,
        static_xy=prop_xy,
        static_radius=prop_r,
    )
    return motion, prop_xy, prop_yaw


def scenery(config: ArenaConfig) -> list[WorldObject]:
    """Floor and (optionally) walls, non-targets, just outside the arena box."""
    hx, hy = (float(v) / 2.0 for v in config.size)
    t, h = config.wall_thickness, config.wall_height
    floor = WorldObject(
        "floor", "floor", "box", (0.0, 0.0, -0.005), 0.0, (2 * (hx + t), 2 * (hy + t), 0.01),
        config.floor_color, target=False,
    )  # fmt: skip
    if not config.walls:
        return [floor]
    walls = [
        WorldObject(
            f"wall-{name}",
            "wall",
            "box",
            (cx, cy, h / 2),
            yaw,
            (length, t, h),
            config.wall_color,
            target=False,
        )  # fmt: skip
        for name, cx, cy, yaw, length in (
            ("east", hx + t / 2, 0.0, np.pi / 2, 2 * (hy + t)),
            ("west", -hx - t / 2, 0.0, np.pi / 2, 2 * (hy + t)),
            ("north", 0.0, hy + t / 2, 0.0, 2 * hx),
            ("south", 0.0, -hy - t / 2, 0.0, 2 * hx),
        )
    ]
    return [floor, *walls]
