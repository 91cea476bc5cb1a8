"""The robot arena's settings: the schema of ``[traffic]`` with ``source = "arena"``, and its
parsed form.

Units: metres, seconds, degrees in the file. The arena is the box [-size_x/2, size_x/2] ×
[-size_y/2, size_y/2] around the world origin. Validation uses ``cadsim.scenario``'s schema
machinery, so a bad key fails like any other scenario key: ``ScenarioError`` naming the file and
the dotted key (e.g. ``traffic.robots[1].variant``). Importing this module registers the schema.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from matplotlib.colors import to_rgb

from cadsim.limits import MAX_IMAGE_SIDE
from cadsim.scenario import (
    REQUIRED,
    Field,
    ScenarioContext,
    Table,
    register_source_schema,
    validate_table,
)

PROP_CLASSES = ("box", "cone", "person")


@dataclass(frozen=True)
class RobotGroup:
    """``count`` look-alike robots. variant: the marker colour (a matplotlib colour name such as
    "tab:red"); it is the WorldObject's ``variant`` and selects the mesh. body_color: RGB [0, 1].
    size: length, width, height (m). speed: (min, max) m/s, drawn per robot."""

    variant: str
    count: int
    body_color: tuple[float, float, float]
    size: tuple[float, float, float]
    speed: tuple[float, float]


@dataclass(frozen=True)
class PropGroup:
    """``count`` other objects of class ``cls`` ("box", "cone" or "person"): size (m), colour RGB
    [0, 1]. People walk (speed (min, max) m/s); boxes and cones stand still."""

    cls: str
    count: int
    size: tuple[float, float, float]
    color: tuple[float, float, float]
    speed: tuple[float, float]


@dataclass(frozen=True)
class CameraIntrinsics:
    """Image size (pixels) and horizontal field of view (degrees)."""

    width: int
    height: int
    hfov_deg: float


@dataclass(frozen=True)
class GroundObserver:
    """The robot carrying the side camera: one more robot of group ``variant`` that patrols an
    ellipse ``ring_margin`` m inside the walls at ``speed`` m/s, facing the arena centre ±
    ``look_jitter_deg`` (offset redrawn every ``look_hold`` s on average). Its camera sits at the
    robot's front, ``camera_height`` m above the floor, tilted ``pitch_deg`` (negative: down)."""

    variant: str
    camera_height: float
    pitch_deg: float
    ring_margin: float
    speed: float
    look_jitter_deg: float
    look_hold: float
    intrinsics: CameraIntrinsics


@dataclass(frozen=True)
class AerialObserver:
    """The aerial robot's camera, drawn per candidate: ``altitude`` (min, max) m, ``pitch_deg``
    (min, max); its optical axis meets the floor ``lead`` (min, max) m ahead of the side camera and
    ``lateral`` (min, max) m to its left; its heading is the side camera's turned by
    ``relative_yaw_deg`` (min, max). ``candidates``: overhead cameras offered per snapshot."""

    altitude: tuple[float, float]
    pitch_deg: tuple[float, float]
    lead: tuple[float, float]
    lateral: tuple[float, float]
    relative_yaw_deg: tuple[float, float]
    candidates: int
    intrinsics: CameraIntrinsics


@dataclass(frozen=True)
class MotionSettings:
    """dt: step (s). clearance: minimum gap between objects (m). waypoint_tolerance (m).
    max_blocked_steps: steps a robot waits before it picks a new waypoint. yaw_rate_deg: robots'
    turn rate (deg/s)."""

    dt: float
    clearance: float
    waypoint_tolerance: float
    max_blocked_steps: int
    yaw_rate_deg: float


@dataclass(frozen=True)
class ArenaConfig:
    size: tuple[float, float]
    walls: bool
    wall_height: float
    wall_thickness: float
    floor_color: tuple[float, float, float]
    wall_color: tuple[float, float, float]
    robots: tuple[RobotGroup, ...]
    objects: tuple[PropGroup, ...]
    motion: MotionSettings
    ground: GroundObserver
    aerial: AerialObserver

    @property
    def n_robots(self) -> int:
        """Team robots plus the ground observer."""
        return sum(g.count for g in self.robots) + 1


# -- schema ------------------------------------------------------------------------------------
MAX_GROUP = 1000  # robots or objects per group: collision checks grow with their square


def _is_colour_name(v) -> bool:
    try:
        to_rgb(v)
    except (ValueError, TypeError):
        return False
    return True


