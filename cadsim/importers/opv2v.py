"""``cadsim import opv2v``: the OPV2V family's labels (OPV2V, V2XSet, V2V4Real, cadsim's own
``export opv2v``) as box-only records: every frame's agents become one record's views.

Layout read (every path confined to the folder given, every yaml through the safe loader,
:mod:`.safe_read`): ``[split/]scenario/<agent id>/<frame>.yaml``, agent ids integers (negative:
infrastructure, as in V2XSet), frames digit names; ``scenario/data_protocol.yaml`` optional.
Per agent and frame:

- ``lidar_pose``: the LiDAR's pose — ``[x, y, z, roll, yaw, pitch]`` (metres, degrees, CARLA's
  left-handed world) or, as V2V4Real gives it, a rotation and translation (``{rotation,
  translation}`` or a 4×4 matrix) in the same axes (:mod:`.carla_frame` converts all of them);
- ``true_ego_pos``: the body's pose (default: the LiDAR's), ``ego_speed`` its speed (km/h; the
  agent becomes an object of the record, so a message latency moves the sender);
  ``predicted_ego_pos``: the pose the
  agent's own localisation reported → the stored localisation prior (each box's world position
  as that pose puts it; stated uncertainty: ``data_protocol.yaml``'s ``prior_sigma_m``, else
  ``--prior-sigma``, else 1 m);
- ``vehicles``: {actor id: {``location``, ``angle`` [roll, yaw, pitch], ``center`` (box centre
  offset in the actor's frame), ``extent`` (half length, width, height), ``speed`` (km/h),
  ``obj_type``, V2V4Real's ``ass_id``}} — the boxes the agent sees; the centre is ``location`` +
  ``center`` added in world axes (OpenCOOD's ``project_world_objects``); ``ass_id`` is the
  cross-agent identity where given (−1: never linked), else actor ids shared across agents are
  the ground truth (V2V4Real's keys are each vehicle's local ids: there a box without
  ``ass_id`` is never linked); a connected agent listed by another is an ordinary object of
  that box.

Files may carry the numpy tags PyYAML's default dumper writes (:mod:`.numpy_yaml`, V2V4Real).

Mapping: a scenario is an episode, its frames the slots (``data_protocol.yaml``'s ``cadsim``
block — written by ``cadsim export opv2v`` — restores the original episode, slot, simulation
seed, time, object and observer ids and the prior's parameters: ``prior_sigma_m``, ``prior_latency_s``
— the other agents' messages that much older, so views 2, 3, … of a record taken with the prior
are moved back along their velocities as the source's evaluation moved them — and the model's
``prior_preset``, ``prior_position_sigma_m``, ``prior_yaw_sigma_deg``, kept in each record's
``meta.prior``); agents are ordered vehicles first (ascending id), then infrastructure (−1, −2,
…); every record has ``agents`` views (default: the fewest agents of any frame, at least 2; a
frame's first ones in that order), so frames with fewer are skipped. Two views: frame pairs,
kept as sequences while a scenario's frames have the same two agents; more: N-view snapshots.
Lost: cameras, point clouds, speeds' directions (taken along the heading), other yaml keys.
"""

from __future__ import annotations

import hashlib
import logging
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cadsim import portable_math as pm
from cadsim.dataset import layout
from cadsim.dataset.box_record import BoxView, box_detections
from cadsim.importers import ImportFormatError
from cadsim.importers.box_dataset import ImportResult, check_out, write_box_dataset
from cadsim.importers.box_sequence import ImportedFrame, sequence_records
from cadsim.importers.carla_frame import carla_matrix, mirrored, mirrored_points
from cadsim.importers.record_time import TimeNote, relative_times
from cadsim.importers.safe_read import (
    confined,
    field,
    matrix,
    number,
    numbers,
    read_bytes,
    read_yaml,
    rigid,
    shown,
)
from cadsim.importers.sensor_frame import (
    apply,
    boxes_in_view,
    heading_of,
    rigid_inverse,
    sensor_camera,
)
from cadsim.observer_pose import ObserverPose
from cadsim.sensing.gnss_error import parse_spec
from cadsim.sensing.latency import sender_offset
from cadsim.world import WorldObject

