"""``cadsim import tumtraf-v2x``: TUMTraf-V2X's cooperative labels (ASAM OpenLABEL JSON) as
box-only frame pairs: the vehicle's LiDAR view and the infrastructure's, objects linked by the
uid OpenLABEL gives them on both sides.

Read (every file confined to the folder given, through :mod:`.safe_read`): every ``*.json``
under ``SRC`` (sorted by path), each ``{"openlabel": {...}}`` with

- ``coordinate_systems`` (optional): {name: {``type``, ``parent``, ``pose_wrt_parent``:
  {``matrix4x4``: 16 numbers, row-major}}} — used when a frame gives no transform between the
  two sensors: both are chained up to their common root;
- ``objects`` (optional): {uid: {``name``, ``type``}} — a frame object's class when its own
  ``object_data`` has no ``type``;
- ``frames``: {key: {``frame_properties``: {``timestamp`` (seconds, optional), ``transforms``:
  {name: {``src``, ``dst``, ``transform_src_to_dst``: {``matrix4x4``}}}}, ``objects``: {uid:
  {``object_data``: {``type``, ``cuboid``: one cuboid or a list of them}}}}}, a cuboid being
  {``name``, ``val``: [x, y, z, qx, qy, qz, qw, l, w, h] (centre, rotation quaternion scalar
  last, size; metres, in its coordinate system), ``coordinate_system``}.

The two sides are the coordinate systems ``vehicle_cs`` (default ``vehicle_lidar_robosense``)
and ``infrastructure_cs`` (default ``s110_lidar_ouster_south``): a frame object's cuboid in the
vehicle's is a box the vehicle sees (x forward, y left, z up), in the infrastructure's one the
infrastructure sees; an object with a cuboid in both is one object on both sides (the shared
uid is the ground truth); cuboids in any other system are counted in ``meta.other_cuboids``.

Mapping: a file is an episode, its frames (sorted by key, numerically where digits) the slots;
the world is the infrastructure LiDAR's frame (its pose the identity, the vehicle's the
transform vehicle → infrastructure); the vehicle's body is its LiDAR. ``time`` from the frame's
``timestamp``, counted from the file's earliest (:mod:`.record_time`). No localisation prior is
stored: a ``--localisation`` preset draws one. Lost: cameras, point clouds, attributes.
"""

from __future__ import annotations

import hashlib
import math
from pathlib import Path

import numpy as np

from cadsim import portable_math as pm
from cadsim.importers import ImportFormatError
from cadsim.importers.box_dataset import ImportResult, check_out, write_box_dataset
from cadsim.importers.box_sequence import ImportedFrame, sequence_records
from cadsim.importers.dair_side import side_view
from cadsim.importers.record_time import TimeNote, relative_times
from cadsim.importers.safe_read import (
    confined,
    field,
    matrix,
    number,
    numbers,
    read_bytes,
    read_json,
    rigid,
    shown,
)

SCENARIO_NAME = "tumtraf-v2x"
SOURCE = {"kind": "tumtraf-v2x", "format": "ASAM OpenLABEL"}
VEHICLE_CS = "vehicle_lidar_robosense"
INFRASTRUCTURE_CS = "s110_lidar_ouster_south"
MAX_FILES = 100_000
MAX_OBJECTS = 2_000  # per frame
MAX_CHAIN = 32  # coordinate systems between a sensor and the root
QUATERNION_ATOL = 1e-3


def _name(value, path: Path, key: str, limit: int = 128) -> str:
    if not isinstance(value, str) or not value or len(value) > limit:
        raise ImportFormatError(path, f"{key}: expected a name string, got {shown(value, 30)}")
    return value


def _mapping(value, path: Path, key: str) -> dict:
    if not isinstance(value, dict):
        raise ImportFormatError(path, f"{key}: expected a mapping, got {shown(value, 30)}")
    return value


def _matrix4(block, path: Path, key: str) -> np.ndarray:
    """A rigid 4×4 from ``{"matrix4x4": 16 numbers}`` (row-major; nested rows accepted)."""
    values = matrix(field(block, "matrix4x4", path, key), path, f"{key}.matrix4x4", 4, 4)
    if not np.allclose(values[3], [0.0, 0.0, 0.0, 1.0], atol=1e-9):
        raise ImportFormatError(path, f"{key}.matrix4x4: last row must be 0 0 0 1")
    return rigid(values[:3, :3].tolist(), values[:3, 3].tolist(), path, f"{key}.matrix4x4")


