"""Scenario files (TOML): loading and validation.

A scenario file names a traffic source (``[traffic] source = "sumo"``, ...), the cameras, how
observer pairs are chosen, the depth-noise, detection and localisation parameters, the sampling
schedule, the seed and the number of frame pairs. Every key is checked here, once, so that a typo fails at load
time with a message naming the file, the dotted key and what was expected. The file format is
documented in docs/scenarios.md.

Each traffic source kind registers the schema of its ``[traffic]`` table with
:func:`register_source_schema`; the ``[noise]``, ``[detection]`` and ``[localisation]`` tables are
checked against the fields of ``cadsim.sensing.depth_noise.NoiseConfig``,
``cadsim.sensing.detection.DetectionConfig`` and ``cadsim.sensing.localisation.LocalisationConfig``.
"""

from __future__ import annotations

import dataclasses
import difflib
import importlib
import logging
import math
import os
import tomllib
import types
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cadsim.limits import MAX_IMAGE_SIDE, MAX_PAIRS
from cadsim.limits import MAX_PAIRS_PER_EPISODE as MAX_PER_EPISODE
from cadsim.limits import MAX_SIMULATED_SECONDS as MAX_SIM_S
from cadsim.scenario_views import view_count

log = logging.getLogger(__name__)

REQUIRED: Any = type("Required", (), {"__repr__": lambda self: "REQUIRED"})()
"""Default marking a key that must be present."""


class ScenarioError(ValueError):
    """A scenario file is malformed. ``path``: the file; ``key``: dotted key ("traffic.sumocfg");
    the message also says what was found and what was expected."""

    def __init__(self, path: str | Path, key: str, problem: str, expected: str = "") -> None:
        self.path = Path(path)
        self.key = key
        self.problem = problem
        self.expected = expected
        where = f"{self.path}: {key}" if key else str(self.path)
        text = f"{where}: {problem}"
        if expected:
            text += f"; expected {expected}"
        super().__init__(text)

    def __reduce__(self):
        # Raised in worker processes too: pickled with its parts, not just the message.
        return (type(self), (self.path, self.key, self.problem, self.expected))


def unknown_key_problem(key: str, known) -> str:
    """The problem text for an unknown dotted ``key``, with "(did you mean 'x'?)" when one of
    ``known`` is close to its last part."""
    close = difflib.get_close_matches(key.rsplit(".", 1)[-1], [str(k) for k in known], n=1)
    return f"unknown key (did you mean {close[0]!r}?)" if close else "unknown key"


def _one_of(known) -> str:
    return "one of " + ", ".join(sorted(str(k) for k in known))


@dataclass(frozen=True)
class ScenarioContext:
    """Where a table is being validated: the scenario file and the folder relative paths resolve
    against. Schema checks raise ``ctx.error(key, problem, expected)``."""

    path: Path

    @property
    def base_dir(self) -> Path:
        return self.path.parent

    def error(self, key: str, problem: str, expected: str = "") -> ScenarioError:
        return ScenarioError(self.path, key, problem, expected)

    def unknown_key(self, key: str, known) -> ScenarioError:
        """The error for an unknown dotted ``key``, suggesting the closest of ``known``."""
        return ScenarioError(self.path, key, unknown_key_problem(key, known), _one_of(known))

    def resolve(self, value: str) -> Path:
        """A path from the file as an absolute path: ``~`` and environment variables expanded
        (``$SUMO_HOME`` defaults to the installed SUMO), relative paths taken against the
        scenario's folder."""
        if "SUMO_HOME" in value and "SUMO_HOME" not in os.environ:
            _set_sumo_home()
        p = Path(os.path.expandvars(value)).expanduser()
        if "SUMO_HOME" in value and not p.exists():
            # SUMO_HOME may point at a SUMO without tools/ (libsumo's sumo_data, another
            # install): fall back to the eclipse-sumo wheel the project installs.
            wheel = _wheel_sumo_home()
            if wheel is not None:
                alt = Path(value.replace("${SUMO_HOME}", wheel).replace("$SUMO_HOME", wheel))
                p = alt if alt.exists() else p
        return (p if p.is_absolute() else self.base_dir / p).resolve()