SCENARIO_NAME = "opv2v"
SOURCE = {
    "kind": "opv2v",
    "repository": "https://github.com/DerrickXuNu/OpenCOOD",
    "commit": "published layout",
    "files": "<scenario>/<agent id>/<frame>.yaml",
    "licence": "the dataset's own terms (not redistributed)",
    "simulator": "CARLA (OPV2V, V2XSet) or real-world recordings (V2V4Real)",
}
DEFAULT_PRIOR_SIGMA_M = 1.0
PROTOCOL = "data_protocol.yaml"
_AGENT = re.compile(r"-?[0-9]{1,9}\Z")  # ASCII digits only, no trailing newline
_FRAME = re.compile(r"[0-9]{1,9}\Z")
_KMH = 1.0 / 3.6
log = logging.getLogger(__name__)
_PRIOR_FRAME = "OPV2V predicted_ego_pos, y negated: right-handed, x and y horizontal, z up, metres"


@dataclass(frozen=True)
class _Agent:
    """One agent's yaml of one frame, read."""

    agent: int
    sensor: np.ndarray  # 4×4 LiDAR → world (right-handed)
    body: np.ndarray  # 4×4 body → world
    predicted: np.ndarray | None  # 4×4 reported body → world
    boxes: list[dict]
    speed: float = 0.0  # ego_speed, m/s
    path: Path | None = None  # the yaml read, for errors


def _pose(value, path: Path, key: str, right_handed: bool = False) -> np.ndarray:
    """4×4 right-handed transform of an OPV2V / V2V4Real pose (module docstring);
    ``right_handed``: a matrix pose is already in a right-handed world (V2V4Real as recorded)."""
    flip = (lambda t: t) if right_handed else mirrored
    if isinstance(value, dict):
        transform = rigid(field(value, "rotation", path, key), field(value, "translation", path, key), path, key)  # fmt: skip
        return flip(transform)
    if isinstance(value, list) and len(value) == 4 and all(isinstance(r, list) for r in value):
        m = matrix(value, path, key, 4, 4)
        if not np.array_equal(m[3], [0.0, 0.0, 0.0, 1.0]):
            raise ImportFormatError(
                path, f"{key}[3]: expected the row [0, 0, 0, 1] of a rigid transform"
            )
        return flip(rigid(m[:3, :3].tolist(), m[:3, 3].tolist(), path, key))
    return flip(carla_matrix(numbers(value, path, key, 6)))


def _boxes(vehicles, path: Path, agent: int = 0, v2v4real: bool = False) -> list[dict]:
    """The boxes of an agent's ``vehicles``: id = ``a<ass_id>`` where the entry has an
    ``ass_id`` ≥ 0 (V2V4Real's cross-vehicle identity), ``<agent>:<actor>`` where it is −1 or,
    in V2V4Real (``v2v4real``), absent (never linked: the key is the agent's local id), else the
    actor id (OPV2V's CARLA actor ids, shared across agents). Two boxes of one agent with one
    id (an ``ass_id`` given twice) are refused."""
    if vehicles is None:
        return []
    if not isinstance(vehicles, dict):
        raise ImportFormatError(path, "vehicles: expected a mapping of actor ids")
    out, seen, ids = [], {}, {}
    for actor, entry in vehicles.items():
        key = (  # a string id quoted, so that '101' and 101 read apart
            f"vehicles.{shown(actor, 20)!r}"
            if isinstance(actor, str)
            else f"vehicles.{shown(actor, 20)}"
        )
        if (
            isinstance(actor, bool)
            or not isinstance(actor, int | str)
            or not _AGENT.match(str(actor))
        ):
            raise ImportFormatError(path, f"{key}: expected an integer actor id (ASCII digits)")
        if seen.setdefault(int(actor), actor) is not actor:
            raise ImportFormatError(
                path, f"{key}: actor {int(actor)} given twice ({seen[int(actor)]!r} and {actor!r})"
            )
        location = numbers(field(entry, "location", path, key), path, f"{key}.location", 3)
        angle = numbers(field(entry, "angle", path, key), path, f"{key}.angle", 3, 1e4)
        center = numbers(entry.get("center", [0.0, 0.0, 0.0]), path, f"{key}.center", 3, 1e3)
        extent = numbers(field(entry, "extent", path, key), path, f"{key}.extent", 3, 1e3)
        if min(extent) <= 0:
            raise ImportFormatError(path, f"{key}.extent: half sizes must be > 0, got {extent}")
        speed = number(entry.get("speed", 0.0), path, f"{key}.speed", 1e4)
        kind = entry.get("obj_type", "car")
        m = carla_matrix([*location, *angle])
        oid = f"{agent}:{int(actor)}" if v2v4real else str(int(actor))  # local without ass_id
        if "ass_id" in entry:
            link = entry["ass_id"]
            if isinstance(link, bool) or not isinstance(link, int) or not -1 <= link < 2**31:
                raise ImportFormatError(
                    path, f"{key}.ass_id: expected an integer >= -1, got {shown(link, 30)}"
                )
            oid = f"{agent}:{int(actor)}" if link == -1 else f"a{link}"
        if oid in ids:
            raise ImportFormatError(
                path, f"{key}: object {oid!r} is also {ids[oid]} (one box per object and agent)"
            )
        ids[oid] = key
        out.append(
            {
                "id": oid,
                "cls": str(kind).lower()[:40] if isinstance(kind, str) else "car",
                "centre": np.add(location, center),  # OpenCOOD: added in world axes
                "direction": m[:3, 0],
                "size": [2.0 * e for e in extent],
                "speed": speed * _KMH,
            }
        )
    return out