def _root_pose(systems: dict, name: str, path: Path) -> tuple[str, np.ndarray]:
    """(root name, 4×4 pose of ``name`` in the root) along ``parent`` / ``pose_wrt_parent``."""
    pose, current, seen = np.eye(4), name, set()
    while True:
        if current in seen or len(seen) > MAX_CHAIN:
            raise ImportFormatError(
                path, f"openlabel.coordinate_systems.{name}: parents form a loop"
            )
        seen.add(current)
        entry = _mapping(field(systems, current, path, "openlabel.coordinate_systems"), path,
                         f"openlabel.coordinate_systems.{current}")  # fmt: skip
        parent = entry.get("parent") or ""
        if not parent:
            return current, pose
        key = f"openlabel.coordinate_systems.{current}.pose_wrt_parent"
        pose = _matrix4(field(entry, "pose_wrt_parent", path, f"openlabel.coordinate_systems.{current}"), path, key) @ pose  # fmt: skip
        current = _name(parent, path, f"openlabel.coordinate_systems.{current}.parent")


def _vehicle_to_infrastructure(frame_props: dict, systems: dict, sides, path: Path, where: str):
    """4×4 vehicle LiDAR → infrastructure LiDAR of one frame (module docstring)."""
    vehicle, infra = sides
    transforms = _mapping(frame_props.get("transforms", {}), path, f"{where}.transforms")
    for name, t in transforms.items():
        key = f"{where}.transforms.{str(name)[:40]}"
        src, dst = field(t, "src", path, key), field(t, "dst", path, key)
        if (src, dst) in ((vehicle, infra), (infra, vehicle)):
            m = _matrix4(field(t, "transform_src_to_dst", path, key), path, f"{key}.transform_src_to_dst")  # fmt: skip
            return m if src == vehicle else np.linalg.inv(m)
    if vehicle in systems and infra in systems:
        root_v, pose_v = _root_pose(systems, vehicle, path)
        root_i, pose_i = _root_pose(systems, infra, path)
        if root_v == root_i:
            return np.linalg.inv(pose_i) @ pose_v
    raise ImportFormatError(
        path,
        f"{where}: no transform between {vehicle!r} and {infra!r} (expected one in "
        "frame_properties.transforms, or both in openlabel.coordinate_systems under one root)",
    )


def _cuboids(data: dict, path: Path, key: str) -> list[dict]:
    cuboid = data.get("cuboid")
    if cuboid is None:
        return []
    items = cuboid if isinstance(cuboid, list) else [cuboid]
    if len(items) > 16:
        raise ImportFormatError(path, f"{key}.cuboid: expected at most 16 cuboids")
    return [_mapping(c, path, f"{key}.cuboid") for c in items]


def _box(cuboid: dict, path: Path, key: str) -> dict:
    """A cuboid as a box: ``centre`` (x, y, z), ``yaw`` (about z, radians), ``size`` (l, w, h)."""
    val = numbers(field(cuboid, "val", path, key), path, f"{key}.val", 10, 1e5)
    qx, qy, qz, qw = val[3:7]
    norm = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    if abs(norm - 1.0) > QUATERNION_ATOL:
        raise ImportFormatError(path, f"{key}.val[3:7]: not a unit quaternion (norm {norm:.6g})")
    qx, qy, qz, qw = (q / norm for q in (qx, qy, qz, qw))
    size = val[7:10]
    if min(size) <= 0 or max(size) > 1e3:
        raise ImportFormatError(path, f"{key}.val[7:10]: sizes must be in (0, 1000] m, got {size}")
    yaw = pm.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
    return {"centre": val[:3], "yaw": float(yaw), "size": size}