def _numbers(n: int, default, doc: str, kind: str = "") -> Field:
    """A list of ``n`` numbers; kind "rgb" (each in [0, 1]), "positive" or "range" (min <= max)."""
    checks = {
        "": (lambda v: True, ""),
        "rgb": (lambda v: all(0.0 <= x <= 1.0 for x in v), " in [0, 1] (RGB)"),
        "positive": (lambda v: all(x > 0 for x in v), ", all > 0"),
        "range": (lambda v: v[0] <= v[1], " [min, max] with min <= max"),
    }
    ok, text = checks[kind]
    return Field(
        list, default, doc, item=float, check=lambda v: len(v) == n and ok(v),
        expect=f"a list of {n} numbers{text}",
    )  # fmt: skip


def _colour_name(default, doc: str) -> Field:
    return Field(str, default, doc, check=_is_colour_name, expect="a colour name such as 'tab:red'")


def _intrinsics(hfov: float) -> dict[str, Field]:
    return {
        "width": Field(int, 640, "image width, pixels", ge=16, le=MAX_IMAGE_SIDE),
        "height": Field(int, 480, "image height, pixels", ge=16, le=MAX_IMAGE_SIDE),
        "hfov_deg": Field(float, hfov, "horizontal field of view, degrees", gt=0, le=170),
    }


ROBOT_TABLE = Table(
    {
        "variant": _colour_name(REQUIRED, "marker colour: the only difference between groups"),
        "count": Field(int, REQUIRED, "robots in this group", ge=1, le=MAX_GROUP),
        "body_color": _numbers(3, [0.16, 0.16, 0.18], "body colour", "rgb"),
        "size": _numbers(3, [0.45, 0.38, 0.32], "length, width, height, metres", "positive"),
        "speed": _numbers(2, [0.2, 0.4], "speed range, m/s", "range"),
    }
)
OBJECT_TABLE = Table(
    {
        "cls": Field(str, REQUIRED, "object class", choices=PROP_CLASSES),
        "count": Field(int, REQUIRED, "objects of this kind", ge=0, le=MAX_GROUP),
        "size": _numbers(3, REQUIRED, "length, width, height, metres", "positive"),
        "color": _numbers(3, REQUIRED, "colour", "rgb"),
        "speed": _numbers(2, [0.4, 0.8], "walking speed range of people, m/s", "range"),
    }
)
MOTION_TABLE = Table(
    {
        "dt": Field(float, 0.1, "simulation step, seconds", gt=0, le=10),
        "clearance": Field(float, 0.15, "minimum gap between any two objects, metres", ge=0),
        "waypoint_tolerance": Field(float, 0.1, "waypoint reached within, metres", gt=0),
        "max_blocked_steps": Field(int, 10, "blocked steps before a new waypoint", ge=1),
        "yaw_rate_deg": Field(float, 90.0, "robots' turn rate, degrees/s", gt=0),
    }
)
GROUND_TABLE = Table(
    {
        "variant": _colour_name(REQUIRED, "the robot group the observer looks like"),
        "camera_height": Field(float, 0.35, "side camera height, metres", gt=0),
        "pitch_deg": Field(
            float, -4.0, "side camera tilt, degrees, negative looks down", ge=-60, le=60
        ),
        "ring_margin": Field(float, 0.5, "patrol ellipse inside the walls by, metres", ge=0),
        "speed": Field(float, 0.25, "patrol speed, m/s", gt=0),
        "look_jitter_deg": Field(float, 20.0, "look offset from the arena centre, ± degrees", ge=0),
        "look_hold": Field(float, 6.0, "mean seconds between look-offset changes", gt=0),
        **_intrinsics(60.0),
    }
)
AERIAL_TABLE = Table(
    {
        "altitude": _numbers(2, [3.5, 5.0], "altitude range, metres", "range"),
        "pitch_deg": _numbers(2, [-80.0, -65.0], "pitch range, degrees", "range"),
        "lead": _numbers(
            2, [1.5, 4.0], "footprint centre ahead of the side camera, metres", "range"
        ),
        "lateral": _numbers(2, [-1.5, 1.5], "... and to its left, metres", "range"),
        "relative_yaw_deg": _numbers(
            2, [-180.0, 180.0], "heading relative to the side camera", "range"
        ),
        "candidates": Field(int, 4, "overhead cameras offered per snapshot", ge=1, le=100),
        **_intrinsics(60.0),
    }
)