def _read_agent(path: Path, agent: int, v2v4real: bool = False) -> _Agent:
    """One agent's yaml; numpy tags (:mod:`.numpy_yaml`) are read in any of the family's
    files; ``v2v4real``: poses in a right-handed world, as V2V4Real records them."""
    data = read_yaml(path, numpy_tags=True)
    if not isinstance(data, dict):
        raise ImportFormatError(path, "top level: expected a mapping")
    sensor = _pose(field(data, "lidar_pose", path), path, "lidar_pose", v2v4real)
    body = (
        _pose(data["true_ego_pos"], path, "true_ego_pos", v2v4real)
        if "true_ego_pos" in data
        else sensor
    )
    predicted = data.get("predicted_ego_pos")
    predicted = None if predicted is None else _pose(predicted, path, "predicted_ego_pos", v2v4real)
    speed = number(data.get("ego_speed", 0.0), path, "ego_speed", 1e4) * _KMH
    boxes = _boxes(data.get("vehicles"), path, agent, v2v4real)
    if v2v4real:  # boxes in the same right-handed world: undo _view's mirroring
        boxes = [b | {"centre": b["centre"] * [1.0, -1.0, 1.0], "direction": b["direction"] * [1.0, -1.0, 1.0]} for b in boxes]  # fmt: skip
    return _Agent(agent, sensor, body, predicted, boxes, speed, path)


def _ordered(agents: list[int]) -> list[int]:
    """Vehicles first (ascending id), then infrastructure (−1, −2, …)."""
    return sorted(agents, key=lambda a: (a < 0, a if a >= 0 else -a))