def _frame(ol: dict, key: str, frame, sides, path: Path, rel: str) -> ImportedFrame:
    where = f"openlabel.frames.{key[:20]}"
    frame = _mapping(frame, path, where)
    props = _mapping(frame.get("frame_properties", {}), path, f"{where}.frame_properties")
    systems = _mapping(ol.get("coordinate_systems", {}), path, "openlabel.coordinate_systems")
    vehicle_pose = _vehicle_to_infrastructure(props, systems, sides, path, f"{where}.frame_properties")  # fmt: skip
    stamp = props.get("timestamp")
    time = None if stamp is None else number(stamp, path, f"{where}.frame_properties.timestamp", 1e13)  # fmt: skip
    catalogue = _mapping(ol.get("objects", {}), path, "openlabel.objects")
    objects = _mapping(frame.get("objects", {}), path, f"{where}.objects")
    if len(objects) > MAX_OBJECTS:
        raise ImportFormatError(path, f"{where}.objects: {len(objects)} objects, at most {MAX_OBJECTS}")  # fmt: skip
    seen: tuple[list, list] = ([], [])
    other = 0
    for uid, obj in objects.items():
        okey = f"{where}.objects.{str(uid)[:40]}"
        uid = _name(str(uid), path, okey, 64)
        data = _mapping(field(obj, "object_data", path, okey), path, f"{okey}.object_data")
        kind = data.get("type") or (catalogue.get(uid) or {}).get("type")
        kind = _name(kind, path, f"{okey}.object_data.type", 40).lower()
        for c, cuboid in enumerate(_cuboids(data, path, f"{okey}.object_data")):
            ckey = f"{okey}.object_data.cuboid[{c}]"
            system = _name(field(cuboid, "coordinate_system", path, ckey), path, f"{ckey}.coordinate_system")  # fmt: skip
            if system not in sides:
                other += 1
                continue
            side = sides.index(system)
            if any(b["id"] == uid for b in seen[side]):
                raise ImportFormatError(path, f"{ckey}: a second cuboid of {uid[:40]!r} in {system!r}")  # fmt: skip
            seen[side].append(_box(cuboid, path, ckey) | {"id": uid, "cls": kind})
    view1, found1 = side_view(f"vehicle:{sides[0]}", "vehicle", vehicle_pose, vehicle_pose, seen[0])  # fmt: skip
    view2, found2 = side_view(f"infrastructure:{sides[1]}", "roadside", np.eye(4), np.eye(4), seen[1])  # fmt: skip
    ids1 = {o.id for o in found1}
    meta = {"source": SOURCE["kind"], "file": rel, "frame": key[:40], "other_cuboids": other}
    meta["linked_objects"] = len(ids1 & {o.id for o in found2})
    return ImportedFrame(time, (view1, view2), found1 + [o for o in found2 if o.id not in ids1], meta)  # fmt: skip


def _frame_order(key: str) -> tuple:
    return (0, int(key), key) if key.isdigit() and len(key) < 19 else (1, 0, key)


def import_tumtraf_v2x(
    src: str | Path,
    out: str | Path,
    vehicle_cs: str = VEHICLE_CS,
    infrastructure_cs: str = INFRASTRUCTURE_CS,
) -> ImportResult:
    """Convert the OpenLABEL files under ``src`` into a box-only dataset at ``out`` (a new or
    empty folder); ``vehicle_cs`` / ``infrastructure_cs``: the two sides' coordinate systems.
    ``ImportFormatError`` (one line naming file and key) for malformed input; nothing is written
    then.

    >>> import_tumtraf_v2x("TUMTraf-V2X/test/labels_point_clouds", "data/tumtraf")  # doctest: +SKIP
    ImportResult(out=PosixPath('data/tumtraf'), episodes={0: 1, ...}, views=2, ...)
    """
    if vehicle_cs == infrastructure_cs:
        raise ValueError(f"coordinate systems: the two sides are both {vehicle_cs!r}")
    root, out = Path(src), check_out(out)  # checked before Path("") could become "."
    if not root.is_dir():
        raise ImportFormatError(root, "not a folder")
    files = sorted(p for p in root.rglob("*.json") if p.is_file() or p.is_symlink())
    if not files:
        raise ImportFormatError(root, "no OpenLABEL .json files")
    if len(files) > MAX_FILES:
        raise ImportFormatError(root, f"{len(files)} .json files, at most {MAX_FILES}")
    sides = (vehicle_cs, infrastructure_cs)
    records, clock, digest = [], TimeNote(), hashlib.sha256()
    for episode, path in enumerate(files):
        rel = path.relative_to(root).as_posix()
        path = confined(root, rel, root, rel)
        ol = _mapping(field(read_json(path), "openlabel", path), path, "openlabel")
        frames = _mapping(field(ol, "frames", path, "openlabel"), path, "openlabel.frames")
        if not frames:
            raise ImportFormatError(path, "openlabel.frames: expected at least one frame")
        keys = sorted((str(k) for k in frames), key=_frame_order)
        imported = [_frame(ol, k, frames[k], sides, path, rel) for k in keys]
        imported = relative_times(imported, path, "openlabel.frames", ordered=False, note=clock)
        records += sequence_records(episode, 0, episode, imported, False)
        digest.update(rel.encode() + b"\0" + hashlib.sha256(read_bytes(path)).digest())
    linked = sum(r.meta["linked_objects"] for r in records)
    source = SOURCE | {"folder": root.name, "files": len(files), "linked_objects": linked}
    source |= {"vehicle_cs": vehicle_cs, "infrastructure_cs": infrastructure_cs}
    source |= {"time": clock.as_manifest(), "sha256": digest.hexdigest()}
    return write_box_dataset(out, records, SCENARIO_NAME, source)


__all__ = ["INFRASTRUCTURE_CS", "VEHICLE_CS", "import_tumtraf_v2x"]
