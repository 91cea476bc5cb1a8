"""highway-env's intersection as a traffic source (``[traffic] source = "highway-env"``).

One seeded run: the environment is reset with seeds drawn from the source's seed, the controlled
vehicle acts by a seeded random policy, and whenever an env episode ends (crash, arrival, time
limit) the environment is reset with the next seed; vehicle ids keep counting across resets.
highway-env runs headless (``SDL_VIDEODRIVER=dummy`` unless set) and renders nothing.

Per snapshot: every vehicle as a 3-D object (id from ``cadsim.sources.highway.tracker``; kind, size and
colour drawn once per vehicle, ``cadsim.sources.highway.appearance``; position and yaw converted once by
``cadsim.sources.highway.frames``), then the static scene of ``cadsim.sources.highway.static_scene``. Snapshot
meta: ``episode`` (env reset count), ``step`` (env steps since that reset), ``controlled`` (ids of
the policy-driven vehicles) and ``approaches`` (``id -> {"junction", "arm", "edge", "distance"}``
for vehicles on incoming lanes, distance in metres before the stop line; ``cadsim.sources.observer_pairs``
turns it into observer pairs, as for SUMO).
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from cadsim import portable_math
from cadsim.scenario import Scenario, ScenarioError
from cadsim.sources.base import ObserverPair, TrafficSource
from cadsim.sources.highway.appearance import Appearance, AppearanceSampler
from cadsim.sources.highway.config import (
    JUNCTION_ID,
    HighwayConfig,
    check_env_overrides,
    highway_config,
    steps_for,
)
from cadsim.sources.highway.frames import highway_direction_to_world, highway_to_world
from cadsim.sources.highway.geometry import JunctionLayout, incoming_arm, read_layout
from cadsim.sources.highway.static_scene import static_scene
from cadsim.sources.highway.tracker import VehicleTracker
from cadsim.sources.observer_pairs import observer_pairs
from cadsim.world import Snapshot, WorldObject

log = logging.getLogger(__name__)

# Streams of the source's SeedSequence: one per independent random use.
_STREAM_EPISODES, _STREAM_POLICY, _STREAM_APPEARANCE, _STREAM_STATIC = range(4)


def import_highway_env():
    """Import gymnasium and highway_env headless and quietly; returns the gymnasium module."""
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    import gymnasium
    import highway_env  # noqa: F401 - registers the environments

    return gymnasium


def _env_class(gymnasium, config: HighwayConfig):
    """The environment class registered as ``config.env_id``; it must be an intersection env."""
    try:
        spec = gymnasium.spec(config.env_id)
    except gymnasium.error.Error as exc:
        raise ScenarioError(
            config.path, "traffic.env_id", str(exc), "a registered highway-env id"
        ) from None
    from gymnasium.envs.registration import load_env_creator
    from highway_env.envs.intersection_env import IntersectionEnv

    cls = load_env_creator(spec.entry_point)
    if not (isinstance(cls, type) and issubclass(cls, IntersectionEnv)):
        raise ScenarioError(
            config.path, "traffic.env_id", f"{config.env_id!r} is not an intersection environment",
            "a highway-env intersection environment such as 'intersection-v2'",
        )  # fmt: skip
    return cls


class HighwaySource(TrafficSource):
    """Seeded highway-env intersection behind the ``TrafficSource`` interface.

    config: the source's settings (``cadsim.sources.highway.config.highway_config(scenario)``);
    seed: the simulation seed."""

    def __init__(self, config: HighwayConfig, seed: int) -> None:
        self.config = config
        self.seed = int(seed)
        self._env = None
        self.layout: JunctionLayout | None = None

    # -- lifecycle ---------------------------------------------------------------------------
    def start(self) -> None:
        cfg = self.config
        gymnasium = import_highway_env()
        cls = _env_class(gymnasium, cfg)
        check_env_overrides(cfg, cls.default_config())
        self._env = gymnasium.make(cfg.env_id, config=dict(cfg.env), disable_env_checker=True)
        # highway-env's kinematics call numpy's arctan/tan/…, whose last bits depend on the CPU's
        # SIMD dispatch; its modules get the C-library versions so the dataset does not.
        portable_math.use_portable_math_in("highway_env")
        try:
            self._prepare()
        except BaseException:
            self.close()
            raise

    def _prepare(self) -> None:
        """Check the made env against the scenario, seed the streams, reset, build the scene."""
        cfg = self.config
        if getattr(self._env.action_space, "n", None) != len(cfg.policy_weights):
            raise ScenarioError(
                cfg.path, "traffic.env.action", f"gives the action space {self._env.action_space}",
                "highway-env's longitudinal DiscreteMetaAction (SLOWER, IDLE, FASTER)",
            )  # fmt: skip
        env_cfg = self._env.unwrapped.config
        sim_hz, policy_hz = env_cfg["simulation_frequency"], env_cfg["policy_frequency"]
        if sim_hz % policy_hz:
            # highway-env simulates floor(sim/policy) ticks per step but advances its clock by
            # 1/policy: snapshot times would drift from the simulated time.
            raise ScenarioError(
                cfg.path, "traffic.env.simulation_frequency", f"is {sim_hz} Hz",
                f"a multiple of policy_frequency ({policy_hz} Hz)",
            )  # fmt: skip
        step = 1.0 / float(policy_hz)
        self._warm_up_steps = steps_for(cfg, "sampling.warm_up", cfg.warm_up, step, 0)
        self._interval_steps = steps_for(cfg, "sampling.interval", cfg.interval, step, 1)
        seeds = np.random.SeedSequence(self.seed).spawn(4)
        self._episode_rng = np.random.default_rng(seeds[_STREAM_EPISODES])
        self._policy_rng = np.random.default_rng(seeds[_STREAM_POLICY])
        weights = np.asarray(cfg.policy_weights, float)
        self._policy_p = weights / weights.sum()
        self._appearance = AppearanceSampler(
            cfg.kinds, cfg.colors, np.random.default_rng(seeds[_STREAM_APPEARANCE])
        )
        self._tracker = VehicleTracker(prefix="veh")
        self._looks: dict[str, Appearance] = {}
        self._episode = -1
        self._time_offset = 0.0
        self._reset()
        self.layout = read_layout(self._env.unwrapped.road.network)
        self._static = static_scene(
            self.layout, cfg.static, np.random.default_rng(seeds[_STREAM_STATIC])
        )

    def close(self) -> None:
        if self._env is not None:
            self._env.close()
            self._env = None

    # -- simulation ----------------------------------------------------------------------------
    def _reset(self) -> None:
        if self._episode >= 0:
            self._time_offset += float(self._env.unwrapped.time)
        self._episode += 1
        self._steps = 0
        seed = int(self._episode_rng.integers(2**31 - 1))
        log.debug("highway-env episode %d: reset with seed %d", self._episode, seed)
        self._env.reset(seed=seed)

    def _step(self) -> None:
        action = int(self._policy_rng.choice(len(self._policy_p), p=self._policy_p))
        _, _, terminated, truncated, _ = self._env.step(action)
        self._steps += 1
        if terminated or truncated:
            self._reset()

    def snapshots(self) -> Iterator[Snapshot]:
        if self._env is None:
            raise RuntimeError(
                "HighwaySource.snapshots: call start() first (or use `with source:`)"
            )
        cfg = self.config
        for _ in range(self._warm_up_steps):
            self._step()
        for k in range(cfg.max_snapshots):
            if k > 0:
                for _ in range(self._interval_steps):
                    self._step()
            snapshot = self._snapshot(k)
            if cfg.max_time is not None and snapshot.time > cfg.max_time + 1e-9:
                return
            yield snapshot

    def _snapshot(self, index: int) -> Snapshot:
        env = self._env.unwrapped
        vehicles = list(env.road.vehicles)
        update = self._tracker.update(vehicles)
        for vid in update.new:
            self._looks[vid] = self._appearance.draw()
        for vid in update.gone:
            del self._looks[vid]
        objects: list[WorldObject] = []
        approaches: dict[str, dict] = {}
        if vehicles:
            xy, yaw = highway_to_world(
                np.array([v.position for v in vehicles]), np.array([v.heading for v in vehicles])
            )
            velocity = highway_direction_to_world(np.array([v.velocity for v in vehicles]))
            for vid, v, p, a, u in zip(update.ids, vehicles, xy, yaw, velocity, strict=True):
                look = self._looks[vid]
                length, width, height = look.kind.size
                objects.append(
                    WorldObject(
                        id=vid,
                        cls=look.kind.cls,
                        shape=look.kind.shape,
                        center=(float(p[0]), float(p[1]), height / 2.0),
                        yaw=float(a),
                        size=(length, width, height),
                        color=look.color,
                        velocity=(float(u[0]), float(u[1]), 0.0),
                    )
                )
                arm = incoming_arm(v.lane_index)
                if arm is not None:
                    longitudinal = v.lane.local_coordinates(v.position)[0]
                    approaches[vid] = {
                        "junction": JUNCTION_ID,
                        "arm": arm,
                        "edge": f"o{arm}:ir{arm}",
                        "distance": round(float(v.lane.length - longitudinal), 4),
                    }
        ego = {id(v) for v in env.controlled_vehicles}
        controlled = [vid for vid, v in zip(update.ids, vehicles, strict=True) if id(v) in ego]
        meta = {
            "source": "highway-env",
            "seed": self.seed,
            "index": index,
            "episode": self._episode,
            "step": self._steps,
            "controlled": controlled,
            "approaches": approaches,
        }
        return Snapshot(
            time=round(self._time_offset + float(env.time), 6),
            objects=objects + self._static,
            meta=meta,
        )

    # -- observers -----------------------------------------------------------------------------
    def observer_pairs(self, snapshot: Snapshot) -> list[ObserverPair]:
        """The shared rule (``cadsim.sources.observer_pairs``), nearest to the junction first, capped at
        ``max_candidates``."""
        cfg = self.config
        centres = {JUNCTION_ID: self.layout.center} if self.layout is not None else {}
        return observer_pairs(snapshot, cfg.camera, cfg.observers, centres)[: cfg.max_candidates]


def make_highway_source(
    scenario: Scenario, seed: int, workdir: Path | None = None
) -> HighwaySource:
    """Factory for ``cadsim.sources``: the source of a ``source = "highway-env"`` scenario.
    ``workdir`` is unused (highway-env writes no files)."""
    return HighwaySource(highway_config(scenario), seed)
