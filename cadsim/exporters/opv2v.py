"""``cadsim export opv2v``: a cadsim dataset in the OPV2V layout, so an OpenCOOD-based pipeline
reads cadsim's scenarios, and ``cadsim import opv2v`` reads them back as the same association
problems.

Layout written: ``DIR/<scenario>/<agent id>/<frame>.yaml`` (+ ``<frame>_camera0.png`` and
``<frame>_depth0.npy`` for records with images) and ``DIR/<scenario>/data_protocol.yaml``. A
scenario is one sequence (frames 0 …) of a sequence dataset, else one record (frame 0); its
name is the record name of its first frame. Agents: the record's views in order, vehicles
numbered 1, 2, … and roadside units −1, −2, … (V2XSet's convention; ``import opv2v`` orders
them back the same way); other objects get actor ids from 1000 in the order of their cadsim
ids. Per agent and frame (:func:`agent_document`):

- ``lidar_pose``: the view's sensor — a camera record's camera, a box record's LiDAR — as
  ``[x, y, z, roll, yaw, pitch]`` (metres, degrees, CARLA's left-handed world,
  :mod:`cadsim.importers.carla_frame`), x along the optical axis;
- ``true_ego_pos``: the observer's body pose, ``ego_speed`` its speed (km/h);
  ``predicted_ego_pos``: the pose its localisation
  reported (the record's own prior; absent when the record has none);
- ``vehicles``: the view's detections (every class, not only vehicles): ``location`` (box
  centre), ``center`` [0, 0, 0], ``angle`` [0, yaw, pitch], ``extent`` (half sizes), ``speed``
  (km/h), ``obj_type`` (the class a matcher sees);
- ``camera0`` (records with images): ``cords`` (camera pose), ``intrinsic`` (3×3 K, pixels) and
  ``extrinsic`` (4×4 LiDAR → camera, OpenCV axes);
- ``data_protocol.yaml``: ``cadsim`` {``episode``, ``slot``, ``sim_seed``, ``start_time``,
  ``interval_s``, ``ids`` {actor id: cadsim object id}, and for records with a prior the
  ``prior_*`` keys of :func:`prior_protocol`}, so a re-import keeps the record identity, the
  object and observer ids (and with them the presets' draws) and the prior the matchers saw:
  its stated uncertainty and its message latency.

Each agent's frame is written by :func:`write_agent_frame`; records with LiDAR points add the
sweep as ``<frame>.pcd`` in the agent's sensor frame (``cadsim.exporters.pcd``). The output folder must be new or empty.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cadsim import portable_math as pm
from cadsim.dataset import layout
from cadsim.dataset.output_folder import check_output_folder
from cadsim.exporters.pcd import agent_point_cloud
from cadsim.exporters.view_boxes import ViewBoxes, snapshot_views
from cadsim.importers.carla_frame import mirrored_points, pose_angles
from cadsim.importers.sensor_frame import sensor_pose

ACTOR_BASE = 1000
_KMH = 3.6
_CAMERA_AXES = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])  # LiDAR → OpenCV


@dataclass(frozen=True)
class ExportResult:
    """What an export wrote: the folder, scenarios, agent-frames."""

    out: Path
    scenarios: int
    files: int


def _yaml(data) -> bytes:
    import yaml

    # insertion order kept: ``vehicles`` lists the view's detections in their order
    return yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=100).encode()


def _agent_ids(views: list[ViewBoxes]) -> list[int]:
    vehicles = roadside = 0
    ids = []
    for view in views:
        if view.kind == "roadside":
            roadside += 1
            ids.append(-roadside)
        else:
            vehicles += 1
            ids.append(vehicles)
    return ids


def _actors(frames: list[list[ViewBoxes]], agents: list[int]) -> dict[str, int]:
    """{cadsim object id: actor id} of a scenario: observers their agent id, the rest 1000 + rank."""
    actors = {v.observer_id: a for v, a in zip(frames[0], agents, strict=True) if v.observer_id}
    others = sorted(
        {i for views in frames for v in views for i in v.detections.object_ids} - set(actors)
    )
    return actors | {oid: ACTOR_BASE + k for k, oid in enumerate(others)}


def agent_document(view: ViewBoxes, actors: dict[str, int]) -> dict:
    """The OPV2V yaml of one agent's frame (module docstring)."""
    d = view.directions
    yaw = -np.degrees(pm.arctan2(d[:, 1], d[:, 0])).reshape(-1)
    pitch = np.degrees(pm.arctan2(d[:, 2], np.hypot(d[:, 0], d[:, 1]))).reshape(-1)
    location = mirrored_points(view.world)
    vehicles = {}
    for k, oid in enumerate(view.detections.object_ids):
        vehicles[actors[oid]] = {
            "angle": [0.0, float(yaw[k]), float(pitch[k])],
            "center": [0.0, 0.0, 0.0],
            "extent": [float(s) / 2.0 for s in view.sizes[k]],
            "location": [float(v) for v in location[k]],
            "speed": float(view.speeds[k]) * _KMH,
            "obj_type": view.classes[k],
        }
    sensor = sensor_pose(view.camera)
    document = {"lidar_pose": pose_angles(sensor), "true_ego_pos": pose_angles(view.body)}
    document["ego_speed"] = float(view.ego_speed) * _KMH
    if view.reported_body is not None:
        document["predicted_ego_pos"] = pose_angles(view.reported_body)
    document["vehicles"] = vehicles
    if view.pixel_boxes is not None:
        extrinsic = np.eye(4)
        extrinsic[:3, :3] = _CAMERA_AXES
        document["camera0"] = {
            "cords": pose_angles(sensor),
            "intrinsic": view.camera.intrinsics().tolist(),
            "extrinsic": extrinsic.tolist(),
        }
    return document


