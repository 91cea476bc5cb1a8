"""``cadsim import v2x-seq``: V2X-Seq-SPD's cooperative frames (DAIR-V2X's sequential perception
data) as box-only frame pairs, vehicle (view 1) and roadside unit (view 2), kept as sequences.

Read (paths relative to the folder given; every one confined to it, :mod:`.safe_read`):

- ``cooperative/data_info.json``: per cooperative frame ``vehicle_frame``,
  ``infrastructure_frame``, ``vehicle_sequence``, ``infrastructure_sequence``,
  ``system_error_offset`` {``delta_x``, ``delta_y``} (metres);
- ``cooperative/label/<vehicle_frame>.json``: objects with ``veh_track_id`` and
  ``inf_track_id`` ("-1" where one side does not see the object) — the ground truth;
- ``vehicle-side/data_info.json`` and ``infrastructure-side/data_info.json``: per frame
  ``frame_id``, ``pointcloud_timestamp`` (µs) and the label and calibration paths
  (``label_lidar_std_path``, ``calib_lidar_to_novatel_path``, ``calib_novatel_to_world_path``,
  ``calib_virtuallidar_to_world_path``; the published defaults when absent);
- each side's labels: ``type``, ``track_id``, ``3d_dimensions`` {h, w, l} (metres),
  ``3d_location`` {x, y, z} (box centre, that side's LiDAR frame: x forward, y left, z up),
  ``rotation`` (yaw about z, radians);
- calibration: vehicle LiDAR → world = ``novatel_to_world`` · ``lidar_to_novatel`` (its
  ``transform``); roadside LiDAR → world = ``virtuallidar_to_world`` with the frame's
  ``system_error_offset`` added to its translation (DAIR-V2X's correction).

Mapping: a cooperative sequence is an episode (its number), its frames in time order the
slots; an object seen by both sides (both track ids given) has one object id, ``v<veh track>``,
on both; one seen by one side ``v<track>`` or ``i<track>``; boxes become box-only detections in
each LiDAR's frame (:mod:`.sensor_frame`); the true relative pose is the calibration's; the
vehicle's body is its NovAtel (GNSS/INS) unit, the roadside unit's its LiDAR; ``time`` is the
vehicle's point-cloud time (s) counted from its sequence's first frame (the source's epoch time
in ``meta.epoch_time_s``: a GNSS preset's walk then spans the sequence, not the years since
1970) and ``meta.time_offset_s`` the vehicle's minus the roadside
unit's. No localisation prior is stored (the data has no noisy pose): a preset draws one.
"""

from __future__ import annotations

import hashlib
import itertools
from collections.abc import Iterable
from dataclasses import replace
from pathlib import Path

import numpy as np

from cadsim import portable_math as pm
from cadsim.dataset.box_record import BoxView, box_detections
from cadsim.importers import ImportFormatError
from cadsim.importers.box_dataset import ImportResult, check_out, write_box_dataset
from cadsim.importers.box_sequence import ImportedFrame, sequence_records
from cadsim.importers.safe_read import confined, field, number, read_bytes, read_json, rigid
from cadsim.importers.sensor_frame import (
    apply,
    boxes_in_view,
    heading_of,
    sensor_camera,
    yaw_directions,
)
from cadsim.observer_pose import ObserverPose
from cadsim.world import WorldObject

SCENARIO_NAME = "v2x-seq-spd"
SOURCE = {
    "kind": "v2x-seq",
    "repository": "https://github.com/AIR-THU/DAIR-V2X-Seq",
    "commit": "published layout",
    "files": "cooperative/, vehicle-side/, infrastructure-side/ (labels, calib, data_info.json)",
    "licence": "the dataset's own terms (not redistributed)",
    "simulator": "none: real-world recordings",
}
_SIDES = {
    "vehicle": ("vehicle-side", "label/lidar", "v"),
    "infrastructure": ("infrastructure-side", "label/virtuallidar", "i"),
}
_MISSING = "-1"


