"""The highway-env source's settings, gathered from a validated scenario: its ``[traffic]`` table
(``cadsim.sources.highway.schema``), ``[observers]``, ``[sampling]`` and ``[camera]``.

Metres, seconds. Checks that need the environment itself (its config keys, its step length)
happen when the source starts and raise ``ScenarioError`` naming the file and the dotted key.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from matplotlib.colors import to_rgb

from cadsim.scenario import CameraConfig, Scenario, ScenarioError
from cadsim.sources.highway.appearance import RGB, VehicleKind
from cadsim.sources.highway.static_scene import StaticSceneConfig

#: The one junction of a highway-env intersection, as ``[observers] junctions`` names it.
JUNCTION_ID = "intersection"


@dataclass(frozen=True)
class HighwayConfig:
    """env_id: a registered highway-env intersection environment; env: overrides of its config.
    policy_weights: probabilities of the controlled vehicle's actions (SLOWER, IDLE, FASTER),
    drawn per env step. kinds, colors: vehicle appearance. static: the added road, buildings,
    lights and signs. warm_up / interval / max_time: sampling, simulated seconds (max_time None:
    no limit); max_snapshots: snapshots offered before the source stops. observers: the
    scenario's validated ``[observers]`` table (distances in metres before the stop line);
    max_candidates: observer pairs proposed per snapshot. camera: the scenario's camera;
    path: the scenario file (for error messages)."""

    env_id: str
    env: dict
    policy_weights: tuple[float, ...]
    kinds: tuple[VehicleKind, ...]
    colors: tuple[RGB, ...]
    static: StaticSceneConfig
    warm_up: float
    interval: float
    max_time: float | None
    max_snapshots: int
    observers: dict
    max_candidates: int
    camera: CameraConfig
    path: Path


def _rgb(hex_color: str) -> RGB:
    return tuple(float(c) for c in to_rgb(hex_color))


def highway_config(scenario: Scenario) -> HighwayConfig:
    """Gather the source's settings from a loaded scenario (``source = "highway-env"``)."""
    t, obs, smp = scenario.traffic, scenario.observers, scenario.sampling
    if t.get("source") != "highway-env":
        raise ScenarioError(
            scenario.path, "traffic.source", f"is {t.get('source')!r}", "'highway-env'"
        )
    if obs["junctions"] and JUNCTION_ID not in obs["junctions"]:
        raise ScenarioError(
            scenario.path, "observers.junctions", f"is {obs['junctions']!r}",
            f"[] or [{JUNCTION_ID!r}] (a highway-env intersection has one junction)",
        )  # fmt: skip
    if obs["min_distance"] > obs["max_distance"]:
        raise ScenarioError(
            scenario.path, "observers.min_distance", f"is {obs['min_distance']}",
            f"at most observers.max_distance ({obs['max_distance']})",
        )  # fmt: skip
    s = t["scene"]
    static = StaticSceneConfig(
        building_depth=tuple(s["building_depth"]),
        building_height=tuple(s["building_heights"]),
        building_setback=s["building_setback"],
        building_colors=tuple(_rgb(c) for c in s["building_colors"]),
        curb_offset=s["curb_offset"],
        sign_distance=s["sign_distance"],
    )
    kinds = tuple(
        VehicleKind(
            cls=k["cls"],
            shape=k.get("shape", k["cls"]),
            weight=float(k.get("weight", 1.0)),
            size=tuple(float(v) for v in k["size"]),
        )
        for k in t["kinds"]
    )
    return HighwayConfig(
        env_id=t["env_id"],
        env=dict(t["env"]),
        policy_weights=tuple(t["policy_weights"]),
        kinds=kinds,
        colors=tuple(_rgb(c) for c in t["vehicle_colors"]),
        static=static,
        warm_up=float(smp["warm_up"]),
        interval=float(smp["interval"]),
        max_time=None if smp.get("max_time") is None else float(smp["max_time"]),
        max_snapshots=int(t["max_snapshots"]),
        observers=dict(obs),
        max_candidates=int(t["max_candidates"]),
        camera=scenario.camera,
        path=scenario.path,
    )


def check_env_overrides(config: HighwayConfig, default_config: dict) -> None:
    """Reject ``[traffic.env]`` keys the environment does not know (``default_config``: the env
    class's ``default_config()``)."""
    for key in sorted(config.env):
        if key not in default_config:
            raise ScenarioError(
                config.path, f"traffic.env.{key}", f"unknown config key of {config.env_id}",
                "one of " + ", ".join(sorted(default_config)),
            )  # fmt: skip


def steps_for(config: HighwayConfig, key: str, seconds: float, step: float, minimum: int) -> int:
    """``seconds`` as a whole number (>= minimum) of env steps of ``step`` seconds; ``key`` (e.g.
    "sampling.interval") is named in the error when it is not a multiple of the step."""
    steps = round(seconds / step)
    if abs(steps * step - seconds) > 1e-6 * max(1.0, seconds) or steps < minimum:
        raise ScenarioError(
            config.path, key, f"is {seconds:g} s",
            f"a multiple of the highway-env step ({step:g} s = 1 / policy_frequency)"
            + (f", at least {minimum * step:g} s" if minimum else ""),
        )  # fmt: skip
    return steps
