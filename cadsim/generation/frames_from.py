"""A two-sensor split from the camera split of the same frames: the LiDAR swept over records
that a camera-only generation already rendered, instead of simulating and rendering them again.

A scenario with ``sensor = "both"`` accepts a pair by its camera detections, with every seed
drawn from the frame's identity (``cadsim.dataset.seeds``), so its records are the camera
scenario's records plus each view's LiDAR (``lidar.npz`` and two keys per observer in
``record.json``). When a complete camera-only dataset (the *frames*) was generated with the same
generation settings and root seed — the scenario files may differ only in ``sensor``, ``[lidar]``
and their comments — an episode whose records the frames hold is derived from them: the
snapshot is rebuilt from the record's stored objects (world frame, as the simulation gave them),
the LiDAR observes it with each view's own seed, and the record's bytes are those a full
generation writes (``tests/test_lidar_records.py`` compares them). Episodes the frames lack are
simulated as usual. Camera frames rendered by another version of the renderer are reused as
they are, as a resumed generation reuses its own.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Callable
from pathlib import Path

from cadsim.camera import Camera
from cadsim.dataset import layout
from cadsim.dataset.encoding import json_bytes, npz_bytes
from cadsim.dataset.lidar_points import view_arrays as lidar_view_arrays
from cadsim.world import Snapshot, WorldObject

log = logging.getLogger(__name__)

SENSOR_KEYS = ("sensor", "lidar", "scenario_sha256")
"""Generation settings a two-sensor scenario may differ in from the camera scenario it adds to."""


def usable_frames(frames_from: str | Path | None, config: dict) -> str | None:
    """``frames_from`` as a path when it is a complete camera-only dataset generated with
    ``config`` (a two-sensor generation's settings) but for :data:`SENSOR_KEYS`; else None,
    logged with the reason (the generation then simulates every episode)."""
    if frames_from is None or config.get("sensor") != "both":
        return None
    folder = Path(frames_from)
    try:
        manifest = json.loads((folder / layout.MANIFEST).read_text())
    except (OSError, ValueError):
        log.info("%s: no readable manifest; every episode is simulated", folder)
        return None
    theirs = manifest.get("generation") if isinstance(manifest, dict) else None
    if not manifest.get("complete") or not isinstance(theirs, dict):
        log.info("%s: not a complete dataset; every episode is simulated", folder)
        return None
    if theirs.get("sensor", "camera") != "camera" or _without_sensor(theirs) != _without_sensor(config):  # fmt: skip
        log.info("%s: other generation settings or seed; every episode is simulated", folder)
        return None
    return str(folder.resolve())


def _without_sensor(config: dict) -> dict:
    return {k: v for k, v in config.items() if k not in SENSOR_KEYS}


def lidar_added(record_dir: Path, sweep: Callable) -> dict[str, bytes]:
    """The two-sensor record's files from a camera-only record folder: its files as they are,
    ``lidar.npz`` and ``record.json`` with each observer's LiDAR keys. ``sweep(snapshot,
    camera, observer_id, noise_seed, view)`` gives a view's LiDAR observation (view 1-based)."""
    head = json.loads((record_dir / layout.RECORD_JSON).read_text())
    snapshot = Snapshot(float(head["time"]), [WorldObject.from_dict(d) for d in head["objects"]])
    files = {name: (record_dir / name).read_bytes() for name in layout.record_files(2)}
    points = {}
    for k, entry in enumerate(head["observers"], start=1):
        camera = Camera.from_dict(entry["camera"])
        obs = sweep(snapshot, camera, entry["id"], int(entry["noise_seed"]), k)
        points |= lidar_view_arrays(k, obs.scan, obs.pose, (obs.boxes, obs.ids))
        entry["sensor"] = "camera+lidar"
        entry["lidar"] = {"pattern": obs.scan.pattern.name}
    files[layout.RECORD_JSON] = json_bytes(head)
    files[layout.LIDAR_NPZ] = npz_bytes(points)
    return files
