"""`make bench` section "dair-import": ``cadsim import dair-v2x`` on a generated folder in
DAIR-V2X-C's layout (the real data is not redistributable, so the bench writes its own).

:func:`write_dair_layout` writes ``frames`` cooperative frame pairs the way DAIR-V2X-C lays them
out: ``cooperative/data_info.json`` of file paths with ``system_error_offset``, both sides'
``data_info.json`` (``pointcloud_timestamp``, ``batch_id``: 100 frames a batch), side labels
without track ids (about 20 vehicle-side and 8 roadside boxes, 6 seen by both), the world
calibrations (``lidar_to_novatel``, ``novatel_to_world``, ``virtuallidar_to_world``) and
``label_world`` fused boxes (``world_8_points``) of the covisible vehicles. Only the import is
timed (target: 10,000 frame pairs within 5 minutes on the project's 2-core machine).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from eval.bench import Target

FRAMES = 10_000
LIMIT_S = 300.0
_CLASSES = ("Car", "Car", "Car", "Van", "Truck", "Pedestrian", "Cyclist", "Trafficcone")
_SIZES = {"Car": (4.4, 1.9, 1.5), "Van": (5.0, 2.0, 2.1), "Truck": (9.0, 2.5, 3.2),
          "Pedestrian": (0.6, 0.6, 1.7), "Cyclist": (1.8, 0.7, 1.6), "Trafficcone": (0.3, 0.3, 0.4)}  # fmt: skip


def _rt(t: np.ndarray) -> dict:
    return {"rotation": t[:3, :3].tolist(), "translation": [[v] for v in t[:3, 3].tolist()]}


def _pose(x: float, y: float, z: float, yaw: float) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = [[np.cos(yaw), -np.sin(yaw), 0.0], [np.sin(yaw), np.cos(yaw), 0.0], [0, 0, 1]]
    out[:3, 3] = (x, y, z)
    return out


def _labels(sensor: np.ndarray, centres, yaws, classes) -> list[dict]:
    inv = np.linalg.inv(sensor)
    local = centres @ inv[:3, :3].T + inv[:3, 3]
    heading = yaws - np.arctan2(sensor[1, 0], sensor[0, 0])
    out = []
    for c, h, cls in zip(local.tolist(), heading.tolist(), classes, strict=True):
        length, width, height = _SIZES[cls]
        out.append({"type": cls, "truncated_state": 0, "occluded_state": 0, "alpha": 0.0,
                    "2d_box": {"xmin": 0.0, "ymin": 0.0, "xmax": 1.0, "ymax": 1.0},
                    "3d_dimensions": {"h": height, "w": width, "l": length},
                    "3d_location": dict(zip("xyz", c, strict=True)), "rotation": h})  # fmt: skip
    return out


def _corners(centre, yaw, cls) -> list[list[float]]:
    length, width, height = _SIZES[cls]
    signs = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)], dtype=float)
    local = signs * [length / 2, width / 2, height / 2]
    return (local @ _pose(0, 0, 0, yaw)[:3, :3].T + centre).tolist()


def write_dair_layout(root: Path, frames: int = FRAMES, seed: int = 0) -> Path:
    """Write a DAIR-V2X-C-layout folder of ``frames`` frame pairs at ``root`` (module docstring)."""
    rng = np.random.default_rng(seed)
    files: dict[str, object] = {}
    coop, veh_info, inf_info = [], [], []
    novatel_in_lidar = _pose(-1.0, 0.0, -1.0, 0.0)
    for k in range(frames):
        vf, inf = f"{k:06d}", f"{k + 500_000:06d}"
        batch = str(k // 100)
        offset = rng.uniform(-1.2, 1.2, 2)
        vehicle = _pose(*rng.uniform(-30, 30, 2), 1.9, rng.uniform(-np.pi, np.pi))
        roadside = _pose(0.0, 0.0, 6.0, rng.uniform(-np.pi, np.pi))
        shared = rng.uniform(-25, 25, (6, 3)) * [1, 1, 0] + [0, 0, 0.8]
        veh_only = (
            rng.uniform(-60, 60, (14, 3)) * [1, 1, 0] + [0, 0, 0.8] + vehicle[:3, 3] * [1, 1, 0]
        )
        inf_only = rng.uniform(-60, 60, (2, 3)) * [1, 1, 0] + [0, 0, 0.8]
        classes = [_CLASSES[c] for c in rng.integers(0, len(_CLASSES), 22)]
        yaws = rng.uniform(-np.pi, np.pi, 22)
        v_idx, i_idx = list(range(20)), [*range(6), 20, 21]
        centres = np.vstack([shared, veh_only, inf_only])
        t = 1_626_000_000_000_000 + 100_000 * k
        published = roadside.copy()
        published[:2, 3] -= offset
        files |= {
            f"vehicle-side/label/lidar/{vf}.json": _labels(vehicle, centres[v_idx], yaws[v_idx], [classes[i] for i in v_idx]),
            f"infrastructure-side/label/virtuallidar/{inf}.json": _labels(roadside, centres[i_idx], yaws[i_idx], [classes[i] for i in i_idx]),
            f"vehicle-side/calib/lidar_to_novatel/{vf}.json": {"transform": _rt(np.linalg.inv(novatel_in_lidar))},
            f"vehicle-side/calib/novatel_to_world/{vf}.json": _rt(vehicle @ novatel_in_lidar),
            f"infrastructure-side/calib/virtuallidar_to_world/{inf}.json": _rt(published),
            f"cooperative/label_world/{vf}.json": [
                {"type": classes[i], "world_8_points": _corners(centres[i], yaws[i], classes[i]),
                 "system_error_offset": {"delta_x": offset[0], "delta_y": offset[1]}}
                for i in range(6) if classes[i] in ("Car", "Van", "Truck")
            ],
        }  # fmt: skip
        veh_info.append({"image_path": f"image/{vf}.jpg", "pointcloud_path": f"velodyne/{vf}.pcd",
                         "pointcloud_timestamp": str(t), "batch_id": batch})  # fmt: skip
        inf_info.append({"image_path": f"image/{inf}.jpg", "pointcloud_path": f"velodyne/{inf}.pcd",
                         "pointcloud_timestamp": str(t - 40_000), "batch_id": batch})  # fmt: skip
        coop.append({"infrastructure_image_path": f"infrastructure-side/image/{inf}.jpg",
                     "infrastructure_pointcloud_path": f"infrastructure-side/velodyne/{inf}.pcd",
                     "vehicle_image_path": f"vehicle-side/image/{vf}.jpg",
                     "vehicle_pointcloud_path": f"vehicle-side/velodyne/{vf}.pcd",
                     "cooperative_label_path": f"cooperative/label_world/{vf}.json",
                     "system_error_offset": {"delta_x": offset[0], "delta_y": offset[1]}})  # fmt: skip
    files |= {"vehicle-side/data_info.json": veh_info, "infrastructure-side/data_info.json": inf_info,
              "cooperative/data_info.json": coop}  # fmt: skip
    for rel, data in files.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(data), encoding="utf-8")
    return root


def measure(frames: int = FRAMES) -> dict:
    """Seconds to write (untimed target) and to import a generated folder of ``frames`` pairs."""
    from cadsim.importers.dair_v2x import import_dair_v2x

    with tempfile.TemporaryDirectory(prefix="cadsim-dair-bench-") as tmp:
        started = time.perf_counter()
        src = write_dair_layout(Path(tmp) / "cooperative-vehicle-infrastructure", frames)
        written = time.perf_counter() - started
        started = time.perf_counter()
        result = import_dair_v2x(src, Path(tmp) / "out")
        seconds = time.perf_counter() - started
    return {"frames": frames, "write_s": written, "import_s": seconds, "records": result.records}


def dair_import_section(args: argparse.Namespace) -> list[Target]:
    """Time ``cadsim import dair-v2x`` on 10,000 generated frame pairs."""
    r = measure(getattr(args, "dair_frames", None) or FRAMES)
    print(
        f"dair-v2x import: {r['records']} frame pairs in {r['import_s']:.1f} s "
        f"({1e3 * r['import_s'] / r['records']:.1f} ms each; folder written in {r['write_s']:.1f} s)"
    )
    return [Target(f"import {r['frames']} DAIR-V2X-C frame pairs", r["import_s"], LIMIT_S)]


if __name__ == "__main__":  # python -m eval.bench.dair_import [frames]
    import sys

    print(measure(int(sys.argv[1]) if len(sys.argv) > 1 else FRAMES))
