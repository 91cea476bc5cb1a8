"""``cadsim import dair-v2x``: DAIR-V2X-C (real vehicle + roadside recordings) as box-only frame
pairs, vehicle (view 1) and roadside unit (view 2), with ground truth recovered from the labels.

DAIR-V2X-C's side labels carry no track id or token, and its cooperative label is fused world
boxes with no per-side link, so which vehicle box and which roadside box are one object is not
written anywhere: this importer recovers it by matching boxes in one frame. Read (paths relative
to the folder given, ``cooperative-vehicle-infrastructure``; each confined to it, :mod:`.safe_read`):

- ``cooperative/data_info.json`` (else ``cooperative/selected_data_info.json``, the one-frame
  sample layout): per frame pair ``vehicle_pointcloud_path`` and ``infrastructure_pointcloud_path``
  (the frame ids are their file stems), ``cooperative_label_path`` (optional) and
  ``system_error_offset`` {``delta_x``, ``delta_y``} (metres, default 0);
- ``vehicle-side/data_info.json`` and ``infrastructure-side/data_info.json`` (optional): per frame
  ``pointcloud_timestamp`` (µs) and ``batch_id`` (the recording segment);
- each side's label (``vehicle-side/label/lidar/<id>.json``,
  ``infrastructure-side/label/virtuallidar/<id>.json``; :mod:`.dair_side`);
- the calibration: ``cooperative/calib/lidar_i2v/<vehicle id>.json`` (roadside LiDAR → vehicle
  LiDAR, the offset already in it) when present, else the roadside's
  ``calib/virtuallidar_to_world`` with the offset added to its translation (DAIR-V2X's
  ``calib_i2v.py``); the vehicle's ``calib/lidar_to_novatel`` and ``calib/novatel_to_world`` place
  the vehicle LiDAR in the world when both are present, else the world is the vehicle LiDAR's
  frame. Rotations re-orthonormalised within :data:`~.safe_read.POLAR_ATOL`;
- ``cooperative/label_world/<id>.json`` (when named, present and the vehicle's world calibration
  is known): ``type`` and ``world_8_points`` (8 corners, world frame, metres) per fused box.

Ground truth (:func:`linked_pairs`): each side's boxes, moved into the world, are matched to the
cooperative boxes where they are given, else the roadside boxes, moved into the vehicle LiDAR
frame, directly to the vehicle's: one-to-one (Hungarian on ground-plane centre distance), same
class only, within :data:`LINK_GATE_M`. A vehicle and a roadside box matched to one cooperative
box are one object, ``c<k>`` (k: the cooperative box); boxes of classes the cooperative label does
not cover (:data:`COOPERATIVE_CLASSES`), and every box where it is not given, are matched side
to side, ``s<k>``; every other box is seen by one side only (``v<k>``, ``i<k>``). No
localisation prior is stored (the data has no noisy pose): a ``--localisation`` preset of
``cadsim evaluate`` draws one. Episodes are ``batch_id``s (:mod:`.episode_names`: a name of
digits is its number, any other is numbered after the largest; 0 when the side
``data_info.json`` is absent), slots the frame pairs in listed order. A side label file holds at
most :data:`~.dair_side.MAX_BOXES` boxes; a frame listed twice in a side ``data_info.json`` is
refused.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
from scipy.optimize import linear_sum_assignment

from cadsim import portable_math as pm
from cadsim.importers import ImportFormatError
from cadsim.importers.box_dataset import ImportResult, check_out, write_box_dataset
from cadsim.importers.box_sequence import ImportedFrame, sequence_records
from cadsim.importers.dair_side import MAX_BOXES, MAX_LABEL_BYTES, read_boxes, side_view
from cadsim.importers.episode_names import episode_numbers
from cadsim.importers.record_time import TimeNote, relative_times
from cadsim.importers.safe_read import (
    confined,
    field,
    matrix,
    number,
    read_bytes,
    read_json,
    rigid,
    shown,
)
from cadsim.importers.sensor_frame import apply

SCENARIO_NAME = "dair-v2x-c"
SOURCE = {
    "kind": "dair-v2x",
    "repository": "https://github.com/AIR-THU/DAIR-V2X",
    "commit": "published layout",
    "files": "cooperative/, vehicle-side/, infrastructure-side/ (labels, calib, data_info.json)",
    "licence": "the dataset's own terms (not redistributed)",
    "simulator": "none: real-world recordings",
}
LINK_GATE_M = 1.0
"""Largest ground-plane centre distance (metres) of two boxes linked as one object. On the real
frame pair checked (docs/external-data.md) the 7 covisible boxes lie 0.09–0.29 m apart after the
calibration and the nearest box of the same class that is another object ≥ 10 m away; traffic
cones stand about 1.3 m apart, so a gate above that could pair a cone with its neighbour."""
COOPERATIVE_CLASSES = frozenset({"car", "truck", "van", "bus"})
"""The classes DAIR-V2X-C's cooperative label covers; boxes of other classes are linked side to
side even where the cooperative boxes are given."""
_SIDES = {
    "vehicle": ("vehicle-side", "label/lidar", "v"),
    "infrastructure": ("infrastructure-side", "label/virtuallidar", "i"),
}


def linked_pairs(
    a_xy: np.ndarray, a_cls: list[str], b_xy: np.ndarray, b_cls: list[str], gate_m: float
) -> list[tuple[int, int]]:
    """One-to-one pairs (i, j) of boxes of the same class whose ground-plane centres (metres,
    one frame) are at most ``gate_m`` apart, minimising the summed distance (Hungarian).

    >>> linked_pairs(np.zeros((1, 2)), ["car"], np.array([[0.3, 0.0]]), ["car"], 1.0)
    [(0, 0)]
    """
    if not len(a_cls) or not len(b_cls):
        return []
    cost = np.linalg.norm(a_xy[:, None, :] - b_xy[None, :, :], axis=2)
    allowed = (np.asarray(a_cls)[:, None] == np.asarray(b_cls)[None, :]) & (cost <= gate_m)
    big = 1e6
    rows, cols = linear_sum_assignment(np.where(allowed, cost, big))
    return [(int(i), int(j)) for i, j in zip(rows, cols, strict=True) if allowed[i, j]]


class _Reader:
    """The files of one DAIR-V2X-C folder; every path read is noted for the digest."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.used: set[Path] = set()

    def path(self, relative: str, where: Path | None = None, key: str = "") -> Path:
        path = confined(self.root, relative, where, key)
        self.used.add(path)
        return path

    def optional(self, relative: str) -> Path | None:
        """``root / relative`` when it exists (confined and noted), else None."""
        candidate = self.root / relative
        if not (candidate.exists() or candidate.is_symlink()):
            return None
        return self.path(relative)

    def side_info(self, side: str) -> dict[str, dict]:
        """{frame id: entry} of a side's optional ``data_info.json`` (by its pointcloud stem),
        each entry with ``_where`` (its index) and ``_episode`` (its ``batch_id``'s number,
        :mod:`.episode_names`, over every entry of the file; 0 without a ``batch_id``, and 0 is
        never a named batch's: a frame the file does not list is episode 0 too)."""
        path = self.optional(f"{_SIDES[side][0]}/data_info.json")
        if path is None:
            return {}
        entries = read_json(path)
        if not isinstance(entries, list):
            raise ImportFormatError(path, "top level: expected a list of frames")
        out = {}
        for k, entry in enumerate(entries):
            frame = _stem(field(entry, "pointcloud_path", path, f"[{k}]"), path, f"[{k}].pointcloud_path")  # fmt: skip
            if frame in out:  # two entries for one frame: neither may silently win
                raise ImportFormatError(
                    path,
                    f"[{k}].pointcloud_path: frame {frame!r} already at {out[frame]['_where']}",
                )
            out[frame] = entry | {"_where": f"[{k}]", "_batch": _batch(entry, path, f"[{k}]")}
        try:  # "0" too: a frame this file does not list is episode 0, never a named batch's
            episodes = episode_numbers([*(e["_batch"] for e in out.values()), "0"])
        except ValueError as exc:
            raise ImportFormatError(path, f"batch_id: {exc}") from None
        return {frame: e | {"_episode": episodes[e["_batch"]]} for frame, e in out.items()}


