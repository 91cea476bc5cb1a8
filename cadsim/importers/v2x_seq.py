"""``cadsim import v2x-seq``: V2X-Seq-SPD's cooperative frames (DAIR-V2X's sequential perception
data) as box-only frame pairs, vehicle (view 1) and roadside unit (view 2), kept as sequences.

Read (paths relative to the folder given; every one confined to it, :mod:`.safe_read`):

- ``cooperative/data_info.json``: per cooperative frame ``vehicle_frame``,
  ``infrastructure_frame``, ``vehicle_sequence``, ``infrastructure_sequence``,
  ``system_error_offset`` {``delta_x``, ``delta_y``} (metres);
- ``cooperative/label/<vehicle_frame>.json``: objects with ``veh_token`` / ``inf_token`` (each
  side label's ``token``), ``veh_track_id`` / ``inf_track_id`` ("-1" or empty where one side does
  not see the object) and ``track_id`` — the ground truth, linked by token and cross-checked
  against the track ids (by track id where the file has no tokens);
- ``vehicle-side/data_info.json`` and ``infrastructure-side/data_info.json``: per frame
  ``frame_id``, ``pointcloud_timestamp`` (µs) and the label and calibration paths
  (``label_lidar_std_path``, ``calib_lidar_to_novatel_path``, ``calib_novatel_to_world_path``,
  ``calib_virtuallidar_to_world_path``; the published defaults when absent);
- each side's labels (:mod:`.dair_side`): ``type``, ``track_id`` (absent for traffic cones:
  such boxes get one frame's id and are counted), ``token``, ``3d_dimensions`` {h, w, l}
  (metres), ``3d_location`` {x, y, z} (box centre, that side's LiDAR frame: x forward, y left,
  z up), ``rotation`` (yaw about z, radians);
- calibration: vehicle LiDAR → world = ``novatel_to_world`` · ``lidar_to_novatel`` (its
  ``transform``); roadside LiDAR → world = ``virtuallidar_to_world`` with the frame's
  ``system_error_offset`` applied by the chosen convention (:data:`OFFSET_CONVENTIONS`; default:
  added to its translation, DAIR-V2X's ``calib_i2v.py``).

Mapping: a cooperative sequence is an episode (its number, :mod:`.episode_names`), its frames
in time order the slots; an object seen by both sides (both track ids given) has one object
id, ``v<veh track>``, on both; one seen by one side ``v<track>`` or ``i<track>``; boxes become
box-only detections in
each LiDAR's frame (:mod:`.sensor_frame`); the true relative pose is the calibration's; the
vehicle's body is its NovAtel (GNSS/INS) unit, the roadside unit's its LiDAR; ``time`` is the
vehicle's point-cloud time (s) counted from its sequence's first frame (the source's epoch time
in ``meta.source_time_s``, :mod:`.record_time`: a GNSS preset's walk then spans the sequence,
not the years since 1970) and ``meta.time_offset_s`` the vehicle's minus the roadside
unit's. No localisation prior is stored (the data has no noisy pose): a preset draws one.
"""

from __future__ import annotations

import hashlib
import itertools
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from cadsim import portable_math as pm
from cadsim.importers import ImportFormatError
from cadsim.importers.box_dataset import ImportResult, check_out, write_box_dataset
from cadsim.importers.box_sequence import ImportedFrame, sequence_records
from cadsim.importers.dair_side import read_boxes, side_view
from cadsim.importers.episode_names import episode_numbers
from cadsim.importers.record_time import TimeNote, relative_times
from cadsim.importers.safe_read import confined, field, number, read_bytes, read_json, rigid

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


OFFSET_CONVENTIONS = ("roadside", "vehicle")
"""Where ``system_error_offset`` applies (docs/external-data.md): ``roadside`` (the default)
adds (delta_x, delta_y) to the roadside LiDAR → world translation, as DAIR-V2X's own
``calib_i2v.py`` and the OpenCOOD / CoAlign / HEAL loaders do; ``vehicle`` adds it to the
roadside → vehicle LiDAR translation, in the vehicle LiDAR's axes, as DAIR-V2X's
``label_i2v.py`` converter, UniV2X and CoopTrack do. They differ by (R_vehicle − I)·δ, up to
2|δ|."""


def _calibration(reader: _Reader, side: str, entry: dict) -> tuple:
    """(sensor → world, body → world) 4×4 of a side's frame, without the system error offset."""
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
    return sensor, sensor