def write_agent_frame(folder: Path, frame: str, document: dict, files: dict[str, bytes]) -> int:
    """Write one agent's frame into its folder: ``<frame>.yaml`` and ``<frame>_<name>`` for
    each of ``files`` (images; a point cloud would go here too); returns the files written."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{frame}.yaml").write_bytes(_yaml(document))
    for name, data in files.items():
        (folder / f"{frame}_{name}").write_bytes(data)
    return 1 + len(files)


def _images(pair, view: ViewBoxes) -> dict[str, bytes]:
    """A camera record's colour image and clean depth of ``view`` (none for box records)."""
    if view.pixel_boxes is None or not pair.has_images:
        return {}
    colour = (pair.path / layout.view_png(view.view)).read_bytes()
    depth = np.load(pair.path / layout.DEPTH_NPZ)[f"depth{view.view}"]
    buffer = io.BytesIO()
    np.save(buffer, depth.astype(np.float32), allow_pickle=False)
    return {"camera0.png": colour, "depth0.npy": buffer.getvalue()}


def prior_protocol(pair) -> dict:
    """The ``data_protocol.yaml`` keys that carry ``pair``'s localisation prior over to a
    re-import (docs/external-data.md): ``prior_sigma_m`` (the stated position uncertainty a
    matcher is told, metres: ``Problem.world_sigma``), ``prior_latency_s`` (the age of the
    other agents' messages, seconds) and, for a simulated prior, the model it was drawn with
    (``prior_position_sigma_m``, ``prior_yaw_sigma_deg``, ``prior_preset`` when one is set)."""
    prior = pair.record.get("prior") or {}
    if prior.get("kind") == "stored":  # an imported record: its messages are already as sent
        return {"prior_sigma_m": float(prior["world_sigma_m"]), "prior_latency_s": 0.0}
    config = pair.localisation[0]
    out = {
        "prior_sigma_m": float(config.stated_sigma_m),
        "prior_latency_s": float(config.latency_s),
        "prior_position_sigma_m": float(config.position_sigma_m),
        "prior_yaw_sigma_deg": float(config.yaw_sigma_deg),
    }
    return out if config.preset is None else out | {"prior_preset": config.preset}


def export_opv2v(dataset: str | Path, out: str | Path) -> ExportResult:
    """Write the dataset at ``dataset`` (verified first) in the OPV2V layout at ``out`` (a new
    or empty folder).

    >>> export_opv2v("data/cad-v2x", "export/cad-v2x-opv2v")  # doctest: +SKIP
    ExportResult(out=PosixPath('export/cad-v2x-opv2v'), scenarios=25, files=100)
    """
    from cadsim.dataset import Dataset

    out = check_output_folder(out, resumable=False)
    ds = Dataset(dataset, verify=True)
    units = [[p.index for p in frames] for frames in ds.iter_sequences()]
    files = 0
    for unit in units:
        first = ds[unit[0]]
        frames = [snapshot_views(ds, k) for k in unit]
        agents = _agent_ids(frames[0])
        actors = _actors(frames, agents)
        scenario = out / first.name
        for f, (k, views) in enumerate(zip(unit, frames, strict=True)):
            pair = ds[k]
            for view, agent in zip(views, agents, strict=True):
                document = agent_document(view, actors)
                files += write_agent_frame(
                    scenario / str(agent), f"{f:06d}", document, _images(pair, view)
                )
                cloud = agent_point_cloud(pair, view.view)  # records with LiDAR points
                if cloud is not None:
                    (scenario / str(agent) / f"{f:06d}.pcd").write_bytes(cloud)
                    files += 1
        sequence = first.record.get("sequence") or {}
        protocol = {"episode": first.episode, "slot": first.slot, "sim_seed": first.sim_seed}
        start = sequence.get("start_time", first.record.get("time"))
        if start is not None:
            protocol["start_time"] = float(start)
        if sequence.get("interval_s") is not None:
            protocol["interval_s"] = float(sequence["interval_s"])
        protocol["ids"] = {
            actor: oid for oid, actor in sorted(actors.items(), key=lambda kv: kv[1])
        }
        if frames[0][0].reported_body is not None:  # the records have a prior to carry over
            protocol |= prior_protocol(first)
        (scenario / "data_protocol.yaml").write_bytes(_yaml({"cadsim": protocol}))
    return ExportResult(out, len(units), files)


__all__ = [
    "ExportResult", "agent_document", "export_opv2v", "prior_protocol", "write_agent_frame",
]  # fmt: skip