def _check_arena(out: dict, ctx: ScenarioContext, prefix: str) -> None:
    """Per-item checks of the arrays of tables and the cross-field rules; replaces each array
    item with its validated form."""
    for key, table, least in (("robots", ROBOT_TABLE, 1), ("objects", OBJECT_TABLE, 0)):
        items = out[key]
        if len(items) < least:
            raise ctx.error(
                f"{prefix}.{key}", "is empty", f"at least {least} [[{prefix}.{key}]] table"
            )
        for i, item in enumerate(items):
            if not isinstance(item, dict):
                raise ctx.error(f"{prefix}.{key}[{i}]", f"is {item!r}", "a table")
        out[key] = [
            validate_table(t, table, ctx, f"{prefix}.{key}[{i}]") for i, t in enumerate(items)
        ]
    variants = [g["variant"] for g in out["robots"]]
    if len(set(variants)) != len(variants):
        raise ctx.error(
            f"{prefix}.robots", f"repeats a variant ({variants})", "one group per variant"
        )
    if out["ground_observer"]["variant"] not in variants:
        raise ctx.error(
            f"{prefix}.ground_observer.variant",
            f"is {out['ground_observer']['variant']!r}",
            "the variant of one of the [[traffic.robots]] groups: " + ", ".join(variants),
        )
    pitch = out["aerial_observer"]["pitch_deg"]
    if not (-90.0 <= pitch[0] and pitch[1] < 0.0):
        raise ctx.error(f"{prefix}.aerial_observer.pitch_deg", f"is {pitch}", "angles in [-90, 0)")
    if out["aerial_observer"]["altitude"][0] <= 0:
        raise ctx.error(
            f"{prefix}.aerial_observer.altitude", "is not above the floor", "> 0 metres"
        )
    half = min(out["size"]) / 2.0
    if out["ground_observer"]["ring_margin"] >= half:
        raise ctx.error(
            f"{prefix}.ground_observer.ring_margin", f"is {out['ground_observer']['ring_margin']}",
            f"less than half the arena's smaller side ({half} m)",
        )  # fmt: skip


ARENA_TABLE = Table(
    {
        "size": _numbers(2, [8.0, 6.0], "arena floor, x by y, metres", "positive"),
        "walls": Field(bool, True, "low walls round the arena"),
        "wall_height": Field(float, 0.4, "metres", gt=0),
        "wall_thickness": Field(float, 0.05, "metres", gt=0),
        "floor_color": _numbers(3, [0.55, 0.55, 0.52], "floor colour", "rgb"),
        "wall_color": _numbers(3, [0.82, 0.82, 0.80], "wall colour", "rgb"),
        "robots": Field(list, REQUIRED, "[[traffic.robots]] groups", item=dict),
        "objects": Field(list, [], "[[traffic.objects]] groups", item=dict),
        "motion": MOTION_TABLE,
        "ground_observer": GROUND_TABLE,
        "aerial_observer": AERIAL_TABLE,
    },
    doc="robot arena (MRC scenario)",
    check=_check_arena,
)

register_source_schema("arena", ARENA_TABLE)


def _t(v) -> tuple:
    return tuple(float(x) for x in v)


def parse_arena(traffic: dict, where: str | Path = "<scenario>") -> ArenaConfig:
    """The arena of a ``[traffic]`` table (raw from TOML, or already validated by
    ``load_scenario``); ``where`` names the scenario file in errors (``ScenarioError``)."""
    ctx = ScenarioContext(Path(where))
    if traffic.get("source") != "arena":
        raise ctx.error("traffic.source", f"is {traffic.get('source')!r}", "'arena'")
    t = validate_table(
        {k: v for k, v in traffic.items() if k != "source"}, ARENA_TABLE, ctx, "traffic"
    )
    g, a = dict(t["ground_observer"]), dict(t["aerial_observer"])
    g_cam = CameraIntrinsics(g.pop("width"), g.pop("height"), g.pop("hfov_deg"))
    a_cam = CameraIntrinsics(a.pop("width"), a.pop("height"), a.pop("hfov_deg"))
    return ArenaConfig(
        size=_t(t["size"]),
        walls=t["walls"],
        wall_height=t["wall_height"],
        wall_thickness=t["wall_thickness"],
        floor_color=_t(t["floor_color"]),
        wall_color=_t(t["wall_color"]),
        robots=tuple(
            RobotGroup(r["variant"], r["count"], _t(r["body_color"]), _t(r["size"]), _t(r["speed"]))
            for r in t["robots"]
        ),
        objects=tuple(
            PropGroup(o["cls"], o["count"], _t(o["size"]), _t(o["color"]), _t(o["speed"]))
            for o in t["objects"]
        ),
        motion=MotionSettings(**t["motion"]),
        ground=GroundObserver(intrinsics=g_cam, **g),
        aerial=AerialObserver(
            altitude=_t(a["altitude"]), pitch_deg=_t(a["pitch_deg"]), lead=_t(a["lead"]),
            lateral=_t(a["lateral"]), relative_yaw_deg=_t(a["relative_yaw_deg"]),
            candidates=a["candidates"], intrinsics=a_cam,
        ),
    )  # fmt: skip