def _view(
    agent: _Agent, prior: bool, names: dict[str, str], latency_s: float = 0.0
) -> tuple[BoxView, list[WorldObject]]:
    """An agent's box view and its boxes as world objects; ``names``: {actor id: object id}
    (``data_protocol.yaml``'s ``cadsim.ids``; an actor not in it keeps its number);
    ``latency_s`` > 0: the view as the agent's message reports it that many seconds before the
    frame (:mod:`cadsim.sensing.latency`: every box and the agent moved back along their
    velocities, speed along the heading), its stored prior with it."""
    k = len(agent.boxes)
    world = mirrored_points([b["centre"] for b in agent.boxes]).reshape(k, 3)
    directions = mirrored_points([b["direction"] for b in agent.boxes]).reshape(k, 3)
    yaw = heading_of(directions)
    forward = agent.body[:3, 0]
    heading = float(pm.arctan2(forward[1], forward[0]))
    speeds = np.array([b["speed"] for b in agent.boxes], dtype=float)
    velocities = np.stack([speeds * np.cos(yaw), speeds * np.sin(yaw), np.zeros(k)], axis=1)
    own = (agent.speed * np.cos(heading), agent.speed * np.sin(heading), 0.0)
    offset = sender_offset(own, latency_s)  # zero without a latency
    sensor = agent.sensor.copy()
    sensor[:3, 3] += offset
    sent = world - latency_s * velocities  # each box where it was latency_s ago
    camera = sensor_camera(sensor)
    positions, headings = boxes_in_view(camera, sent, directions)
    ids = [names.get(b["id"], b["id"]) for b in agent.boxes]
    classes = [b["cls"] for b in agent.boxes]
    me = names.get(str(agent.agent), str(agent.agent))
    sizes = np.array([b["size"] for b in agent.boxes], dtype=float).reshape(k, 3)
    stored = None
    if prior:  # the reported pose moved with the agent: about its body origin when it sent
        reported = pm.matmul(agent.predicted, rigid_inverse(agent.body))
        stored = apply(reported, sent - offset) + offset
    pose = ObserverPose(tuple(float(v) for v in agent.body[:3, 3]), heading)
    kind = "roadside" if agent.agent < 0 else "vehicle"
    det = box_detections(positions, sizes, headings, ids, classes, world=stored)
    view = BoxView(me, kind, camera, pose, det, sizes)
    objects = [
        WorldObject(i, c, "box", tuple(w), float(y), tuple(s), (0.5, 0.5, 0.5),
                    velocity=(b["speed"] * np.cos(y), b["speed"] * np.sin(y), 0.0))
        for i, c, w, y, s, b in zip(ids, classes, world.tolist(), yaw, sizes.tolist(), agent.boxes, strict=True)
    ]  # fmt: skip
    objects.append(  # the agent itself (the sender of its messages), moving along its heading
        WorldObject(me, "agent", "box", tuple(float(v) for v in agent.body[:3, 3]),
                    heading, (0.1, 0.1, 0.1), (0.5, 0.5, 0.5), target=False,
                    velocity=(agent.speed * np.cos(heading), agent.speed * np.sin(heading), 0.0))
    )  # fmt: skip
    return view, objects


def _protocol(folder: Path, root: Path) -> dict:
    """The ``cadsim`` block of a scenario's ``data_protocol.yaml`` (empty when absent); like
    every file, it must lie inside ``root`` (a link out of it is refused)."""
    path = folder / PROTOCOL
    if not (path.exists() or path.is_symlink()):
        return {}
    path = confined(root, path.relative_to(root).as_posix(), path, PROTOCOL)
    block = read_yaml(path)
    block = block.get("cadsim") if isinstance(block, dict) else None
    if block is None:
        return {}
    out = {}
    for key in ("episode", "slot", "sim_seed"):
        value = field(block, key, path, "cadsim")
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < 2**63:
            raise ImportFormatError(
                path, f"cadsim.{key}: expected an integer >= 0, got {shown(value, 30)}"
            )
        out[key] = value
    for key in ("start_time", "interval_s"):
        if block.get(key) is not None:
            out[key] = number(block[key], path, f"cadsim.{key}", 1e12)
            if key != "start_time" and out[key] <= 0:
                raise ImportFormatError(path, f"cadsim.{key}: expected a number > 0")
    out |= _prior_keys(block, path)
    ids = block.get("ids", {})
    if not isinstance(ids, dict) or not all(
        _AGENT.match(str(k)) and isinstance(v, str) and 0 < len(v) <= 200 for k, v in ids.items()
    ):
        raise ImportFormatError(path, "cadsim.ids: expected {actor id: object id string}")
    names = {str(int(k)): v for k, v in ids.items()}
    if len(set(names.values())) != len(names):
        raise ImportFormatError(path, "cadsim.ids: two actors with one object id")
    return out | ({"ids": names} if names else {})


# data_protocol.yaml's prior keys (docs/external-data.md): name -> (bound, zero allowed, unit)
PRIOR_KEYS = {
    "prior_sigma_m": (1e4, False, "metres"),
    "prior_latency_s": (10.0, True, "seconds"),
    "prior_position_sigma_m": (1e4, True, "metres"),
    "prior_yaw_sigma_deg": (180.0, True, "degrees"),
}