@dataclass(frozen=True)
class Field:
    """One key of a table.

    types: the accepted Python type(s) after TOML parsing (an int is accepted where a float is
    expected and converted). default: the value when the key is absent (``REQUIRED``: must be
    given; ``None``: stays None). item: element type for lists. gt/ge/le: numeric bounds.
    choices: allowed values. path: "file" (one existing file) or "files" (a list of them),
    resolved to absolute path strings. check: extra predicate on the converted value.
    expect: how the expectation reads in error messages (derived when empty).
    """

    types: type | tuple[type, ...]
    default: Any = REQUIRED
    doc: str = ""
    item: type | None = None
    gt: float | None = None
    ge: float | None = None
    le: float | None = None
    choices: tuple = ()
    path: str = ""
    check: Callable[[Any], bool] | None = None
    expect: str = ""

    def expectation(self) -> str:
        if self.expect:
            return self.expect
        if self.path == "file":
            return "a path to an existing file (relative to the scenario file's folder)"
        if self.path == "files":
            return "a list of paths to existing files (relative to the scenario file's folder)"
        if self.choices:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        text = " or ".join(_type_name(t) for t in _as_tuple(self.types))
        if self.item is not None:
            text += f" of {_type_name(self.item)}"
        bounds = [f"> {self.gt:g}" if self.gt is not None else ""]
        bounds += [f">= {self.ge:g}" if self.ge is not None else ""]
        bounds += [f"<= {self.le:g}" if self.le is not None else ""]
        bounds = [b for b in bounds if b]
        return text + (" " + " and ".join(bounds) if bounds else "")


@dataclass(frozen=True)
class Table:
    """A TOML table: its fields (a Field or a nested Table per key).

    when_absent: "defaults" (an absent table is filled with its defaults) or "omit" (an absent
    table stays absent / None). check: cross-field validation, called with the validated dict and
    the context, raising ``ctx.error(...)``; it may also add derived entries.
    """

    fields: Mapping[str, Field | Table]
    doc: str = ""
    when_absent: str = "defaults"
    check: Callable[[dict, ScenarioContext, str], None] | None = None


@dataclass(frozen=True)
class CameraConfig:
    """Forward camera of an observer. width/height: pixels. hfov_deg: horizontal field of view,
    degrees. mount_height: metres above the ground, or "roof" (on the carrying vehicle's roof).
    pitch_deg: tilt, degrees, negative looks down."""

    width: int = 640
    height: int = 480
    hfov_deg: float = 90.0
    mount_height: float | str = 1.6
    pitch_deg: float = 0.0


@dataclass(frozen=True)
class Scenario:
    """A validated scenario file. ``text`` is the file's exact contents (for manifests);
    ``traffic`` is the validated [traffic] table with relative paths resolved to absolute;
    ``noise``, ``detection``, ``localisation`` and ``appearance`` are the raw tables (keys
    checked against NoiseConfig / DetectionConfig / LocalisationConfig / AppearanceConfig; an
    empty ``appearance``: no appearance realism); ``observers`` and ``sampling`` have their
    defaults filled in."""

    path: Path
    text: str
    name: str
    seed: int
    pairs: int
    traffic: dict
    camera: CameraConfig
    observers: dict
    noise: dict
    detection: dict
    sampling: dict
    localisation: dict = dataclasses.field(default_factory=dict)
    appearance: dict = dataclasses.field(default_factory=dict)
    sequence: dict | None = None
    sensor: str = "camera"
    lidar: dict = dataclasses.field(default_factory=dict)


def _set_sumo_home() -> None:
    """Importing the eclipse-sumo wheel sets SUMO_HOME (if it is installed)."""
    try:
        import sumo  # noqa: F401
    except ImportError:
        pass


def _wheel_sumo_home() -> str | None:
    """SUMO_HOME of the eclipse-sumo wheel (bin/, tools/, data/), or None if it is not installed."""
    try:
        import sumo
    except ImportError:
        return None
    return str(sumo.SUMO_HOME)


# --------------------------------------------------------------------------------------------
# Schemas of the tables every scenario has.

MAX_DISTANCE_M = 10_000.0  # distances of observers from a junction and from each other
MAX_VEHICLE_OBSERVERS = 8  # OPV2V-style scenes hold up to 7 connected vehicles
MAX_SEQUENCE_FRAMES = 1000  # frames of one [sequence]