def corrected_roadside(
    roadside: np.ndarray, vehicle: np.ndarray, offset: tuple[float, float], convention: str
) -> np.ndarray:
    """The roadside LiDAR → world 4×4 with the system error offset (metres) applied by
    ``convention`` (:data:`OFFSET_CONVENTIONS`); ``vehicle``: the vehicle LiDAR → world."""
    out = np.array(roadside, dtype=np.float64)
    delta = np.array([offset[0], offset[1], 0.0])
    if convention == "roadside":
        out[:3, 3] += delta
    elif convention == "vehicle":  # T_i2v's translation + δ, in the vehicle LiDAR's axes
        out[:3, 3] += pm.matmul(np.asarray(vehicle, dtype=np.float64)[:3, :3], delta)
    else:
        raise ValueError(
            f"offset convention: expected one of {OFFSET_CONVENTIONS}, got {convention!r}"
        )
    return out


def _links(path: Path) -> list[dict]:
    """The cooperative label's objects seen by both sides: ``id`` (``v<veh track>``, else
    ``c<track_id>``), per side its ``token`` (``veh_token`` / ``inf_token``, None when the file
    has none) and ``track`` (``veh_track_id`` / ``inf_track_id``)."""
    labels = read_json(path)
    if not isinstance(labels, list):
        raise ImportFormatError(path, "top level: expected a list of objects")
    out, seen = [], {}
    for k, label in enumerate(labels):
        where = f"[{k}]"
        if not isinstance(label, dict):
            raise ImportFormatError(path, f"{where}: expected a mapping")
        entry = {"where": where}
        for side, short in (("vehicle", "veh"), ("infrastructure", "inf")):
            track = _track(label, f"{short}_track_id", path, where)
            token = _track(label, f"{short}_token", path, where)
            entry[side] = {"track": track, "token": token}
        v, i = entry["vehicle"], entry["infrastructure"]
        if (v["token"] or v["track"]) is None or (i["token"] or i["track"]) is None:
            continue  # one side alone sees it
        entry["id"] = (
            f"v{v['track']}" if v["track"] else f"c{_track(label, 'track_id', path, where)}"
        )
        for side in ("vehicle", "infrastructure"):
            key = (side, entry[side]["token"] or entry[side]["track"])
            if key in seen:
                raise ImportFormatError(
                    path, f"{where}: {side} object {key[1][:20]!r} linked twice (also {seen[key]})"
                )
            seen[key] = where
        out.append(entry)
    return out


def _track(label: dict, key: str, path: Path, where: str) -> str | None:
    value = label.get(key)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | str) or len(str(value)) > 64:
        raise ImportFormatError(
            path, f"{where}.{key}: expected an id string, got {str(value)[:30]}"
        )
    return None if str(value) in ("", _MISSING) else str(value)


def _side_ids(
    boxes: list[dict], side: str, prefix: str, links: list[dict], coop: Path, frame: str
) -> int:
    """Give each box of a side its object id (in place): linked by token where the cooperative
    label names tokens, the track ids cross-checked (a mismatch is an error naming the frame),
    else by track id; an unlinked box ``<prefix><track>``, a box without a track id
    ``<prefix>untracked:<frame>:<index>``. Returns the number of boxes without a track id."""
    by_token = {e[side]["token"]: e for e in links if e[side]["token"]}
    by_track = {e[side]["track"]: e for e in links if e[side]["track"] and not e[side]["token"]}
    untracked, seen = 0, set()
    for k, box in enumerate(boxes):
        entry = by_token.get(box["token"]) if box["token"] else None
        if entry is not None:
            listed = entry[side]["track"]
            if listed is not None and listed != box["track"]:
                raise ImportFormatError(
                    coop,
                    f"{entry['where']}: frame {frame[:20]!r}: {side} token {box['token'][:30]!r} "
                    f"is track {str(box['track'])[:20]!r} in the side label, {listed[:20]!r} here",
                )
        elif box["track"] is not None:
            entry = by_track.get(box["track"])
        if entry is not None:
            box["id"] = entry["id"]
        elif box["track"] is not None:
            box["id"] = f"{prefix}{box['track']}"
        else:
            box["id"] = f"{prefix}untracked:{frame}:{k}"
            untracked += 1
        if box["id"] in seen:
            raise ImportFormatError(
                coop, f"frame {frame[:20]!r}: {side} object {box['id'][:30]!r} appears twice"
            )
        seen.add(box["id"])
    return untracked