def _batch(entry: dict, path: Path, where: str) -> str:
    """A side entry's ``batch_id`` as a name ("0" when absent): a string or an integer."""
    value = entry.get("batch_id", 0)
    if isinstance(value, bool) or not isinstance(value, int | str) or len(str(value)) > 64:
        raise ImportFormatError(
            path,
            f"{where}.batch_id: expected a recording name (string or integer), "
            f"got {shown(value, 30)}",
        )
    return str(value)


def _stem(value, path: Path, key: str) -> str:
    """The frame id of a data_info path (its file stem: ASCII digits)."""
    if not isinstance(value, str) or len(value) > 300:
        raise ImportFormatError(path, f"{key}: expected a file path, got {shown(value, 40)}")
    stem = Path(value).stem
    if not (stem.isascii() and stem.isdigit() and len(stem) <= 12):
        raise ImportFormatError(path, f"{key}: expected a digit file name, got {stem[:30]!r}")
    return stem


def _transform(reader: _Reader, relative: str, where: Path, key: str) -> np.ndarray:
    path = reader.path(relative, where, key)
    calib = read_json(path)
    calib = calib.get("transform", calib) if isinstance(calib, dict) else calib
    return rigid(field(calib, "rotation", path), field(calib, "translation", path), path, "")


def _poses(reader: _Reader, veh: str, inf: str, offset, where: Path, key: str) -> tuple:
    """(vehicle LiDAR → world, vehicle body → world, roadside LiDAR → world, world known)."""
    l2n = reader.optional(f"vehicle-side/calib/lidar_to_novatel/{veh}.json")
    n2w = reader.optional(f"vehicle-side/calib/novatel_to_world/{veh}.json")
    known = l2n is not None and n2w is not None
    if known:
        body = _transform(reader, f"vehicle-side/calib/novatel_to_world/{veh}.json", where, key)
        lidar_to_body = _transform(reader, f"vehicle-side/calib/lidar_to_novatel/{veh}.json", where, key)  # fmt: skip
        vehicle = pm.matmul(body, lidar_to_body)
    else:
        vehicle = body = np.eye(4)
    if reader.optional(f"cooperative/calib/lidar_i2v/{veh}.json") is not None:
        i2v = _transform(reader, f"cooperative/calib/lidar_i2v/{veh}.json", where, key)
        return vehicle, body, pm.matmul(vehicle, i2v), known
    if not known:
        raise ImportFormatError(
            reader.root / "cooperative" / "calib" / "lidar_i2v" / f"{veh}.json",
            "missing file (and no vehicle-side world calibration to place the roadside unit)",
        )
    roadside = _transform(reader, f"infrastructure-side/calib/virtuallidar_to_world/{inf}.json", where, key)  # fmt: skip
    roadside[:2, 3] += offset  # DAIR-V2X's calib_i2v.py: the offset corrects the roadside pose
    return vehicle, body, roadside, known


