"""The ``[traffic]`` table of ``source = "sumo"`` (documented key by key in docs/scenarios.md).

Exactly one of three ways to get a road network:
  * ``sumocfg``: an existing SUMO scenario (its net, routes and additional files, unedited);
  * ``net`` (+ ``routes``): an existing network and route files, or random demand (``[traffic.demand]``);
  * ``[traffic.network]``: a grid of signalised junctions built with netgenerate at run time
    (one junction = a four-arm intersection), with random demand from ``[traffic.demand]``.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from cadsim.field_checks import hex_color_list, positive_range
from cadsim.limits import MAX_SIMULATED_SECONDS
from cadsim.scenario import Field, ScenarioContext, Table, register_source_schema
from cadsim.sources.sumo.build import BUILTIN_TYPES
from cadsim.sources.sumo.config import SumoConfigError, read_sumocfg
from cadsim.sources.sumo.confinement import ConfinementError, check_loadable
from cadsim.sources.sumo.options import OptionError, check_netgenerate_args, sumocfg_options
from cadsim.sources.sumo.xml_files import parse_xml

HEX_COLOR = "a list of colours written '#rrggbb'"
# Bounds where memory or run time grows with the value (docs/reliability.md).
MAX_GRID_SIDE = 20  # junctions per side: 400 junctions, each with its static scene
MAX_LENGTH_M = 10_000.0
MIN_PERIOD_S = 0.01  # at most 100 departures a second per kind
MAX_TRIPS = 1_000_000  # trips per kind: end / period
MIN_STEP_S = 0.001
PERIOD_OR_OFF = f"0 (none) or a number >= {MIN_PERIOD_S:g} (seconds)"
MIN_CLUTTER_SPACING_M = 10.0  # shortest step 5 m: longer than a trailer (4 m mean), no overlaps
MAX_CLUTTER_OBJECTS = 100_000  # roadside objects drawn per scene: road length / spacing
CLUTTER_SPACING = f"0 (none) or metres in [{MIN_CLUTTER_SPACING_M:g}, {MAX_LENGTH_M:g}]"


def _period_or_off(value: float) -> bool:
    return value == 0 or value >= MIN_PERIOD_S


def _spacing_or_off(value: float) -> bool:
    return value == 0 or MIN_CLUTTER_SPACING_M <= value <= MAX_LENGTH_M


NETWORK = Table(
    {
        "junctions": Field(
            int,
            1,
            "junctions per side of the grid (1: one four-arm intersection)",
            ge=1,
            le=MAX_GRID_SIDE,
        ),
        "block_length": Field(
            float, 200.0, "distance between neighbouring junctions, metres", gt=0, le=MAX_LENGTH_M
        ),
        "arm_length": Field(
            float, 150.0, "length of the roads leaving the grid, metres", gt=0, le=MAX_LENGTH_M
        ),
        "lanes": Field(int, 2, "lanes per direction", ge=1, le=6),
        "speed": Field(float, 13.89, "speed limit, m/s", gt=0, le=100),
        "traffic_lights": Field(bool, True, "signalise the junctions (else priority junctions)"),
        "sidewalks": Field(bool, True, "sidewalks along every road"),
        "sidewalk_width": Field(float, 2.0, "sidewalk width, metres", gt=0, le=20),
        "crossings": Field(bool, True, "pedestrian crossings at the junctions"),
        "extra_args": Field(
            list,
            [],
            "further netgenerate options (allowlisted: those shaping the network, none naming "
            "a file)",
            item=str,
        ),
    },
    when_absent="omit",
)

DEMAND = Table(
    {
        "vtypes": Field(str, doc="vType / vTypeDistribution file", path="file"),
        "vehicle_type": Field(str, "vehicles", "vType or distribution id of motor vehicles"),
        "vehicle_period": Field(
            float, 1.0, "mean seconds between vehicle departures", ge=MIN_PERIOD_S
        ),
        "bicycle_type": Field(str, "bicycles", "vType or distribution id of bicycles"),
        "bicycle_period": Field(
            float,
            8.0,
            "mean seconds between bicycle departures (0: no bicycles)",
            check=_period_or_off,
            expect=PERIOD_OR_OFF,
        ),
        "person_type": Field(str, "persons", "vType or distribution id of pedestrians"),
        "person_period": Field(
            float,
            3.0,
            "mean seconds between pedestrian departures (0: no pedestrians)",
            check=_period_or_off,
            expect=PERIOD_OR_OFF,
        ),
        "end": Field(float, 900.0, "last departure time, seconds", gt=0, le=MAX_SIMULATED_SECONDS),
    },
    when_absent="omit",
)

SCENE = Table(
    {
        "radius": Field(
            float,
            200.0,
            "objects within this distance (m) of an observed junction are kept",
            gt=0,
            le=MAX_LENGTH_M,
        ),
        "road": Field(bool, True, "road surface boxes and a ground plane"),
        "buildings": Field(bool, True, "building blocks between the roads"),
        "building_frontage": Field(float, 18.0, "building length along the street, metres", gt=0),
        "building_depth": Field(float, 14.0, "building depth away from the street, metres", gt=0),
        "building_gap": Field(float, 4.0, "gap between neighbouring buildings, metres", ge=0),
        "building_setback": Field(
            float, 4.0, "clearance between a building and any lane or sidewalk, metres", ge=0
        ),
        "building_heights": Field(
            list,
            [6.0, 20.0],
            "minimum and maximum building height, metres",
            item=float,
            check=positive_range,
            expect="[min, max] with 0 < min <= max (metres)",
        ),
        "building_colors": Field(
            list,
            ["#b8a58c", "#9e9e9e", "#c9c2b2", "#8c5a46", "#d8d8d0", "#6f7a80"],
            "facade colours",
            item=str,
            check=hex_color_list,
            expect=HEX_COLOR,
        ),
        "signs": Field(bool, True, "road signs on the approaches and exits of observed junctions"),
        "sign_distance": Field(float, 20.0, "distance of a sign from the junction, metres", gt=0),
        "traffic_lights": Field(bool, True, "a pole with a signal head per signalised approach"),
        "clutter_spacing": Field(
            float,
            0.0,
            "mean distance between roadside clutter objects (trees, poles, bins, parked "
            "trailers) along each road side, metres (0: none)",
            check=_spacing_or_off,
            expect=CLUTTER_SPACING,
        ),
    }
)


def check_traffic(t: dict, ctx: ScenarioContext, prefix: str) -> None:
    """Cross-key rules: one network source; demand where needed; files inside a sumocfg exist;
    vType ids exist; an existing net has a junction that two vehicles can approach."""
    given = [k for k in ("sumocfg", "net", "network") if t[k] is not None]
    if len(given) != 1:
        problem = "none given" if not given else "several given (" + ", ".join(given) + ")"
        raise ctx.error(
            prefix + ".sumocfg",
            problem,
            "exactly one of traffic.sumocfg, traffic.net or a [traffic.network] table",
        )
    if t["network"] is not None and t["demand"] is None:
        raise ctx.error(
            prefix + ".demand", "missing", "a [traffic.demand] table for a generated network"
        )
    if t["sumocfg"] is not None and t["demand"] is not None:
        raise ctx.error(
            prefix + ".demand", "not allowed with traffic.sumocfg", "demand from the sumocfg itself"
        )
    if t["net"] is not None and t["demand"] is None and not t["routes"]:
        raise ctx.error(
            prefix + ".routes",
            "no routes for traffic.net",
            "route files or a [traffic.demand] table",
        )
    if t["network"] is not None:
        try:
            check_netgenerate_args(t["network"]["extra_args"])
        except OptionError as exc:
            raise ctx.error(
                f"{prefix}.network.extra_args[{exc.index}]",
                str(exc),
                "netgenerate options that shape the network (none that names a file)",
            ) from None
    for key in ("routes", "additional"):
        for i, path in enumerate(t[key]):
            _check_confinable(path, ctx, f"{prefix}.{key}[{i}]")
    if t["demand"] is not None:
        _check_trip_counts(t["demand"], ctx, prefix + ".demand")
        _check_vtypes(t["demand"], ctx, prefix + ".demand")
        _check_confinable(t["demand"]["vtypes"], ctx, prefix + ".demand.vtypes")
    if t["sumocfg"] is not None:
        net = _check_sumocfg(t["sumocfg"], ctx, prefix + ".sumocfg")
        road_m = require_usable_junction(net, ctx, prefix + ".sumocfg")
    elif t["net"] is not None:
        _check_confinable(t["net"], ctx, prefix + ".net")
        road_m = require_usable_junction(t["net"], ctx, prefix + ".net")
    else:
        road_m = _grid_road_m(t["network"])
    _check_clutter_count(t["scene"], road_m, ctx, prefix + ".scene.clutter_spacing")


def _grid_road_m(network: dict) -> float:
    """Road-side length (m) of a generated grid, an upper bound: both sides of its
    2·J·(J − 1) blocks and 4·J arms (junction areas not subtracted)."""
    j = network["junctions"]
    return 2.0 * (2 * j * (j - 1) * network["block_length"] + 4 * j * network["arm_length"])


def _check_clutter_count(scene: dict, road_m: float, ctx: ScenarioContext, key: str) -> None:
    """Roadside clutter is drawn along every road of the network (then kept near the observed
    junctions): road length / spacing objects, at most MAX_CLUTTER_OBJECTS."""
    spacing = scene.get("clutter_spacing", 0.0) if scene else 0.0
    if spacing > 0 and road_m / spacing > MAX_CLUTTER_OBJECTS:
        raise ctx.error(
            key,
            f"is {spacing:g}: about {road_m / spacing:,.0f} clutter objects along "
            f"{road_m / 1000:,.1f} km of road sides",
            f"at most {MAX_CLUTTER_OBJECTS:,} objects (a larger spacing, 0, or a smaller network)",
        )


def _check_sumocfg(path: str, ctx: ScenarioContext, key: str) -> str:
    try:
        cfg = read_sumocfg(path)
    except SumoConfigError as exc:
        raise ctx.error(key, str(exc), "a SUMO configuration (XML)") from None
    if cfg.net is None:
        raise ctx.error(key, f"{path} names no net-file", "a sumocfg with a net-file")
    for p in [cfg.net, *cfg.routes, *cfg.additional]:
        if not p.is_file():
            raise ctx.error(
                key, f"{path} refers to {str(p)!r}, which does not exist", "its input files"
            )
    try:
        sumocfg_options(cfg.options)
    except OptionError as exc:
        raise ctx.error(key, f"{path}: {exc}", "a sumocfg SUMO can run confined") from None
    for p in [cfg.net, *cfg.routes, *cfg.additional]:  # the network can declare outputs too
        _check_confinable(str(p), ctx, key)
    return str(cfg.net)


def _check_confinable(path: str, ctx: ScenarioContext, key: str) -> None:
    try:
        check_loadable(Path(path))
    except ConfinementError as exc:
        raise ctx.error(key, str(exc), "a SUMO XML file without <include>") from None


def _check_trip_counts(demand: dict, ctx: ScenarioContext, key: str) -> None:
    """The demand holds end / period trips per kind: bounded by MAX_TRIPS."""
    for kind in ("vehicle", "bicycle", "person"):
        period, end = demand[f"{kind}_period"], demand["end"]
        if period > 0 and end / period > MAX_TRIPS:
            raise ctx.error(
                f"{key}.{kind}_period",
                f"is {period:g}: {end / period:.0f} trips until end = {end:g} s",
                f"at most {MAX_TRIPS} trips per kind (a longer period or an earlier end)",
            )


def _check_vtypes(demand: dict, ctx: ScenarioContext, key: str) -> None:
    try:
        root = parse_xml(demand["vtypes"]).getroot()
    except (ET.ParseError, OSError) as exc:
        raise ctx.error(
            key + ".vtypes", f"not XML ({exc})", "a SUMO additional file with vTypes"
        ) from None
    ids = {e.get("id") for e in root.iter() if e.tag in ("vType", "vTypeDistribution")}
    ids |= BUILTIN_TYPES
    for name in ("vehicle", "bicycle", "person"):
        type_id = demand[f"{name}_type"]
        if (name == "vehicle" or demand[f"{name}_period"] > 0) and type_id not in ids:
            raise ctx.error(
                f"{key}.{name}_type",
                f"{type_id!r} is not defined in {demand['vtypes']}",
                "one of " + ", ".join(sorted(i for i in ids if i)),
            )


def require_usable_junction(net_path: str, ctx: ScenarioContext, key: str) -> float:
    """Raise unless the net has a junction that two vehicles can approach on different arms;
    returns the length (m) of its road sides (one per normal edge, the clutter's line)."""
    from cadsim.sources.sumo.free_space import right_hand_lanes
    from cadsim.sources.sumo.network import RoadNetwork

    try:
        network = RoadNetwork(net_path)
    except Exception as exc:  # sumolib raises assorted errors on a broken net
        raise ctx.error(
            key, f"cannot read the network {net_path} ({exc})", "a SUMO .net.xml"
        ) from None
    if not network.junction_arms:
        raise ctx.error(
            key,
            f"the network {net_path} has no junction that vehicles can approach on two different arms "
            f"({len(network.net.getNodes())} nodes)",
            "a net with at least one junction joining three or more roads",
        )
    return float(sum(cum[-1] for _, _, cum in right_hand_lanes(network)))


TRAFFIC = Table(
    {
        "sumocfg": Field(str, None, "an existing SUMO configuration", path="file"),
        "net": Field(str, None, "an existing .net.xml", path="file"),
        "routes": Field(
            list, [], "route files (with net; added to a sumocfg's)", item=str, path="files"
        ),
        "additional": Field(
            list, [], "additional files (with net; added to a sumocfg's)", item=str, path="files"
        ),
        "step_length": Field(
            float,
            None,
            "simulation step, seconds (default 0.1; a sumocfg's own)",
            ge=MIN_STEP_S,
            le=10,
        ),
        "vehicle_colors": Field(
            list,
            ["#f0f0f0", "#b4b4b8", "#1e1e1e", "#a01e1e", "#1e3c8c", "#5a5a5a"],
            "colours of vehicles whose route files give none",
            item=str,
            check=hex_color_list,
            expect=HEX_COLOR,
        ),
        "person_colors": Field(
            list,
            ["#303c96", "#963028", "#2d2d2d", "#d2c8b4", "#2d6e3c"],
            "colours of pedestrians whose route files give none",
            item=str,
            check=hex_color_list,
            expect=HEX_COLOR,
        ),
        "network": NETWORK,
        "demand": DEMAND,
        "scene": SCENE,
    },
    check=check_traffic,
)


register_source_schema("sumo", TRAFFIC)
