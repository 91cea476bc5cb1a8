"""The robot-arena traffic source (MRC scenario): look-alike robots, props, and two observers.

World frame as in ``cadsim.world``. One seeded simulation: the layout (``cadsim.sources.arena.layout``),
the motion (``cadsim.sources.arena.motion``) and the overhead-camera candidates (``cadsim.sources.arena.observers``)
all derive from the seed, so the same seed gives the same snapshots and observer pairs. Snapshot k
is taken at ``warm_up + k · interval`` simulated seconds (the scenario's ``[sampling]`` table) up
to ``max_time``; ``snapshot.meta["index"]`` is k.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cadsim.sources.arena.config import ArenaConfig, parse_arena
from cadsim.sources.arena.layout import GROUND_ID, arena_bodies, initial_motion, scenery
from cadsim.sources.arena.observers import overhead_cameras, side_camera
from cadsim.sources.arena.robot_meshes import register_robot_mesh
from cadsim.sources.base import ObserverPair, TrafficSource
from cadsim.world import Snapshot, WorldObject

log = logging.getLogger(__name__)

__all__ = ["GROUND_ID", "ArenaSource", "Schedule", "make_arena_source"]

DEFAULT_MAX_SNAPSHOTS = 250  # when [sampling] sets no max_time (the arena never runs out)
AIM_FRACTION = 0.7  # overhead aim points lie in the arena box scaled by this


@dataclass(frozen=True)
class Schedule:
    """Snapshot times: warm_up + k · interval seconds, k < max_snapshots."""

    warm_up: float = 2.0
    interval: float = 4.0
    max_snapshots: int = DEFAULT_MAX_SNAPSHOTS

    @classmethod
    def from_sampling(cls, sampling: dict) -> Schedule:
        """From a validated ``[sampling]`` table (warm_up, interval, max_time: seconds)."""
        warm_up, interval = float(sampling["warm_up"]), float(sampling["interval"])
        max_time = sampling.get("max_time")
        if max_time is None:
            return cls(warm_up, interval)
        return cls(warm_up, interval, max(0, int(np.floor((max_time - warm_up) / interval)) + 1))


class ArenaSource(TrafficSource):
    """Seeded robot-arena simulation behind the ``TrafficSource`` interface."""

    def __init__(self, config: ArenaConfig, seed: int, schedule: Schedule | None = None) -> None:
        self.config = config
        self.seed = int(seed)
        self.schedule = schedule or Schedule()
        self.half = np.asarray(config.size, float) / 2.0
        self._scenery = scenery(config)

    def snapshots(self) -> Iterator[Snapshot]:
        """Snapshots at ``warm_up + k · interval`` s, k = 0 .. max_snapshots - 1. Every call
        replays the same seeded run from the start."""
        rng = np.random.default_rng(np.random.SeedSequence([self.seed, 0]))
        movers, props = arena_bodies(self.config, rng)
        motion, prop_xy, prop_yaw = initial_motion(self.config, movers, props, rng)
        still = [b.at(xy, yaw) for b, xy, yaw in zip(props, prop_xy, prop_yaw, strict=True)]
        log.debug("arena seed %d: %d movers, %d props", self.seed, len(movers), len(props))
        sched = self.schedule
        motion.advance(sched.warm_up)
        for k in range(sched.max_snapshots):
            if k:
                motion.advance(sched.interval)
            moving: list[WorldObject] = [
                b.at(xy, yaw, v)
                for b, xy, yaw, v in zip(
                    movers, motion.pos, motion.yaw, motion.velocity, strict=True
                )
            ]
            yield Snapshot(
                time=round(motion.time, 6),
                objects=moving + still + self._scenery,
                meta={"index": k},
            )

    def observer_pairs(self, snapshot: Snapshot) -> list[ObserverPair]:
        """The side camera on the ground robot with each of ``candidates`` overhead cameras, in a
        fixed order drawn from (seed, snapshot index)."""
        robot = snapshot.by_id().get(GROUND_ID)
        if robot is None:
            raise ValueError(
                f"snapshot at t={snapshot.time} has no {GROUND_ID!r}: not from the arena"
            )
        index = int(snapshot.meta.get("index", round(snapshot.time * 1000)))
        rng = np.random.default_rng(np.random.SeedSequence([self.seed, 1, index]))
        side = side_camera(robot, self.config.ground)
        # Aim inside the central part of the arena so the overhead view stays over the floor.
        candidates = overhead_cameras(side, self.config.aerial, AIM_FRACTION * self.half, rng)
        return [
            ObserverPair(
                camera1=side,
                camera2=overhead,
                observer1_id=GROUND_ID,
                observer2_id="",
                meta={
                    "candidate": k,
                    "aerial_target": [float(v) for v in target],
                    "views": ["side", "overhead"],
                },
            )  # fmt: skip
            for k, (overhead, target) in enumerate(candidates)
        ]


def make_arena_source(scenario, seed: int, workdir: Path | None = None) -> ArenaSource:
    """Factory for ``cadsim.sources``: the arena of a loaded ``Scenario`` (its ``traffic`` and
    ``sampling`` tables), seeded with ``seed``. ``workdir`` is unused (nothing is written)."""
    register_robot_mesh()
    config = parse_arena(scenario.traffic, scenario.path)
    return ArenaSource(config, seed, Schedule.from_sampling(scenario.sampling))