def _cooperative_boxes(path: Path) -> tuple[np.ndarray, list[str]]:
    """(k, 2) ground-plane centres (world, metres) and classes of a ``label_world`` file."""
    labels = read_json(path, MAX_LABEL_BYTES)
    if not isinstance(labels, list):
        raise ImportFormatError(path, "top level: expected a list of objects")
    if len(labels) > MAX_BOXES:
        raise ImportFormatError(path, f"{len(labels)} boxes, more than {MAX_BOXES}")
    centres, classes = [], []
    for k, label in enumerate(labels):
        corners = matrix(field(label, "world_8_points", path, f"[{k}]"), path, f"[{k}].world_8_points", 8, 3)  # fmt: skip
        kind = field(label, "type", path, f"[{k}]")
        if not isinstance(kind, str) or not kind:
            raise ImportFormatError(path, f"[{k}].type: expected a class name")
        centres.append(corners.mean(axis=0)[:2])
        classes.append(kind.lower()[:40])
    return np.array(centres, dtype=float).reshape(-1, 2), classes


def _ids(veh_boxes, inf_boxes, vehicle, roadside, coop, gate_m) -> str:
    """Give every box its object id (in place); returns how the links were made."""
    v_xy = apply(vehicle, [b["centre"] for b in veh_boxes])[:, :2]
    i_xy = apply(roadside, [b["centre"] for b in inf_boxes])[:, :2]
    v_cls, i_cls = [b["cls"] for b in veh_boxes], [b["cls"] for b in inf_boxes]
    for k, box in enumerate(veh_boxes):
        box["id"] = f"v{k}"
    for k, box in enumerate(inf_boxes):
        box["id"] = f"i{k}"
    direct_v = [k for k, c in enumerate(v_cls) if coop is None or c not in COOPERATIVE_CLASSES]
    direct_i = [k for k, c in enumerate(i_cls) if coop is None or c not in COOPERATIVE_CLASSES]
    pairs = [
        (direct_v[v], direct_i[i], f"s{n}")
        for n, (v, i) in enumerate(
            linked_pairs(v_xy[direct_v], [v_cls[k] for k in direct_v],
                         i_xy[direct_i], [i_cls[k] for k in direct_i], gate_m)
        )
    ]  # fmt: skip
    how = "side boxes"
    if coop is not None:
        c_xy, c_cls = coop
        v_of = {c: v for v, c in linked_pairs(v_xy, v_cls, c_xy, c_cls, gate_m)}
        i_of = {c: i for i, c in linked_pairs(i_xy, i_cls, c_xy, c_cls, gate_m)}
        pairs += [(v_of[c], i_of[c], f"c{c}") for c in sorted(set(v_of) & set(i_of))]
        how = "cooperative boxes (other classes: side boxes)"
    for v, i, name in pairs:
        veh_boxes[v]["id"] = inf_boxes[i]["id"] = name
    return how