def _frame(
    reader: _Reader, coop: dict, where: Path, key: str, convention: str = "roadside"
) -> tuple[str, ImportedFrame]:
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
    coop_path = reader.path(f"cooperative/label/{veh_id}.json", where, f"{key}.vehicle_frame")
    links = _links(coop_path)
    vehicle_sensor, vehicle_body = _calibration(reader, "vehicle", veh)
    roadside, _ = _calibration(reader, "infrastructure", inf)
    roadside = corrected_roadside(roadside, vehicle_sensor, offset, convention)
    views, objects, untracked = [], {}, 0
    sides = (
        ("vehicle", veh, "vehicle", vehicle_sensor, vehicle_body),
        ("infrastructure", inf, "roadside", roadside, roadside),
    )
    for side, entry, kind, sensor, body in sides:
        folder, label_folder, prefix = _SIDES[side]
        frame = str(entry["frame_id"])
        label = reader.side_path(
            side, entry, "label_lidar_std_path", f"{label_folder}/{frame}.json"
        )
        boxes = read_boxes(label)
        untracked += _side_ids(boxes, side, prefix, links, coop_path, veh_id)
        view, found = side_view(f"{side}:{frame}", kind, sensor, body, boxes)
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
        "offset_convention": convention,
        "untracked_objects": untracked,
    }
    return sequence, ImportedFrame(t_veh, tuple(views), list(objects.values()), meta)


def _digest(root: Path, files: Iterable[Path]) -> str:
    """SHA-256 over the files the import read (relative name and SHA-256 of each), each read
    again within the reader's size limit — never the rest of the folder."""
    h = hashlib.sha256()
    for path in sorted(set(files)):
        h.update(path.relative_to(root).as_posix().encode() + b"\0")
        h.update(hashlib.sha256(read_bytes(path)).digest())
    return h.hexdigest()


def import_v2x_seq(
    src: str | Path,
    out: str | Path,
    sequences: Iterable[str] | None = None,
    offset_convention: str = "roadside",
) -> ImportResult:
    """Convert the V2X-Seq-SPD folder ``src`` (only ``sequences``, e.g. ``["0010"]``, if given)
    into a box-only dataset at ``out`` (a new or empty folder); ``offset_convention``: where
    ``system_error_offset`` applies (:data:`OFFSET_CONVENTIONS`). Raises ``ImportFormatError``
    (one line naming the file and key) for malformed input; nothing is written then.

    >>> import_v2x_seq("V2X-Seq-SPD", "data/v2x-seq")  # doctest: +SKIP
    ImportResult(out=PosixPath('data/v2x-seq'), episodes={10: 80, ...}, views=2, ...)
    """
    if offset_convention not in OFFSET_CONVENTIONS:
        raise ValueError(
            f"offset convention: expected one of {OFFSET_CONVENTIONS}, got {offset_convention!r}"
        )
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
        sequence, frame = _frame(reader, coop, coop_path, f"[{k}]", offset_convention)
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
    records, clock = [], TimeNote()
    try:
        episodes = episode_numbers(grouped)
    except ValueError as exc:
        raise ImportFormatError(coop_path, f"vehicle_sequence: {exc}") from None
    for sequence in sorted(grouped):
        episode = episodes[sequence]
        frames = sorted(grouped[sequence], key=lambda f: f.time)
        for a, b in itertools.pairwise(frames):
            if a.time == b.time:
                raise ImportFormatError(
                    reader.root / "vehicle-side" / "data_info.json",
                    f"frames {a.meta['vehicle_frame'][:20]!r} and {b.meta['vehicle_frame'][:20]!r} "
                    f"of sequence {sequence[:20]!r}: same pointcloud_timestamp",
                )
        frames = relative_times(
            frames, reader.root / "vehicle-side" / "data_info.json", f"sequence {sequence[:20]!r}",
            ordered=True, note=clock,
        )  # fmt: skip
        records += sequence_records(episode, 0, episode, frames, sequential)
    source = SOURCE | {
        "folder": root.name,
        "sequences": {s: len(f) for s, f in sorted(grouped.items())},
        "offset_convention": offset_convention,
        "time": clock.as_manifest(),
        "untracked_objects": sum(
            f.meta["untracked_objects"] for frames in grouped.values() for f in frames
        ),
    }
    return write_box_dataset(
        out, records, SCENARIO_NAME, source | {"sha256": _digest(root, reader.used)}
    )


__all__ = ["OFFSET_CONVENTIONS", "corrected_roadside", "import_v2x_seq"]