def _check_observers(t: dict, ctx: ScenarioContext, prefix: str) -> None:
    if t["min_distance"] > t["max_distance"]:
        raise ctx.error(
            _join(prefix, "min_distance"),
            f"is {t['min_distance']:g}, more than max_distance {t['max_distance']:g}",
            "min_distance <= max_distance",
        )


CAMERA = Table(
    {
        "width": Field(int, 640, "image width, pixels", ge=16, le=MAX_IMAGE_SIDE),
        "height": Field(int, 480, "image height, pixels", ge=16, le=MAX_IMAGE_SIDE),
        "hfov_deg": Field(float, 90.0, "horizontal field of view, degrees", gt=0, le=170),
        "mount_height": Field(
            (float, str),
            1.6,
            'camera height above the ground, metres, or "roof" (the vehicle\'s roof)',
            check=lambda v: v == "roof" if isinstance(v, str) else v > 0,
            expect='a number > 0 (metres) or "roof"',
        ),
        "pitch_deg": Field(float, 0.0, "camera tilt, degrees, negative looks down", ge=-60, le=60),
    }
)

OBSERVERS = Table(
    {
        "max_distance": Field(
            float,
            40.0,
            "an observer is at most this far (metres, along its route) from the junction",
            gt=0,
            le=MAX_DISTANCE_M,
        ),
        "min_distance": Field(
            float,
            0.0,
            "an observer is at least this far (metres) from the junction",
            ge=0,
            le=MAX_DISTANCE_M,
        ),
        "min_separation": Field(
            float,
            5.0,
            "the two observers are at least this far apart (metres)",
            ge=0,
            le=MAX_DISTANCE_M,
        ),
        "classes": Field(
            list,
            ["car", "van", "bus", "truck"],
            "object classes that may carry a camera",
            item=str,
            check=bool,
            expect="a non-empty list of class names",
        ),
        "junctions": Field(
            list, [], "junction ids to observe (empty: every usable junction)", item=str
        ),
        "arm_relations": Field(
            list,
            [],
            'allowed relations of the two observers\' arms by heading difference: "opposite" '
            '(>= 135°), "adjacent" (45°-135°), "parallel" (< 45°); empty: any',
            item=str,
            check=lambda v: (
                len(set(v)) == len(v) and set(v) <= {"opposite", "adjacent", "parallel"}
            ),
            expect='a list of distinct values among "opposite", "adjacent", "parallel"',
        ),
        "aim": Field(
            str,
            "heading",
            'camera yaw: "heading" (along the carrying vehicle) or "junction" (towards the centre '
            "of the junction it approaches)",
            choices=("heading", "junction"),
        ),
        "min_shared_area_m2": Field(
            float,
            0.0,
            "the two cameras' ground footprints (within overlap_range_m) overlap by at least this "
            "area, m² (0: no requirement)",
            ge=0,
        ),
        "overlap_range_m": Field(
            float, 50.0, "range of a camera's ground footprint for min_shared_area_m2, metres", gt=0
        ),
        "count": Field(
            int,
            2,
            "vehicles carrying a camera per snapshot (2: frame pairs; more: N-view snapshot "
            "records, SUMO source only; docs/multi-agent.md)",
            ge=2,
            le=MAX_VEHICLE_OBSERVERS,
        ),
        "roadside_units": Field(
            int,
            0,
            "pole-mounted cameras at the junction's corners with exactly known poses, per "
            "snapshot (SUMO source only; any makes the records N-view)",
            ge=0,
            le=4,
        ),
        "roadside_height_m": Field(
            float, 6.0, "a roadside unit's camera height above the ground, metres", gt=0, le=30
        ),
        "roadside_offset_m": Field(
            float,
            12.0,
            "a roadside unit's distance from the junction centre along the corner's diagonal, "
            "metres",
            gt=0,
            le=200,
        ),
        "roadside_pitch_deg": Field(
            float,
            -15.0,
            "a roadside unit's camera tilt, degrees, negative looks down",
            ge=-60,
            le=0,
        ),
    },
    check=lambda t, ctx, prefix: _check_observers(t, ctx, prefix),
)

