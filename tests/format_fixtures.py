"""Small folders written to the field's published layouts (V2X-Seq-SPD, OPV2V / V2XSet,
V2V4Real), from world boxes whose truth the tests know: a few frames, two and three agents, an
object one side alone sees, a track that leaves and returns, infrastructure agents."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import yaml

from cadsim.importers.carla_frame import mirrored, pose_angles

# World boxes per frame: id -> (x, y, z, yaw rad, l, w, h). "d" leaves at frame 1 and returns.
WORLD = [
    {"a": (12.0, 2.0, 0.8, 0.3, 4.5, 1.9, 1.6), "b": (16.0, -3.0, 0.9, -1.2, 10.0, 2.5, 3.2),
     "c": (9.0, 6.0, 0.9, 2.0, 0.6, 0.6, 1.8), "d": (22.0, 1.0, 0.8, 0.0, 4.2, 1.8, 1.5),
     "e": (-5.0, 0.0, 0.8, 0.1, 4.0, 1.8, 1.5)},
    {"a": (12.5, 2.1, 0.8, 0.3, 4.5, 1.9, 1.6), "b": (16.0, -3.5, 0.9, -1.2, 10.0, 2.5, 3.2),
     "c": (9.1, 6.0, 0.9, 2.0, 0.6, 0.6, 1.8), "e": (-4.5, 0.0, 0.8, 0.1, 4.0, 1.8, 1.5)},
    {"a": (13.0, 2.2, 0.8, 0.3, 4.5, 1.9, 1.6), "b": (16.0, -4.0, 0.9, -1.2, 10.0, 2.5, 3.2),
     "c": (9.2, 6.0, 0.9, 2.0, 0.6, 0.6, 1.8), "d": (23.0, 1.0, 0.8, 0.0, 4.2, 1.8, 1.5),
     "e": (-4.0, 0.0, 0.8, 0.1, 4.0, 1.8, 1.5)},
]  # fmt: skip
VEHICLE_SEES = {"a", "b", "c", "d"}
INFRA_SEES = {"a", "b", "c", "e"}  # "e": the roadside unit alone; "d": the vehicle alone


def rotation(yaw: float, pitch: float = 0.0, roll: float = 0.0) -> np.ndarray:
    cy, sy, cp, sp, cr, sr = (
        np.cos(yaw),
        np.sin(yaw),
        np.cos(pitch),
        np.sin(pitch),
        np.cos(roll),
        np.sin(roll),
    )
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return rz @ ry @ rx


def transform(x, y, z, yaw, pitch=0.0, roll=0.0) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = rotation(yaw, pitch, roll)
    t[:3, 3] = (x, y, z)
    return t


def vehicle_lidar(frame: int) -> np.ndarray:
    return transform(0.5 * frame, 0.1 * frame, 1.9, 0.1 + 0.01 * frame, 0.004, -0.003)


INFRA_LIDAR = transform(20.0, 9.0, 6.0, -2.5, 0.0)
NOVATEL_IN_LIDAR = transform(-1.0, 0.0, -1.0, 0.0)  # novatel -> lidar
OFFSET = (0.5, -0.25)


def _labels(sensor: np.ndarray, boxes: dict, ids: set, track0: int) -> list[dict]:
    inv = np.linalg.inv(sensor)
    out = []
    for oid in sorted(ids & set(boxes)):
        x, y, z, yaw, length, w, h = boxes[oid]
        c = inv @ [x, y, z, 1.0]
        d = inv[:3, :3] @ [np.cos(yaw), np.sin(yaw), 0.0]
        out.append({
            "token": f"{'inf' if track0 else 'veh'}-tok-{oid}", "type": "Car" if length < 8 else "Bus", "track_id": f"{track0 + ord(oid):06d}",
            "3d_dimensions": {"h": h, "w": w, "l": length}, "3d_location": dict(zip("xyz", c[:3].tolist(), strict=True)),
            "rotation": float(np.arctan2(d[1], d[0])),
        })  # fmt: skip
    return out


def _rt(t: np.ndarray) -> dict:
    return {"rotation": t[:3, :3].tolist(), "translation": [[v] for v in t[:3, 3].tolist()]}


def write_v2x_seq(root: Path) -> Path:
    """A V2X-Seq-SPD folder: one cooperative sequence "0010" of three frames."""

    def dump(rel: str, data) -> None:
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(data), encoding="utf-8")

    coop, veh_info, inf_info = [], [], []
    for k, boxes in enumerate(WORLD):
        vf, inf = f"{10 + k:06d}", f"{20 + k:06d}"
        t_v, t_i = 1_626_000_000_000_000 + 100_000 * k, 1_626_000_000_000_000 + 100_000 * k - 30_000
        veh_info.append({"frame_id": vf, "sequence_id": "0010", "pointcloud_timestamp": str(t_v),
                         "image_timestamp": str(t_v), "label_lidar_std_path": f"label/lidar/{vf}.json",
                         "calib_lidar_to_novatel_path": f"calib/lidar_to_novatel/{vf}.json",
                         "calib_novatel_to_world_path": f"calib/novatel_to_world/{vf}.json"})  # fmt: skip
        inf_info.append({"frame_id": inf, "sequence_id": "0010", "pointcloud_timestamp": str(t_i),
                         "label_lidar_std_path": f"label/virtuallidar/{inf}.json",
                         "calib_virtuallidar_to_world_path": f"calib/virtuallidar_to_world/{inf}.json"})  # fmt: skip
        coop.append({"vehicle_frame": vf, "infrastructure_frame": inf, "vehicle_sequence": "0010",
                     "infrastructure_sequence": "0010",
                     "system_error_offset": {"delta_x": OFFSET[0], "delta_y": OFFSET[1]}})  # fmt: skip
        lidar = vehicle_lidar(k)
        novatel = lidar @ NOVATEL_IN_LIDAR
        dump(f"vehicle-side/label/lidar/{vf}.json", _labels(lidar, boxes, VEHICLE_SEES, 0))
        dump(
            f"vehicle-side/calib/lidar_to_novatel/{vf}.json",
            {"transform": _rt(np.linalg.inv(NOVATEL_IN_LIDAR))},
        )
        dump(f"vehicle-side/calib/novatel_to_world/{vf}.json", _rt(novatel))
        dump(
            f"infrastructure-side/label/virtuallidar/{inf}.json",
            _labels(INFRA_LIDAR, boxes, INFRA_SEES, 1000),
        )
        published = INFRA_LIDAR.copy()
        published[:2, 3] -= OFFSET  # the importer adds the system error offset back
        dump(f"infrastructure-side/calib/virtuallidar_to_world/{inf}.json", _rt(published))
        links = [{"track_id": f"c{oid}", "type": "Car", "veh_frame_id": vf, "inf_frame_id": inf,
                  "veh_token": f"veh-tok-{oid}" if oid in VEHICLE_SEES else "",
                  "inf_token": f"inf-tok-{oid}" if oid in INFRA_SEES else "",
                  "veh_track_id": f"{ord(oid):06d}" if oid in VEHICLE_SEES else "-1",
                  "inf_track_id": f"{1000 + ord(oid):06d}" if oid in INFRA_SEES else "-1"}
                 for oid in sorted(boxes)]  # fmt: skip
        dump(f"cooperative/label/{vf}.json", links)
    dump("vehicle-side/data_info.json", veh_info)
    dump("infrastructure-side/data_info.json", inf_info)
    dump("cooperative/data_info.json", coop)
    return root


AGENT_SENSORS = {  # agent id -> sensor pose (right-handed world)
    7: transform(0.0, 0.0, 1.9, 0.1),
    3: transform(30.0, 4.0, 1.9, 3.0),
    -1: transform(20.0, 9.0, 6.0, -2.5, -0.1),
}
AGENT_SEES = {7: {"a", "b", "c", "d"}, 3: {"a", "b", "d", "e"}, -1: {"a", "b", "c", "e"}}
ACTOR = {"a": 101, "b": 102, "c": 103, "d": 104, "e": 105}


def _vehicles(boxes: dict, ids: set) -> dict:
    out = {}
    for oid in sorted(ids & set(boxes)):
        x, y, z, yaw, length, w, h = boxes[oid]
        out[ACTOR[oid]] = {"angle": [0.0, float(-np.degrees(yaw)), 0.0], "center": [0.0, 0.0, 0.0],
                           "extent": [length / 2, w / 2, h / 2], "location": [x, -y, z], "speed": 18.0}  # fmt: skip
    return out


def write_opv2v(root: Path, v2v4real: bool = False, agents=(7, 3, -1)) -> Path:
    """An OPV2V split with one scenario; ``v2v4real``: poses as rotation + translation."""
    scenario = root / "2021_08_22_21_41_24"
    for agent in agents:
        folder = scenario / str(agent)
        folder.mkdir(parents=True, exist_ok=True)
        for k, boxes in enumerate(WORLD):
            sensor = AGENT_SENSORS[agent].copy()
            sensor[0, 3] += 0.3 * k
            body = sensor @ transform(-1.0, 0.0, -1.2, 0.0)
            if v2v4real:
                carla = mirrored(sensor)
                pose = {"rotation": carla[:3, :3].tolist(), "translation": carla[:3, 3].tolist()}
                ego = mirrored(body)[:3, :3].tolist(), mirrored(body)[:3, 3].tolist()
                true_ego = {"rotation": ego[0], "translation": ego[1]}
            else:
                pose, true_ego = pose_angles(sensor), pose_angles(body)
            data = {"lidar_pose": pose, "true_ego_pos": true_ego, "predicted_ego_pos": true_ego,
                    "ego_speed": 18.0, "vehicles": _vehicles(boxes, AGENT_SEES[agent])}  # fmt: skip
            (folder / f"{68 + 2 * k:06d}.yaml").write_text(yaml.safe_dump(data), encoding="utf-8")
    return root


# --- the field's real encodings (the project's own files, reproducing the encodings only) ---


def write_v2v4real(root: Path, numpy_major: int = 1) -> Path:
    """A V2V4Real-encoded scenario of two vehicles (0, 1), three frames: yaml written by PyYAML's
    default dumper from numpy values (``lidar_pose`` a 4×4 array, ``gps`` numpy scalars), poses
    in a right-handed world, ``vehicles`` keyed by each vehicle's local id with ``ass_id`` the
    cross-vehicle identity. ``numpy_major`` 1 writes the ``numpy.core`` spelling of the real
    files, 2 the ``numpy._core`` one numpy 2.x writes.

    Objects: "a", "b" seen by both (ass_id 7, 8; different local keys), "c" seen by both with
    ass_id -1 under the same local key 5 (must never be linked), "d" vehicle 0 only."""
    scenario = root / "testoutput_CAV_data_2022-03-15-09-54-40_1"
    sees = {0: {"a": (3, 7), "b": (4, 8), "c": (5, -1), "d": (6, -1)},
            1: {"a": (11, 7), "b": (12, 8), "c": (5, -1)}}  # fmt: skip
    sensors = {0: transform(0.0, 0.0, 1.9, 0.1), 1: transform(30.0, 4.0, 1.9, 3.0)}
    for agent, seen in sees.items():
        folder = scenario / str(agent)
        folder.mkdir(parents=True, exist_ok=True)
        for k, boxes in enumerate(WORLD):
            sensor = sensors[agent].copy()
            sensor[0, 3] += 0.3 * k
            vehicles = {}
            for oid, (key, ass) in seen.items():
                if oid not in boxes:
                    continue
                x, y, z, yaw, length, w, h = boxes[oid]
                vehicles[key] = {
                    "angle": [0.0, float(np.degrees(yaw)), 0.0], "ass_id": ass,
                    "center": [0.0, 0.0, 0.0], "extent": [length / 2, w / 2, h / 2],
                    "location": [np.float64(x), np.float64(y), np.float64(z)], "obj_type": "Car",
                }  # fmt: skip
            data = {"ego_speed": 0, "gps": [np.float64(v) for v in (39.9, -83.0, 228.5, 2.3, 0.1, 0.0)],
                    "lidar_pose": sensor, "true_ego_pos": sensor, "vehicles": vehicles}  # fmt: skip
            text = yaml.dump(data)  # PyYAML's default dumper, as the dataset was written
            if numpy_major == 1:
                text = text.replace("numpy._core.multiarray", "numpy.core.multiarray")
            (folder / f"{k:06d}.yaml").write_text(text, encoding="utf-8")
    return root


DAIR_CLASSES = {"a": "Car", "b": "Car", "c": "Pedestrian", "d": "Car", "e": "Van"}


def _dair_labels(sensor: np.ndarray, boxes: dict, ids: set, shift: dict) -> list[dict]:
    inv = np.linalg.inv(sensor)
    out = []
    for oid in sorted(ids & set(boxes)):
        x, y, z, yaw, length, w, h = boxes[oid]
        c = inv @ [x + shift.get(oid, 0.0), y, z, 1.0]
        d = inv[:3, :3] @ [np.cos(yaw), np.sin(yaw), 0.0]
        out.append({"type": DAIR_CLASSES[oid], "truncated_state": "0", "occluded_state": "0", "alpha": "0",
                    "3d_dimensions": {"h": h, "w": w, "l": length},
                    "3d_location": dict(zip("xyz", c[:3].tolist(), strict=True)),
                    "rotation": float(np.arctan2(d[1], d[0]))})  # fmt: skip
    return out


def _corners(box) -> list[list[float]]:
    x, y, z, yaw, length, w, h = box
    r = rotation(yaw)
    local = np.array([[sx * length / 2, sy * w / 2, sz * h / 2]
                      for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])  # fmt: skip
    return (local @ r.T + [x, y, z]).tolist()


def write_dair_v2x(
    root: Path, cooperative: bool = True, world: bool = True, i2v: bool = False, skew: float = 0.0
) -> Path:
    """A DAIR-V2X-C folder (``cooperative-vehicle-infrastructure``) of the three frames of
    :data:`WORLD`: side labels without track ids or tokens, ``cooperative/data_info.json`` of
    file paths, the world calibrations (``world``), ``cooperative/calib/lidar_i2v`` (``i2v``,
    its rotation scaled by 1 + ``skew``: not orthonormal), ``label_world`` boxes
    (``cooperative``) of the vehicle classes seen by both sides but "b": the roadside's "b" is
    0.6 m off, within the gate, yet the fused label keeps "a" only. Frames 0, 1 are batch 3,
    frame 2 batch 4."""

    def dump(rel: str, data) -> None:
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(data), encoding="utf-8")

    coop, veh_info, inf_info = [], [], []
    for k, boxes in enumerate(WORLD):
        vf, inf = f"{10 + k:06d}", f"{20 + k:06d}"
        t_v = 1_626_000_000_000_000 + 100_000 * k
        batch = "3" if k < 2 else "4"
        veh_info.append({"image_path": f"image/{vf}.jpg", "pointcloud_path": f"velodyne/{vf}.pcd",
                         "pointcloud_timestamp": str(t_v), "batch_id": batch})  # fmt: skip
        inf_info.append({"image_path": f"image/{inf}.jpg", "pointcloud_path": f"velodyne/{inf}.pcd",
                         "pointcloud_timestamp": str(t_v - 30_000), "batch_id": batch})  # fmt: skip
        coop.append({"infrastructure_image_path": f"infrastructure-side/image/{inf}.jpg",
                     "infrastructure_pointcloud_path": f"infrastructure-side/velodyne/{inf}.pcd",
                     "vehicle_image_path": f"vehicle-side/image/{vf}.jpg",
                     "vehicle_pointcloud_path": f"vehicle-side/velodyne/{vf}.pcd",
                     "cooperative_label_path": f"cooperative/label_world/{vf}.json",
                     "system_error_offset": {"delta_x": OFFSET[0], "delta_y": OFFSET[1]}})  # fmt: skip
        lidar = vehicle_lidar(k)
        novatel = lidar @ NOVATEL_IN_LIDAR
        dump(f"vehicle-side/label/lidar/{vf}.json", _dair_labels(lidar, boxes, VEHICLE_SEES, {}))
        dump(f"infrastructure-side/label/virtuallidar/{inf}.json",
             _dair_labels(INFRA_LIDAR, boxes, INFRA_SEES, {"b": 0.6}))  # fmt: skip
        if world:
            dump(f"vehicle-side/calib/lidar_to_novatel/{vf}.json",
                 {"transform": _rt(np.linalg.inv(NOVATEL_IN_LIDAR))})  # fmt: skip
            dump(f"vehicle-side/calib/novatel_to_world/{vf}.json", _rt(novatel))
            published = INFRA_LIDAR.copy()
            published[:2, 3] -= OFFSET  # the importer adds the system error offset back
            dump(f"infrastructure-side/calib/virtuallidar_to_world/{inf}.json", _rt(published))
        if i2v:
            t = np.linalg.inv(lidar) @ INFRA_LIDAR
            rt = _rt(t)
            rt["rotation"] = (np.asarray(rt["rotation"]) * (1.0 + skew)).tolist()
            dump(f"cooperative/calib/lidar_i2v/{vf}.json", rt)
        if cooperative:
            fused = [{"type": DAIR_CLASSES[o], "world_8_points": _corners(boxes[o]),
                      "system_error_offset": {"delta_x": OFFSET[0], "delta_y": OFFSET[1]}}
                     for o in sorted(VEHICLE_SEES & INFRA_SEES & set(boxes)) if o == "a"]  # fmt: skip
            dump(f"cooperative/label_world/{vf}.json", fused)
    dump("vehicle-side/data_info.json", veh_info)
    dump("infrastructure-side/data_info.json", inf_info)
    dump("cooperative/data_info.json", coop)
    return root