def _prior_keys(block: dict, path: Path) -> dict:
    """The ``prior_*`` keys of a ``cadsim`` block, checked (one line naming file and key)."""
    out = {}
    for key, (bound, zero, unit) in PRIOR_KEYS.items():
        if key not in block:
            continue
        value = block[key]
        ok = isinstance(value, int | float) and not isinstance(value, bool)
        try:
            ok = ok and math.isfinite(value) and (value >= 0 if zero else value > 0)
        except OverflowError:  # an integer beyond float range
            ok = False
        ok = ok and value <= bound
        if not ok:
            least = ">= 0" if zero else "> 0"
            raise ImportFormatError(
                path,
                f"cadsim.{key}: expected a number {least} and <= {bound:g} ({unit}), "
                f"got {str(value)[:40]}",
            )
        out[key] = float(value)
    if "prior_preset" in block:
        preset = block["prior_preset"]
        try:
            if not isinstance(preset, str) or len(preset) > 60:
                raise ValueError
            parse_spec(preset)
        except ValueError:
            raise ImportFormatError(
                path,
                f"cadsim.prior_preset: expected a localisation preset name such as "
                f"gnss-urban, got {str(preset)[:40]}",
            ) from None
        out["prior_preset"] = preset
    return out


def _check_ids(read: list[_Agent], names: dict[str, str], owners: dict[str, str], where: Path):
    """Every object id of a scenario names one actor (agents included): ``cadsim.ids`` may not
    give an actor the number or the name of another. ``owners``: {object id: actor}, so far."""
    for agent in read:
        for actor in (str(agent.agent), *(b["id"] for b in agent.boxes)):
            oid = names.get(actor, actor)
            if owners.setdefault(oid, actor) != actor:
                raise ImportFormatError(
                    where,
                    f"cadsim.ids: actors {owners[oid]} and {actor} would both be object "
                    f"{shown(oid, 40)!r}",
                )


def _scenarios(root: Path) -> list[Path]:
    def agents_of(folder: Path) -> list[Path]:
        return [
            p
            for p in folder.iterdir()
            if p.is_dir() and not p.is_symlink() and _AGENT.match(p.name)
        ]

    if not root.is_dir():
        raise ImportFormatError(root, "not a folder")
    if agents_of(root):
        return [root]
    found = sorted(p for p in root.iterdir() if p.is_dir() and not p.is_symlink() and agents_of(p))
    if not found:
        raise ImportFormatError(root, "no scenario folders (<scenario>/<agent id>/<frame>.yaml)")
    return found


def _frames(scenario: Path) -> dict[str, dict[int, Path]]:
    """{frame name: {agent id: yaml path}}; links are not followed."""
    frames: dict[str, dict[int, Path]] = {}
    spelling: dict[int, str] = {}
    for folder in sorted(scenario.iterdir()):
        if not (folder.is_dir() and not folder.is_symlink() and _AGENT.match(folder.name)):
            continue
        for path in sorted(folder.iterdir()):
            if (
                path.suffix == ".yaml"
                and _FRAME.match(path.stem)
                and path.is_file()
                and not path.is_symlink()
            ):
                # one spelling per frame and agent: 70.yaml beside 000070.yaml, or 3/ beside
                # 03/ (0/ beside -0/), would be one frame or agent read twice
                stem = spelling.setdefault(int(path.stem), path.stem)
                if stem != path.stem:
                    raise ImportFormatError(
                        path,
                        f"frame {int(path.stem)} is also named {stem}.yaml: one name per frame",
                    )
                by_agent = frames.setdefault(stem, {})
                if int(folder.name) in by_agent:
                    other = by_agent[int(folder.name)].parent.name
                    raise ImportFormatError(
                        path, f"agent {int(folder.name)} is also the folder {other}/: one per agent"
                    )
                by_agent[int(folder.name)] = path
    return dict(sorted(frames.items(), key=lambda kv: int(kv[0])))