SAMPLING = Table(
    {
        "warm_up": Field(
            float, 60.0, "simulated seconds before the first snapshot", ge=0, le=MAX_SIM_S
        ),
        "interval": Field(float, 2.0, "simulated seconds between snapshots", gt=0, le=MAX_SIM_S),
        "pairs_per_snapshot": Field(
            int, 1, "at most this many frame pairs from one snapshot", ge=1, le=MAX_PER_EPISODE
        ),
        "pairs_per_episode": Field(
            int,
            10,
            "frame pairs taken from one simulation before a new one starts",
            ge=1,
            le=MAX_PER_EPISODE,
        ),
        "max_time": Field(
            float,
            None,
            "stop a simulation at this time (s); absent: when its demand ends",
            gt=0,
            le=MAX_SIM_S,
        ),
        "distinct_observers": Field(
            bool, False, "two observer vehicles give at most one frame pair per episode"
        ),
    }
)

SEQUENCE = Table(
    {
        "frames": Field(
            int,
            REQUIRED,
            "frames per sequence: the start frame and its followers",
            ge=1,
            le=MAX_SEQUENCE_FRAMES,
        ),
        "interval_s": Field(
            float,
            REQUIRED,
            "simulated seconds between consecutive frames of a sequence",
            gt=0,
            le=MAX_SIM_S,
        ),
        "min_frames": Field(
            int,
            1,
            "a sequence cut shorter than this (an observer left) is dropped",
            ge=1,
            le=MAX_SEQUENCE_FRAMES,
        ),
        "odometry_scale_sigma": Field(
            float,
            0.01,
            "odometry: per-sequence distance scale error, 1 sigma (0.01: 1 %)",
            ge=0,
            le=1,
        ),
        "odometry_heading_sigma_deg_per_m": Field(
            float,
            0.01,
            "odometry: per-sequence heading drift, 1 sigma, degrees per metre",
            ge=0,
            le=10,
        ),
        "odometry_position_walk": Field(
            float,
            0.02,
            "odometry: random-walk position noise, metres per sqrt(metre)",
            ge=0,
            le=10,
        ),
        "odometry_heading_walk_deg": Field(
            float,
            0.005,
            "odometry: random-walk heading noise, degrees per sqrt(metre)",
            ge=0,
            le=10,
        ),
    },
    doc="consecutive frames of each accepted observer pair (docs/scenarios.md, [sequence])",
    when_absent="omit",
    check=lambda t, ctx, prefix: _check_sequence(t, ctx, prefix),
)


def _check_sequence(t: dict, ctx: ScenarioContext, prefix: str) -> None:
    if t["min_frames"] > t["frames"]:
        raise ctx.error(
            _join(prefix, "min_frames"),
            f"is {t['min_frames']}, more than frames {t['frames']}",
            "min_frames <= frames",
        )


TOP_LEVEL = {
    "name": Field(str, None, "scenario name (default: the file name without .toml)"),
    "description": Field(str, "", "free text"),
    "seed": Field(int, 0, "base seed of every random choice", ge=0),
    "pairs": Field(int, 50, "number of frame pairs in a dataset", ge=1, le=MAX_PAIRS),
    "sensor": Field(
        str,
        "camera",
        "what every observer senses: camera images, a LiDAR ([lidar]) or both",
        choices=("camera", "lidar", "both"),
    ),
}
TABLES = (
    "traffic",
    "camera",
    "observers",
    "noise",
    "detection",
    "sampling",
    "localisation",
    "appearance",
    "sequence",
    "lidar",
)

# kind -> schema of its [traffic] table; kinds listed in _SCHEMA_MODULES register on first use.
_SOURCE_SCHEMAS: dict[str, Table] = {}
_SCHEMA_MODULES: dict[str, str] = {
    "sumo": "cadsim.sources.sumo.schema",
    "arena": "cadsim.sources.arena.config",
    "highway-env": "cadsim.sources.highway.schema",
}

# [noise] / [detection] -> the dataclass whose fields they set.
_CONFIG_CLASSES: dict[str, tuple[str, str]] = {
    "noise": ("cadsim.sensing.depth_noise", "NoiseConfig"),
    "detection": ("cadsim.sensing.detection", "DetectionConfig"),
    "localisation": ("cadsim.sensing.localisation", "LocalisationConfig"),
    "appearance": ("cadsim.render.appearance", "AppearanceConfig"),
    "lidar": ("cadsim.sensing.lidar.beam_pattern", "LidarConfig"),
}