class _Reader:
    """The files of one V2X-Seq-SPD folder, read once each."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.used: set[Path] = set()  # every file named to be read: the source digest's files
        self.info = {side: self._side_info(side) for side in _SIDES}

    def path(self, relative: str, where: Path | None = None, key: str = "") -> Path:
        """``root / relative``, confined to the root, and noted for the digest."""
        path = confined(self.root, relative, where, key)
        self.used.add(path)
        return path

    def _side_info(self, side: str) -> dict[str, dict]:
        folder = _SIDES[side][0]
        path = self.path(f"{folder}/data_info.json")
        entries = read_json(path)
        if not isinstance(entries, list):
            raise ImportFormatError(path, "top level: expected a list of frames")
        out = {}
        for k, entry in enumerate(entries):
            frame = str(field(entry, "frame_id", path, f"[{k}]"))
            if frame in out:
                first = out[frame]["_where"]
                raise ImportFormatError(path, f"[{k}].frame_id: {frame[:20]!r} already at {first}")
            out[frame] = entry | {"_where": f"[{k}]"}
        return out

    def frame(self, side: str, frame_id: str, where: Path, key: str) -> dict:
        info = self.info[side]
        if frame_id not in info:
            folder = _SIDES[side][0]
            raise ImportFormatError(
                where, f"{key}: frame {frame_id[:20]!r} not in {folder}/data_info.json"
            )
        return info[frame_id]

    def side_path(self, side: str, entry: dict, key: str, default: str) -> Path:
        folder = _SIDES[side][0]
        where = self.root / folder / "data_info.json"
        relative = entry.get(key, default)
        path = confined(self.root / folder, relative, where, f"{entry['_where']}.{key}")
        self.used.add(path)
        return path


def _timestamp(entry: dict, path: Path) -> float:
    """Point-cloud time of a side's frame, seconds (the source's µs)."""
    value = field(entry, "pointcloud_timestamp", path, entry["_where"])
    if isinstance(value, str) and value.isdigit() and len(value) <= 20:
        value = int(value)
    return number(value, path, f"{entry['_where']}.pointcloud_timestamp", 1e20) / 1e6


def _calibration(reader: _Reader, side: str, entry: dict, offset: tuple[float, float]) -> tuple:
    """(sensor → world, body → world) 4×4 of a side's frame."""
    frame = str(entry["frame_id"])
    if side == "vehicle":
        l2n_path = reader.side_path(
            side, entry, "calib_lidar_to_novatel_path", f"calib/lidar_to_novatel/{frame}.json"
        )
        n2w_path = reader.side_path(
            side, entry, "calib_novatel_to_world_path", f"calib/novatel_to_world/{frame}.json"
        )
        l2n = read_json(l2n_path)
        l2n = l2n.get("transform", l2n) if isinstance(l2n, dict) else l2n
        n2w = read_json(n2w_path)
        lidar_to_novatel = rigid(field(l2n, "rotation", l2n_path, "transform"), field(l2n, "translation", l2n_path, "transform"), l2n_path, "transform")  # fmt: skip
        novatel_to_world = rigid(field(n2w, "rotation", n2w_path), field(n2w, "translation", n2w_path), n2w_path, "")  # fmt: skip
        return pm.matmul(novatel_to_world, lidar_to_novatel), novatel_to_world
    path = reader.side_path(side, entry, "calib_virtuallidar_to_world_path", f"calib/virtuallidar_to_world/{frame}.json")  # fmt: skip
    calib = read_json(path)
    sensor = rigid(field(calib, "rotation", path), field(calib, "translation", path), path, "")
    sensor[:2, 3] += offset
    return sensor, sensor


def _labels(path: Path, prefix: str, links: dict[str, str]) -> list[dict]:
    """A side's objects: id, class, centre (sensor frame), yaw, size l, w, h."""
    objects = read_json(path)
    if not isinstance(objects, list):
        raise ImportFormatError(path, "top level: expected a list of objects")
    out, seen = [], set()
    for k, obj in enumerate(objects):
        where = f"[{k}]"
        track = str(field(obj, "track_id", path, where))
        dims = field(obj, "3d_dimensions", path, where)
        loc = field(obj, "3d_location", path, where)
        size = [number(field(dims, a, path, f"{where}.3d_dimensions"), path, f"{where}.3d_dimensions.{a}", 1e3) for a in "lwh"]  # fmt: skip
        if min(size) <= 0:
            raise ImportFormatError(path, f"{where}.3d_dimensions: sizes must be > 0, got {size}")
        centre = [number(field(loc, a, path, f"{where}.3d_location"), path, f"{where}.3d_location.{a}") for a in "xyz"]  # fmt: skip
        oid = links.get(track, f"{prefix}{track}")
        if oid in seen:
            raise ImportFormatError(path, f"{where}.track_id: {track[:20]!r} appears twice")
        seen.add(oid)
        out.append(
            {
                "id": oid,
                "cls": str(field(obj, "type", path, where)).lower()[:40],
                "centre": centre,
                "yaw": number(field(obj, "rotation", path, where), path, f"{where}.rotation", 1e3),
                "size": size,
            }
        )
    return out