def _timestamp(entry: dict | None, path: Path) -> float | None:
    if entry is None or "pointcloud_timestamp" not in entry:
        return None
    value = entry["pointcloud_timestamp"]
    if isinstance(value, str) and value.isdigit() and len(value) <= 20:
        value = int(value)
    return number(value, path, f"{entry['_where']}.pointcloud_timestamp", 1e20) / 1e6


def _frame(reader, entry, infos, where: Path, key: str, gate_m: float) -> tuple[int, ImportedFrame]:
    """(episode, frame) of one cooperative frame pair."""
    veh = _stem(field(entry, "vehicle_pointcloud_path", where, key), where, f"{key}.vehicle_pointcloud_path")  # fmt: skip
    inf = _stem(field(entry, "infrastructure_pointcloud_path", where, key), where, f"{key}.infrastructure_pointcloud_path")  # fmt: skip
    offset_entry = entry.get("system_error_offset") or {}
    if not isinstance(offset_entry, dict):
        raise ImportFormatError(where, f"{key}.system_error_offset: expected {{delta_x, delta_y}}")
    offset = tuple(
        number(offset_entry.get(a, 0.0), where, f"{key}.system_error_offset.{a}", 1e3)
        for a in ("delta_x", "delta_y")
    )
    vehicle, body, roadside, known = _poses(reader, veh, inf, offset, where, key)
    veh_boxes = read_boxes(reader.path(f"vehicle-side/label/lidar/{veh}.json", where, key))
    inf_boxes = read_boxes(reader.path(f"infrastructure-side/label/virtuallidar/{inf}.json", where, key))  # fmt: skip
    coop = None
    label = entry.get("cooperative_label_path")
    if label is not None and known:
        path = confined(reader.root, label, where, f"{key}.cooperative_label_path")
        if path.exists():
            reader.used.add(path)
            coop = _cooperative_boxes(path)
    how = _ids(veh_boxes, inf_boxes, vehicle, roadside, coop, gate_m)
    view1, found1 = side_view(f"vehicle:{veh}", "vehicle", vehicle, body, veh_boxes)
    view2, found2 = side_view(f"infrastructure:{inf}", "roadside", roadside, roadside, inf_boxes)
    ids1 = {o.id for o in found1}
    objects = found1 + [o for o in found2 if o.id not in ids1]  # a shared object: the vehicle's box
    v_info, i_info = infos["vehicle"].get(veh), infos["infrastructure"].get(inf)
    t_veh = _timestamp(v_info, reader.root / "vehicle-side" / "data_info.json")
    t_inf = _timestamp(i_info, reader.root / "infrastructure-side" / "data_info.json")
    episode = v_info["_episode"] if v_info is not None else 0
    meta = {
        "source": SOURCE["kind"],
        "vehicle_frame": veh,
        "infrastructure_frame": inf,
        "system_error_offset": list(offset),
        "links_from": how,
        "link_gate_m": gate_m,
        "world": "vehicle calibration" if known else "vehicle LiDAR frame",
    }
    if t_veh is not None and t_inf is not None:
        meta["time_offset_s"] = t_veh - t_inf
    return episode, ImportedFrame(t_veh, (view1, view2), objects, meta)


