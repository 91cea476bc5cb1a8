"""Static objects a highway-env intersection lacks: road surface, corner buildings, a traffic light
and a road sign per approach. World frame (x east, y north, z up, metres; yaw CCW from +x).

highway-env regulates its junction by priorities (the east-west road is major), not by signals.
The added furniture says the same thing: on major arms the light shows green and the sign is a
priority-road sign; on minor arms the light shows amber and the sign is a yield sign. Sizes,
colours and the road's height follow the shared street furniture (``cadsim.sources.street_furniture``) so
both sources look alike to the renderer and the detector.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cadsim import portable_math as pm
from cadsim.sources.highway.geometry import Approach, JunctionLayout
from cadsim.sources.street_furniture import ROAD_COLOR, light_object, sign_object
from cadsim.world import WorldObject

ROAD_TOP = -0.02  # metres: road slabs sit just below z = 0, where vehicles stand
ROAD_THICKNESS = 0.05


@dataclass(frozen=True)
class StaticSceneConfig:
    """Sizes of the added furniture, metres. building_depth / building_height: (low, high) ranges
    sampled per corner; building_setback: gap between the curb and a building's face;
    building_colors: RGB palette in [0, 1]; curb_offset: distance of lights and signs beyond the
    curb; sign_distance: how far before the stop line the sign stands."""

    building_depth: tuple[float, float] = (14.0, 26.0)
    building_height: tuple[float, float] = (6.0, 16.0)
    building_setback: float = 4.0
    building_colors: tuple[tuple[float, float, float], ...] = (
        (0.62, 0.58, 0.52),
        (0.55, 0.55, 0.58),
        (0.70, 0.64, 0.55),
    )
    curb_offset: float = 1.0
    sign_distance: float = 12.0


def _yaw_of(direction: np.ndarray) -> float:
    return float(pm.arctan2(direction[1], direction[0]))


def _stop_line_distance(layout: JunctionLayout, approach: Approach) -> float:
    """Distance [m] from the junction centre to the arm's stop line, along the arm."""
    return float(np.dot(approach.stop_line - layout.center, approach.outward))


def road_surface(layout: JunctionLayout) -> list[WorldObject]:
    """One flat box per arm (both directions' lanes) and one for the junction area."""
    objects = []
    inner = max(_stop_line_distance(layout, a) for a in layout.approaches)
    thickness = ROAD_THICKNESS
    z = ROAD_TOP - thickness / 2.0
    cx, cy = (float(v) for v in layout.center)
    objects.append(
        WorldObject(
            id="road_junction",
            cls="road",
            shape="road",
            center=(cx, cy, z),
            yaw=0.0,
            size=(2.0 * inner, 2.0 * inner, thickness),
            color=ROAD_COLOR,
            target=False,
            variant="junction",
        )
    )
    for a in layout.approaches:
        start = _stop_line_distance(layout, a)
        mid = layout.center + a.outward * (start + a.length / 2.0)
        objects.append(
            WorldObject(
                id=f"road_arm{a.arm}",
                cls="road",
                shape="road",
                center=(float(mid[0]), float(mid[1]), z),
                yaw=_yaw_of(a.outward),
                size=(a.length, 2.0 * layout.road_half_width, thickness),
                color=ROAD_COLOR,
                target=False,
                variant="lane",
            )
        )
    return objects


def corner_buildings(
    layout: JunctionLayout, config: StaticSceneConfig, rng: np.random.Generator
) -> list[WorldObject]:
    """One building block in each corner between two neighbouring arms that meet at about a right
    angle; footprint and height drawn from ``rng``."""
    arms = sorted(layout.approaches, key=lambda a: _yaw_of(a.outward))
    objects = []
    for k, a in enumerate(arms):
        b = arms[(k + 1) % len(arms)]
        if abs(float(np.dot(a.outward, b.outward))) > 0.2:  # not a right-angle corner
            continue
        depth_a, depth_b = rng.uniform(*config.building_depth, size=2)
        height = float(rng.uniform(*config.building_height))
        color = config.building_colors[int(rng.integers(len(config.building_colors)))]
        face = layout.road_half_width + config.building_setback
        corner = layout.center + face * (a.outward + b.outward)
        center = corner + a.outward * depth_a / 2.0 + b.outward * depth_b / 2.0
        objects.append(
            WorldObject(
                id=f"building_{a.arm}_{b.arm}",
                cls="building",
                shape="building",
                center=(float(center[0]), float(center[1]), height / 2.0),
                yaw=_yaw_of(a.outward),
                size=(float(depth_a), float(depth_b), height),
                color=tuple(float(c) for c in color),
                target=False,
            )
        )
    return objects


def _is_major(layout: JunctionLayout, approach: Approach) -> bool:
    return approach.priority == max(a.priority for a in layout.approaches)


def traffic_lights(layout: JunctionLayout, config: StaticSceneConfig) -> list[WorldObject]:
    """A signal on the right-hand curb at each stop line, facing the approaching traffic; green on
    major arms, amber on minor ones (``state`` "G" / "y")."""
    objects = []
    for a in layout.approaches:
        state = "G" if _is_major(layout, a) else "y"
        pos = a.stop_line + a.right * (a.lane_width / 2.0 + config.curb_offset)
        objects.append(light_object(f"tl_arm{a.arm}", pos, _yaw_of(a.outward), state))
    return objects


def road_signs(layout: JunctionLayout, config: StaticSceneConfig) -> list[WorldObject]:
    """A sign on the right-hand curb ``sign_distance`` before each stop line, facing the
    approaching traffic: ``variant`` "priority_road" on major arms, "yield" on minor ones."""
    objects = []
    for a in layout.approaches:
        variant = "priority_road" if _is_major(layout, a) else "yield"
        pos = (
            a.stop_line
            - a.direction * config.sign_distance
            + a.right * (a.lane_width / 2.0 + config.curb_offset)
        )
        objects.append(sign_object(f"sign_arm{a.arm}", variant, pos, _yaw_of(a.outward)))
    return objects


def static_scene(
    layout: JunctionLayout, config: StaticSceneConfig, rng: np.random.Generator
) -> list[WorldObject]:
    """Road surface, corner buildings, traffic lights and signs for one junction."""
    return (
        road_surface(layout)
        + corner_buildings(layout, config, rng)
        + traffic_lights(layout, config)
        + road_signs(layout, config)
    )