def _stated_sigmas(protocols: list[dict], given: float | None) -> None:
    """Log where the stored prior's stated uncertainty comes from: one info line when
    ``given`` (``--prior-sigma``) or the default fills scenarios whose ``data_protocol.yaml``
    states none, one warning line when ``given`` overrides values the files state."""
    stated = sorted({p["prior_sigma_m"] for p in protocols if "prior_sigma_m" in p})
    lacking = sum("prior_sigma_m" not in p for p in protocols)
    if given is not None and stated:
        log.warning(
            "prior sigma %g m from the command line (--prior-sigma) overrides the %s m that "
            "data_protocol.yaml states (%d of %d scenarios)",
            given, "/".join(f"{v:g}" for v in stated), len(protocols) - lacking, len(protocols),
        )  # fmt: skip
    if lacking and not (given is not None and stated):
        source = (
            "from the command line (--prior-sigma)"
            if given is not None
            else "the default (set it with --prior-sigma)"
        )
        log.info(
            "prior sigma %g m, %s: data_protocol.yaml states none for %d of %d scenarios",
            DEFAULT_PRIOR_SIGMA_M if given is None else given, source, lacking, len(protocols),
        )  # fmt: skip


def import_opv2v(
    src: str | Path,
    out: str | Path,
    agents: int | None = None,
    prior: bool = True,
    prior_sigma_m: float | None = None,
    v2v4real: bool = False,
) -> ImportResult:
    """Convert the OPV2V-layout folder ``src`` (a split or one scenario) into a box-only dataset
    at ``out`` (a new or empty folder): ``agents`` views per record (default: the fewest of any
    frame); ``prior`` False ignores ``predicted_ego_pos`` (no stored prior: the localisation
    presets can then draw one). The stored prior's stated uncertainty (metres) is
    ``prior_sigma_m`` when given (``--prior-sigma``: it overrides a ``data_protocol.yaml``'s
    ``prior_sigma_m``, with a warning), else the file's, else :data:`DEFAULT_PRIOR_SIGMA_M`;
    an info line says which came from where (:func:`_stated_sigmas`). An agent without
    ``predicted_ego_pos`` gets no stored prior (the others keep theirs; the manifest's
    ``source.agents_without_prior`` and ``cadsim info`` name them). ``v2v4real``: the files'
    poses and boxes are in a right-handed world (V2V4Real as recorded; ``cadsim import
    v2v4real``). ``ImportFormatError``
    (one line naming file and key) for malformed input; nothing is written then.

    >>> import_opv2v("OPV2V/test", "data/opv2v-test")  # doctest: +SKIP
    ImportResult(out=PosixPath('data/opv2v-test'), episodes={0: 147, ...}, views=2, ...)
    """
    if prior_sigma_m is not None and not (
        math.isfinite(prior_sigma_m) and 0 < prior_sigma_m <= PRIOR_KEYS["prior_sigma_m"][0]
    ):
        raise ValueError(
            f"--prior-sigma: expected a finite number in (0, 1e4] metres, got {prior_sigma_m}"
        )
    root, out = Path(src), check_out(out)  # checked before Path("") could become "."
    scenarios = _scenarios(root)
    listing = [(s, _frames(s), _protocol(s, root)) for s in scenarios]
    counts = [len(a) for _, frames, _ in listing for a in frames.values()]
    if not counts or max(counts) < 2:
        raise ImportFormatError(root, "no frame with two or more agents")
    n = agents if agents is not None else max(2, min(c for c in counts if c >= 2))
    if not 2 <= n <= layout.MAX_VIEWS:
        raise ImportFormatError(root, f"agents: expected 2..{layout.MAX_VIEWS}, got {n}")
    pieces = []  # (episode, first slot, sim_seed, interval, frames)
    skipped, stored, files = 0, False, []
    lacking: set[tuple[str, int]] = set()  # (scenario, agent) read without predicted_ego_pos
    next_episode = 0
    for scenario, frames, protocol in listing:
        episode = protocol.get("episode", next_episode)
        next_episode = max(next_episode, episode) + 1
        slot = protocol.get("slot", 0)
        run, chosen_before, owners = [], None, {}
        where = scenario / PROTOCOL
        for name, by_agent in frames.items():
            chosen = _ordered(list(by_agent))[:n]
            if len(chosen) < n:
                skipped += 1
                continue
            read = [_read_agent(by_agent[a], a, v2v4real) for a in chosen]
            _check_ids(read, protocol.get("ids", {}), owners, where)
            files += [by_agent[a] for a in chosen]
            stored = stored or any(a.predicted is not None for a in read)
            lacking |= {(scenario.name, a.agent) for a in read if a.predicted is None}
            if chosen != chosen_before and run:
                pieces.append((episode, slot, protocol, scenario, run))
                slot += len(run)
                run = []
            chosen_before = chosen
            run.append((name, scenario.name, read))
        if run:
            pieces.append((episode, slot, protocol, scenario, run))
    if not pieces:
        raise ImportFormatError(root, f"no frame with {n} agents")
    use_prior = prior and stored
    if use_prior:
        _stated_sigmas([p for _, _, p in listing], prior_sigma_m)
    sequential = n == 2 and any(len(run) > 1 for *_, run in pieces)
    records, clock = [], TimeNote()
    for episode, slot, protocol, scenario_path, run in pieces:
        imported = []
        # the other agents' messages are as old as the exported prior's latency (views 2, 3, …
        # send to view 1); without the prior a preset's redraw applies its own latency
        latency = protocol.get("prior_latency_s", 0.0) if use_prior else 0.0
        sigma = None
        if use_prior:
            sigma = protocol.get("prior_sigma_m", DEFAULT_PRIOR_SIGMA_M)
            sigma = sigma if prior_sigma_m is None else prior_sigma_m
        ids = protocol.get("ids", {})
        for k, (name, scenario_name, read) in enumerate(run):
            views, objects = [], {}
            for v, agent in enumerate(read):
                own = use_prior and agent.predicted is not None  # a prior per agent
                try:
                    view, found = _view(agent, own, ids, latency if v else 0.0)
                except ImportFormatError:
                    raise
                except ValueError as exc:  # a check past the reader's: still name the file
                    raise ImportFormatError(agent.path or root, str(exc)) from None
                views.append(view)
                for obj in found:  # a box (class, size) wins over the agent's own marker
                    if obj.id not in objects or not objects[obj.id].target:
                        objects[obj.id] = obj
            start = protocol.get("start_time")
            time = None if start is None else start + k * protocol.get("interval_s", 0.1)
            meta = {"source": SOURCE["kind"], "scenario": scenario_name, "frame": name}
            meta["agents"] = [a.agent for a in read]
            if use_prior and any(a.predicted is None for a in read):
                meta["agents_without_prior"] = [a.agent for a in read if a.predicted is None]
            if use_prior:
                meta["prior"] = {"stated_sigma_m": sigma, "latency_s": latency} | {
                    key.removeprefix("prior_"): protocol[key]
                    for key in ("prior_preset", "prior_position_sigma_m", "prior_yaw_sigma_deg")
                    if key in protocol
                }
            imported.append(
                ImportedFrame(time, tuple(views), list(objects.values()), meta,
                              sigma, _PRIOR_FRAME if use_prior else "")
            )  # fmt: skip
        imported = relative_times(
            imported, scenario_path / PROTOCOL, f"scenario {run[0][1][:40]!r}", ordered=sequential,
            interval_s=protocol.get("interval_s"), own_clock=True, note=clock,
        )  # fmt: skip
        sim_seed = protocol.get("sim_seed", episode)
        records += sequence_records(
            episode, slot, sim_seed, imported, sequential, protocol.get("interval_s")
        )
    keys = [(r.episode, r.slot) for r in records]
    if len(set(keys)) != len(keys):
        raise ImportFormatError(
            root, "two frames with the same episode and slot (data_protocol.yaml)"
        )
    h = hashlib.sha256()
    for path in files:
        h.update(path.relative_to(root).as_posix().encode() + b"\0")
        h.update(hashlib.sha256(read_bytes(path)).digest())
    source = SOURCE | {"folder": root.name, "agents": n, "skipped_frames": skipped}
    source |= {"prior": "stored" if use_prior else "none", "time": clock.as_manifest()}
    source["sha256"] = h.hexdigest()
    if use_prior and lacking:
        source["agents_without_prior"] = [f"{s}/{a}" for s, a in sorted(lacking)]
    return write_box_dataset(out, records, SCENARIO_NAME, source)


__all__ = ["DEFAULT_PRIOR_SIGMA_M", "import_opv2v"]