def import_dair_v2x(
    src: str | Path, out: str | Path, link_gate_m: float | None = None
) -> ImportResult:
    """Convert the DAIR-V2X-C folder ``src`` (``cooperative-vehicle-infrastructure``) into a
    box-only dataset at ``out`` (a new or empty folder); ``link_gate_m``: the link gate
    (default :data:`LINK_GATE_M`). ``ImportFormatError`` (one line naming file and key) for
    malformed input; nothing is written then.

    >>> import_dair_v2x("cooperative-vehicle-infrastructure", "data/dair-v2x-c")  # doctest: +SKIP
    ImportResult(out=PosixPath('data/dair-v2x-c'), episodes={...}, views=2, checksum='...')
    """
    gate = LINK_GATE_M if link_gate_m is None else float(link_gate_m)
    if not 0 < gate <= 10:
        raise ValueError(f"link gate: expected metres in (0, 10], got {gate}")
    root, out = Path(src), check_out(out)  # checked before Path("") could become "."
    if not root.is_dir():
        raise ImportFormatError(root, "not a folder")
    reader = _Reader(root)
    info = reader.optional("cooperative/data_info.json") or reader.optional(
        "cooperative/selected_data_info.json"
    )
    if info is None:
        raise ImportFormatError(root / "cooperative" / "data_info.json", "missing file")
    entries = read_json(info)
    if not isinstance(entries, list) or not entries:
        raise ImportFormatError(info, "top level: expected a non-empty list of frame pairs")
    infos = {side: reader.side_info(side) for side in _SIDES}
    by_episode: dict[int, list[ImportedFrame]] = {}
    seen: dict[str, str] = {}
    for k, entry in enumerate(entries):
        episode, frame = _frame(reader, entry, infos, info, f"[{k}]", gate)
        first = seen.setdefault(frame.meta["vehicle_frame"], f"[{k}]")
        if first != f"[{k}]":
            raise ImportFormatError(
                info,
                f"[{k}].vehicle_pointcloud_path: frame {frame.meta['vehicle_frame']!r} already at {first}",
            )
        by_episode.setdefault(episode, []).append(frame)
    records, clock = [], TimeNote()
    for episode in sorted(by_episode):
        frames = relative_times(
            by_episode[episode], root / "vehicle-side" / "data_info.json", f"batch {episode}",
            ordered=False, note=clock,
        )  # fmt: skip
        records += sequence_records(episode, 0, episode, frames, False)
    linked = sum(
        len({o.id for o in f.objects if o.id[0] in "cs"})
        for frames in by_episode.values()
        for f in frames
    )
    source = SOURCE | {"folder": root.name, "frame_pairs": len(entries), "linked_objects": linked}
    source |= {"link_gate_m": gate, "time": clock.as_manifest()}
    source["sha256"] = _digest(root, reader.used)
    return write_box_dataset(out, records, SCENARIO_NAME, source)


def _digest(root: Path, files) -> str:
    """SHA-256 over the files the import read (relative name and SHA-256 of each)."""
    h = hashlib.sha256()
    for path in sorted(set(files)):
        h.update(path.relative_to(root).as_posix().encode() + b"\0")
        h.update(hashlib.sha256(read_bytes(path)).digest())
    return h.hexdigest()


__all__ = ["COOPERATIVE_CLASSES", "LINK_GATE_M", "SCENARIO_NAME", "import_dair_v2x", "linked_pairs"]