def register_source_schema(kind: str, schema: Table | Mapping[str, Field | Table] | type) -> None:
    """Declare the ``[traffic]`` table of source ``kind``: a :class:`Table`, a mapping of key to
    :class:`Field`/:class:`Table`, or a dataclass whose typed fields are the keys. The ``source``
    key itself is implicit."""
    if isinstance(schema, Table):
        _SOURCE_SCHEMAS[kind] = schema
    elif isinstance(schema, type) and dataclasses.is_dataclass(schema):
        _SOURCE_SCHEMAS[kind] = Table(_fields_of_dataclass(schema))
    elif isinstance(schema, Mapping):
        _SOURCE_SCHEMAS[kind] = Table(dict(schema))
    else:
        raise TypeError(f"schema for source {kind!r} must be a Table, a mapping or a dataclass")


def source_schema(kind: str) -> Table | None:
    """The registered schema of a source kind (importing its module on first use), or None."""
    if kind not in _SOURCE_SCHEMAS and kind in _SCHEMA_MODULES:
        importlib.import_module(_SCHEMA_MODULES[kind])
    return _SOURCE_SCHEMAS.get(kind)


def known_source_kinds() -> list[str]:
    return sorted(set(_SOURCE_SCHEMAS) | set(_SCHEMA_MODULES))


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario file; raise :class:`ScenarioError` on any problem."""
    path = Path(path).expanduser().resolve()
    ctx = ScenarioContext(path)
    if not path.is_file():
        raise ScenarioError(path, "", "scenario file does not exist", "an existing .toml file")
    data = path.read_bytes()
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ScenarioError(
            path,
            "",
            f"not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start})",
            "a TOML file, which is UTF-8",
        ) from None
    try:
        raw = tomllib.loads(text)
        _reject_non_finite(raw, ctx, "")
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(path, "", f"invalid TOML ({exc})", "a TOML document") from None
    except RecursionError:  # arrays or tables nested thousands deep
        raise ScenarioError(
            path, "", "nested too deeply to read", "a scenario file (a few levels of tables)"
        ) from None

    for key in raw:
        if key not in TOP_LEVEL and key not in TABLES:
            raise ctx.unknown_key(key, [*TOP_LEVEL, *TABLES])
    top = validate_table({k: raw[k] for k in TOP_LEVEL if k in raw}, Table(TOP_LEVEL), ctx, "")
    for key in TABLES:
        if key in raw and not isinstance(raw[key], dict):
            raise ctx.error(key, f"is a {_type_name(type(raw[key]))}", "a table")

    traffic = _validate_traffic(raw.get("traffic"), ctx)
    camera = CameraConfig(**validate_table(raw.get("camera", {}), CAMERA, ctx, "camera"))
    observers = validate_table(raw.get("observers", {}), OBSERVERS, ctx, "observers")
    _check_shared_area(observers, camera, ctx)
    if view_count(observers) != 2 and traffic["source"] != "sumo":
        key = "count" if observers["count"] != 2 else "roadside_units"
        raise ctx.error(
            f"observers.{key}",
            f"asks for {view_count(observers)} views per snapshot with source "
            f"{traffic['source']!r}",
            'count = 2 and roadside_units = 0 (N-view snapshots need source = "sumo")',
        )
    sampling = validate_table(raw.get("sampling", {}), SAMPLING, ctx, "sampling")
    sequence = None
    if "sequence" in raw:
        sequence = validate_table(raw["sequence"], SEQUENCE, ctx, "sequence")
        _check_sequence_fits(sequence, traffic, observers, ctx)
    noise = dict(raw.get("noise", {}))
    detection = dict(raw.get("detection", {}))
    localisation = dict(raw.get("localisation", {}))
    appearance = dict(raw.get("appearance", {}))
    lidar = dict(raw.get("lidar", {}))
    _check_sensor(top["sensor"], "lidar" in raw, view_count(observers), sequence, ctx)
    for key, table in (
        ("noise", noise),
        ("detection", detection),
        ("localisation", localisation),
        ("appearance", appearance),
        ("lidar", lidar),
    ):
        config_class = _config_class(key)
        if config_class is not None:
            validate_dataclass_table(table, config_class, ctx, key)

    return Scenario(
        path=path,
        text=text,
        name=top["name"] or path.stem,
        seed=top["seed"],
        pairs=top["pairs"],
        traffic=traffic,
        camera=camera,
        observers=observers,
        noise=noise,
        detection=detection,
        sampling=sampling,
        localisation=localisation,
        appearance=appearance,
        sequence=sequence,
        sensor=top["sensor"],
        lidar=lidar,
    )


def _check_shared_area(observers: dict, camera: CameraConfig, ctx) -> None:
    """``min_shared_area_m2`` no larger than one camera's footprint (its hfov wedge out to
    ``overlap_range_m``): two footprints never share more, so no pair would ever qualify and
    generation would search until its time limit."""
    from cadsim.camera import Camera
    from cadsim.sources.frustum_overlap import ground_footprint, polygon_area

    wanted, reach = observers["min_shared_area_m2"], observers["overlap_range_m"]
    most = polygon_area(
        ground_footprint(Camera((0.0, 0.0, 0.0), 0.0, hfov_deg=camera.hfov_deg), reach)
    )
    if wanted > most:
        raise ctx.error(
            "observers.min_shared_area_m2",
            f"is {wanted:g} m², more than one camera's footprint ({most:.0f} m² for hfov_deg "
            f"{camera.hfov_deg:g} within overlap_range_m {reach:g})",
            f"at most {most:.0f} m² (or a larger overlap_range_m / hfov_deg)",
        )


def _check_sensor(sensor: str, has_lidar: bool, views: int, sequence, ctx) -> None:
    """A ``[lidar]`` table only with a LiDAR (``sensor`` "lidar" or "both"), and LiDAR records
    are frame pairs (two views); a ``[sequence]`` of them only with ``sensor = "lidar"`` (boxes
    and points per frame; "both" is not written as sequences)."""
    if has_lidar and sensor == "camera":
        raise ctx.error(
            "lidar",
            'is given but sensor is "camera"',
            'sensor = "lidar" or "both" (or no [lidar] table)',
        )
    if sensor != "camera" and (views != 2 or (sequence is not None and sensor != "lidar")):
        key = "sequence" if sequence is not None else "observers"
        raise ctx.error(
            key,
            f'is set with sensor = "{sensor}"',
            'frame pairs (LiDAR records are two-view records; sequences with sensor = "lidar")',
        )


def _check_sequence_fits(sequence: dict, traffic: dict, observers: dict, ctx) -> None:
    """A ``[sequence]`` needs frame pairs (two views) and, with SUMO, an ``interval_s`` that is a
    whole number of simulation steps (frames are snapshots of the simulation's steps)."""
    if view_count(observers) != 2:
        raise ctx.error(
            "sequence",
            f"asks for sequences of {view_count(observers)}-view snapshots",
            "no [sequence] table with N-view observers (sequences are of frame pairs)",
        )
    step = traffic.get("step_length") if traffic.get("source") == "sumo" else None
    if step:
        steps = sequence["interval_s"] / step
        if abs(steps - round(steps)) > 1e-6 or round(steps) < 1:
            raise ctx.error(
                "sequence.interval_s",
                f"is {sequence['interval_s']:g}, not a multiple of traffic.step_length {step:g}",
                f"a multiple of {step:g} s (one frame per simulation step or every few steps)",
            )


def _reject_non_finite(value: Any, ctx: ScenarioContext, dotted: str) -> None:
    """TOML allows ``inf`` and ``nan``; no key of a scenario does: raise naming the first."""
    if isinstance(value, float) and not math.isfinite(value):
        raise ctx.error(dotted, f"is {value!r}", "a finite number")
    if isinstance(value, dict):
        for key, item in value.items():
            _reject_non_finite(item, ctx, _join(dotted, key))
    elif isinstance(value, list):
        for i, item in enumerate(value):
            _reject_non_finite(item, ctx, f"{dotted}[{i}]")


def _validate_traffic(raw: Any, ctx: ScenarioContext) -> dict:
    if raw is None:
        raise ctx.error("traffic", "missing", "a [traffic] table with a 'source' key")
    if "source" not in raw:
        raise ctx.error("traffic.source", "missing", "one of " + ", ".join(known_source_kinds()))
    kind = raw["source"]
    schema = source_schema(kind) if isinstance(kind, str) else None
    if schema is None:
        raise ctx.error(
            "traffic.source",
            f"unknown source {kind!r}",
            "one of " + ", ".join(known_source_kinds()),
        )
    body = {k: v for k, v in raw.items() if k != "source"}
    return {"source": kind, **validate_table(body, schema, ctx, "traffic")}


def _config_class(table: str) -> type | None:
    module_name, class_name = _CONFIG_CLASSES[table]
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name != module_name:
            raise
        log.warning("%s is not installed: [%s] is not validated", module_name, table)
        return None
    return getattr(module, class_name)


# --------------------------------------------------------------------------------------------
# Generic validation.


def validate_table(raw: Mapping, schema: Table, ctx: ScenarioContext, prefix: str) -> dict:
    """Check ``raw`` against ``schema``; return a new dict with defaults filled in, ints widened
    to floats where floats are expected and paths resolved. ``prefix``: dotted key of the table."""
    out: dict = {}
    for key in raw:
        if key not in schema.fields:
            raise ctx.unknown_key(_join(prefix, key), schema.fields)
    for key, spec in schema.fields.items():
        dotted = _join(prefix, key)
        if isinstance(spec, Table):
            if key in raw:
                if not isinstance(raw[key], dict):
                    raise ctx.error(dotted, f"is a {_type_name(type(raw[key]))}", "a table")
                out[key] = validate_table(raw[key], spec, ctx, dotted)
            elif spec.when_absent == "defaults":
                out[key] = validate_table({}, spec, ctx, dotted)
            else:
                out[key] = None
            continue
        if key not in raw:
            if spec.default is REQUIRED:
                raise ctx.error(dotted, "missing", spec.expectation())
            out[key] = _copy_default(spec.default)
            continue
        out[key] = _validate_value(raw[key], spec, ctx, dotted)
    if schema.check is not None:
        schema.check(out, ctx, prefix)
    return out


def _validate_value(value: Any, spec: Field, ctx: ScenarioContext, dotted: str) -> Any:
    expected = spec.expectation()
    converted = _convert(value, _as_tuple(spec.types))
    if converted is _MISMATCH:
        raise ctx.error(dotted, f"has the wrong type ({_describe_value(value)})", expected)
    value = converted
    _reject_non_finite(value, ctx, dotted)
    if isinstance(value, list) and spec.item is not None:
        items = [_convert(v, (spec.item,)) for v in value]
        if any(v is _MISMATCH for v in items):
            bad = next(i for i, v in enumerate(items) if v is _MISMATCH)
            raise ctx.error(
                f"{dotted}[{bad}]", f"has the wrong type ({_describe_value(value[bad])})", expected
            )
        value = items
    if spec.choices and value not in spec.choices:
        raise ctx.error(dotted, f"is {value!r}", expected)
    if isinstance(value, int | float) and not isinstance(value, bool):
        out_of_range = (
            (spec.gt is not None and not value > spec.gt)
            or (spec.ge is not None and not value >= spec.ge)
            or (spec.le is not None and not value <= spec.le)
        )
        if out_of_range:
            raise ctx.error(dotted, f"is {value!r}", expected)
    if spec.check is not None and not spec.check(value):
        raise ctx.error(dotted, f"is {value!r}", expected)
    if spec.path == "file":
        value = str(_existing_file(value, ctx, dotted, expected))
    elif spec.path == "files":
        value = [
            str(_existing_file(v, ctx, f"{dotted}[{i}]", expected)) for i, v in enumerate(value)
        ]
    return value


def _existing_file(value: str, ctx: ScenarioContext, dotted: str, expected: str) -> Path:
    p = ctx.resolve(value)
    if not p.is_file():
        raise ctx.error(dotted, f"file {str(p)!r} does not exist", expected)
    return p


_MISMATCH: Any = object()


def _convert(value: Any, accepted: tuple[type, ...]) -> Any:
    """``value`` if it is one of ``accepted`` (bool is not an int; int widens to float), else
    _MISMATCH."""
    for t in accepted:
        if t is bool and isinstance(value, bool):
            return value
        if t is int and isinstance(value, int) and not isinstance(value, bool):
            return value
        if t is float and isinstance(value, int | float) and not isinstance(value, bool):
            return float(value)
        if t not in (bool, int, float) and isinstance(value, t):
            return value
    return _MISMATCH


def validate_dataclass_table(raw: Mapping, cls: type, ctx: ScenarioContext, prefix: str) -> None:
    """Check that every key of ``raw`` is an init field of dataclass ``cls``, that its value
    matches the field's type annotation (int accepted for float; tuple fields accept lists), and
    that ``cls(**raw)`` accepts the values (its own range checks)."""
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    for key, value in raw.items():
        dotted = _join(prefix, key)
        if key not in fields:
            raise ctx.unknown_key(dotted, fields)
        hint = hints.get(key, Any)
        if not _matches(value, hint):
            raise ctx.error(
                dotted, f"has the wrong type ({_describe_value(value)})", _describe_hint(hint)
            )
    try:
        cls(**raw)
    except (TypeError, ValueError) as exc:
        named = [k for k in raw if k in str(exc)]
        key = _join(prefix, named[0]) if len(named) == 1 else prefix
        raise ctx.error(key, f"invalid value: {exc}") from None  # the rule, not the class name


def _fields_of_dataclass(cls: type) -> dict[str, Field]:
    """A Table's fields from a dataclass: each init field's annotation checked by _matches."""
    hints = typing.get_type_hints(cls)
    out = {}
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        if f.default is not dataclasses.MISSING:
            default = f.default
        elif f.default_factory is not dataclasses.MISSING:
            default = f.default_factory()
        else:
            default = REQUIRED
        hint = hints.get(f.name, Any)
        out[f.name] = Field(
            object,
            default,
            check=lambda v, h=hint: _matches(v, h),
            expect=_describe_hint(hint),
        )
    return out


def _matches(value: Any, hint: Any) -> bool:
    """Whether a TOML value fits a type annotation."""
    if hint is Any or hint is object:
        return True
    origin = typing.get_origin(hint)
    args = typing.get_args(hint)
    if origin is typing.Union or origin is types.UnionType:
        return any(_matches(value, a) for a in args)
    if origin is typing.Literal:
        return any(value == a and type(value) is type(a) for a in args)
    if hint is type(None):
        return value is None
    if hint is bool:
        return isinstance(value, bool)
    if hint is int:
        return isinstance(value, int) and not isinstance(value, bool)
    if hint is float:
        return isinstance(value, int | float) and not isinstance(value, bool)
    if origin in (list, tuple, typing.Sequence) or hint in (list, tuple):
        if not isinstance(value, list | tuple):
            return False
        if not args:
            return True
        if origin is tuple and not (len(args) == 2 and args[1] is Ellipsis):
            return len(value) == len(args) and all(
                _matches(v, a) for v, a in zip(value, args, strict=True)
            )
        return all(_matches(v, args[0]) for v in value)
    if origin is dict or hint is dict:
        return isinstance(value, dict)
    if isinstance(hint, type):
        return isinstance(value, hint)
    return True


def _describe_hint(hint: Any) -> str:
    if isinstance(hint, type):
        return hint.__name__
    return str(hint).replace("typing.", "")


def _describe_value(value: Any) -> str:
    return f"{_type_name(type(value))} {value!r}"


def _type_name(t: type) -> str:
    return {
        str: "a string",
        int: "an integer",
        float: "a number",
        bool: "a boolean",
        list: "a list",
        dict: "a table",
    }.get(t, getattr(t, "__name__", str(t)))


def _as_tuple(t: type | tuple[type, ...]) -> tuple[type, ...]:
    return t if isinstance(t, tuple) else (t,)


def _join(prefix: str, key: str) -> str:
    return f"{prefix}.{key}" if prefix else key


def _copy_default(value: Any) -> Any:
    return (
        list(value)
        if isinstance(value, list)
        else dict(value)
        if isinstance(value, dict)
        else value
    )


__all__ = [
    "REQUIRED",
    "CameraConfig",
    "Field",
    "Scenario",
    "ScenarioContext",
    "ScenarioError",
    "Table",
    "load_scenario",
    "register_source_schema",
    "source_schema",
    "validate_dataclass_table",
    "validate_table",
]