def _links(path: Path) -> tuple[dict[str, str], dict[str, str]]:
    """{vehicle track: object id}, {roadside track: object id} of a cooperative label file."""
    labels = read_json(path)
    if not isinstance(labels, list):
        raise ImportFormatError(path, "top level: expected a list of objects")
    veh, inf = {}, {}
    for k, label in enumerate(labels):
        v = str(field(label, "veh_track_id", path, f"[{k}]"))
        i = str(field(label, "inf_track_id", path, f"[{k}]"))
        if v == _MISSING or i == _MISSING:
            continue
        if veh.get(v, i) != i or inf.get(i, v) != v:
            raise ImportFormatError(path, f"[{k}]: track {v!r} / {i!r} linked twice")
        veh[v], inf[i] = i, v
    return {v: f"v{v}" for v in veh}, {i: f"v{v}" for i, v in inf.items()}


def _view(observer: str, kind: str, sensor: np.ndarray, body: np.ndarray, boxes: list[dict]):
    """A side's box view and its boxes as world objects."""
    camera = sensor_camera(sensor)
    k = len(boxes)
    centres = np.array([b["centre"] for b in boxes], dtype=float).reshape(k, 3)
    yaws = np.array([b["yaw"] for b in boxes], dtype=float)
    world = apply(sensor, centres)
    directions = pm.matmul(yaw_directions(yaws), sensor[:3, :3].T)
    positions, headings = boxes_in_view(camera, world, directions)
    sizes = np.array([b["size"] for b in boxes], dtype=float).reshape(k, 3)
    ids, classes = [b["id"] for b in boxes], [b["cls"] for b in boxes]
    forward = body[:3, 0]
    pose = ObserverPose(
        tuple(float(v) for v in body[:3, 3]), float(pm.arctan2(forward[1], forward[0]))
    )
    det = box_detections(positions, sizes, headings, ids, classes)
    view = BoxView(observer, kind, camera, pose, det, sizes)
    world_yaw = heading_of(directions)
    objects = [
        WorldObject(i, c, "box", tuple(w), float(y), tuple(s), (0.5, 0.5, 0.5))
        for i, c, w, y, s in zip(
            ids, classes, world.tolist(), world_yaw, sizes.tolist(), strict=True
        )
    ]
    return view, objects


def _frame(reader: _Reader, coop: dict, where: Path, key: str) -> tuple[str, ImportedFrame]:
    """(sequence id, frame) of one cooperative frame."""
    veh_id = str(field(coop, "vehicle_frame", where, key))
    inf_id = str(field(coop, "infrastructure_frame", where, key))
    sequence = str(field(coop, "vehicle_sequence", where, key))
    offset_entry = coop.get("system_error_offset") or {}
    if not isinstance(offset_entry, dict):
        raise ImportFormatError(
            where,
            f"{key}.system_error_offset: expected {{delta_x, delta_y}} (metres), "
            f"got {type(offset_entry).__name__}",
        )
    offset = tuple(
        number(offset_entry.get(a, 0.0), where, f"{key}.system_error_offset.{a}", 1e3)
        for a in ("delta_x", "delta_y")
    )
    veh = reader.frame("vehicle", veh_id, where, f"{key}.vehicle_frame")
    inf = reader.frame("infrastructure", inf_id, where, f"{key}.infrastructure_frame")
    veh_links, inf_links = _links(reader.path(f"cooperative/label/{veh_id}.json", where, f"{key}.vehicle_frame"))  # fmt: skip
    views, objects = [], {}
    for side, entry, links, kind in (("vehicle", veh, veh_links, "vehicle"), ("infrastructure", inf, inf_links, "roadside")):  # fmt: skip
        folder, label_folder, prefix = _SIDES[side]
        frame = str(entry["frame_id"])
        label = reader.side_path(
            side, entry, "label_lidar_std_path", f"{label_folder}/{frame}.json"
        )
        sensor, body = _calibration(
            reader, side, entry, offset if side == "infrastructure" else (0.0, 0.0)
        )
        view, found = _view(f"{side}:{frame}", kind, sensor, body, _labels(label, prefix, links))
        views.append(view)
        for obj in found:
            objects.setdefault(obj.id, obj)  # the vehicle's box of a shared object first
    info_path = reader.root / "vehicle-side" / "data_info.json"
    t_veh = _timestamp(veh, info_path)
    t_inf = _timestamp(inf, reader.root / "infrastructure-side" / "data_info.json")
    meta = {
        "source": SOURCE["kind"],
        "vehicle_frame": veh_id,
        "infrastructure_frame": inf_id,
        "sequence": sequence,
        "infrastructure_sequence": str(coop.get("infrastructure_sequence", "")),
        "time_offset_s": t_veh - t_inf,
        "system_error_offset": list(offset),
    }
    return sequence, ImportedFrame(t_veh, tuple(views), list(objects.values()), meta)


def _episode(sequence: str, index: int) -> int:
    """The episode of a sequence id: the id itself when it is ASCII digits ('0010' → 10;
    '²' or '١٠' are names like any other), else its index."""
    plain = sequence.isascii() and sequence.isdigit() and len(sequence) <= 9
    return int(sequence) if plain else index


def _digest(root: Path, files: Iterable[Path]) -> str:
    """SHA-256 over the files the import read (relative name and SHA-256 of each), each read
    again within the reader's size limit — never the rest of the folder."""
    h = hashlib.sha256()
    for path in sorted(set(files)):
        h.update(path.relative_to(root).as_posix().encode() + b"\0")
        h.update(hashlib.sha256(read_bytes(path)).digest())
    return h.hexdigest()


def import_v2x_seq(
    src: str | Path, out: str | Path, sequences: Iterable[str] | None = None
) -> ImportResult:
    """Convert the V2X-Seq-SPD folder ``src`` (only ``sequences``, e.g. ``["0010"]``, if given)
    into a box-only dataset at ``out`` (a new or empty folder). Raises ``ImportFormatError``
    (one line naming the file and key) for malformed input; nothing is written then.

    >>> import_v2x_seq("V2X-Seq-SPD", "data/v2x-seq")  # doctest: +SKIP
    ImportResult(out=PosixPath('data/v2x-seq'), episodes={10: 80, ...}, views=2, ...)
    """
    root, out = Path(src), check_out(out)  # checked before Path("") could become "."
    if not root.is_dir():
        raise ImportFormatError(root, "not a folder")
    reader = _Reader(root)
    coop_path = reader.path("cooperative/data_info.json")
    coops = read_json(coop_path)
    if not isinstance(coops, list) or not coops:
        raise ImportFormatError(
            coop_path, "top level: expected a non-empty list of cooperative frames"
        )
    wanted = None if sequences is None else {str(s) for s in sequences}
    grouped: dict[str, list[ImportedFrame]] = {}
    listed: dict[str, str] = {}  # vehicle frame -> the key that lists it
    for k, coop in enumerate(coops):
        sequence = str(field(coop, "vehicle_sequence", coop_path, f"[{k}]"))
        if wanted is not None and sequence not in wanted:
            continue
        sequence, frame = _frame(reader, coop, coop_path, f"[{k}]")
        first = listed.setdefault(frame.meta["vehicle_frame"], f"[{k}]")
        if first != f"[{k}]":
            raise ImportFormatError(
                coop_path,
                f"[{k}].vehicle_frame: {frame.meta['vehicle_frame'][:20]!r} "
                f"already listed at {first}",
            )
        grouped.setdefault(sequence, []).append(frame)
    if not grouped:
        raise ImportFormatError(
            coop_path, f"no cooperative frames of sequences {sorted(wanted or [])}"
        )
    sequential = any(len(frames) > 1 for frames in grouped.values())
    records, used = [], set()
    for index, sequence in enumerate(sorted(grouped)):
        episode = _episode(sequence, index)
        if episode in used:
            raise ImportFormatError(coop_path, f"sequence {sequence!r}: episode {episode} twice")
        used.add(episode)
        frames = sorted(grouped[sequence], key=lambda f: f.time)
        for a, b in itertools.pairwise(frames):
            if a.time == b.time:
                raise ImportFormatError(
                    reader.root / "vehicle-side" / "data_info.json",
                    f"frames {a.meta['vehicle_frame'][:20]!r} and {b.meta['vehicle_frame'][:20]!r} "
                    f"of sequence {sequence[:20]!r}: same pointcloud_timestamp",
                )
        start = frames[0].time  # times from the sequence's first frame (the epoch in meta)
        frames = [
            replace(f, time=f.time - start, meta=f.meta | {"epoch_time_s": f.time}) for f in frames
        ]
        records += sequence_records(episode, 0, episode, frames, sequential)
    source = SOURCE | {
        "folder": root.name,
        "sequences": {s: len(f) for s, f in sorted(grouped.items())},
    }
    return write_box_dataset(
        out, records, SCENARIO_NAME, source | {"sha256": _digest(root, reader.used)}
    )


__all__ = ["import_v2x_seq"]
