"""One frame pair of a dataset (:class:`FramePair`): two views' detections, their ground truth,
images loaded on first use, and the matching ``Problem``. Imports neither SUMO nor pyrender
(``redetect`` imports the depth-noise and detection modules, which need only numpy/scipy/OpenCV).

The localisation prior (``FramePair.prior``, filled into ``Problem.world1/world2/world_sigma``) is
drawn here, at read time: simulated records store the pose-error parameters and seeds, the pair
places each view's detections in the world through its camera pose with that error
(``cadsim.sensing.localisation``); imported records store the prior's world positions as given.

The dataset (:class:`cadsim.dataset.reader.Dataset`) makes these; an N-view record's pairs of
views come from :class:`cadsim.dataset.multi_view.SnapshotViews`, which wraps one of them.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Sequence
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from cadsim.camera import Camera
from cadsim.dataset import layout
from cadsim.dataset.cues import CAMERA_CUES, record_cues
from cadsim.dataset.detections import ViewDetections, ground_truth_pairs
from cadsim.dataset.encoding import decode_png, load_npz
from cadsim.dataset.manifest import DatasetError
from cadsim.dataset.seeds import (
    LOCALISATION_STREAM,
    NOISE_STREAM,
    redraw_episode_seed,
    redraw_seed,
)
from cadsim.observer_pose import ObserverPose, camera_to_world
from cadsim.sensing.gnss_error import draw_error as draw_gnss_error
from cadsim.sensing.gnss_error import model_of as gnss_model
from cadsim.sensing.latency import (
    MIN_VELOCITY_FORMAT,
    delayed_positions,
    sender_offset,
    velocities_of,
)
from cadsim.sensing.localisation import LocalisationConfig
from cadsim.sensing.pose_error import PoseError, perturbed_world
from cadsim.world import WorldObject

if TYPE_CHECKING:  # imported where used: reading a dataset needs neither
    from cadsim.sensing.depth_noise import NoiseConfig
    from cadsim.sensing.detection import DetectionPlan


class FramePair:
    """One frame pair of a dataset: two views' detections plus ground truth.

    index: position in the dataset. episode, slot: the record's identity; sim_seed: its
    simulation's seed. view1, view2: ``ViewDetections`` (positions in each observer's camera
    frame, metres). gt_pairs: (k, 2) int64 (i, j) indices of the same object in view1/view2.
    cameras: the two ``Camera``s (world frame poses; None for imported records without images).
    observer_poses: the two observers' true world poses (``ObserverPose``: body origin, metres,
    and heading, radians). camera_extrinsics: per view, the 4×4 camera (OpenCV) → observer body
    transform. camera_to_world: per view, the 4×4 camera (OpenCV) → world transform. noise_rate:
    the depth-noise rate the current detections were made at. Images (color1/2, clean depth1/2,
    instance1/2) load on first use. ``prior()``: the localisation prior, see :meth:`localise`.
    """

    def __init__(
        self,
        path: Path,
        index: int,
        entry: dict,
        noise: dict,
        detection: dict,
        views: tuple[ViewDetections, ViewDetections] | None = None,
        noise_rate: float | None = None,
        *,
        record_files: tuple[str, ...] = layout.RECORD_FILES,
        localisation: tuple[LocalisationConfig, tuple[int, int]] | None | str = "record",
        view_numbers: tuple[int, int] = (1, 2),
    ) -> None:
        self.path = Path(path)
        self.index = int(index)
        self.view_numbers = (int(view_numbers[0]), int(view_numbers[1]))
        a, b = self.view_numbers
        self.name: str = entry["name"] if (a, b) == (1, 2) else f"{entry['name']}:{a}-{b}"
        self.episode = int(entry["episode"])
        self.slot = int(entry["slot"])
        self.sim_seed = int(entry["sim_seed"])
        self.checksum: str = entry["checksum"]
        self._entry = entry
        self._noise = dict(noise)
        self._detection = dict(detection)
        self._record_files = tuple(record_files)
        self._localisation = localisation  # "record": the record's own pose-error draw
        self._odometry: tuple | None = None  # a redrawn odometry (with_odometry); None: stored
        if views is None:
            what = self.path / layout.DETECTIONS_NPZ
            arrays = load_npz(str(self._file(layout.DETECTIONS_NPZ)), str(what))
            views = (
                ViewDetections.from_arrays(arrays, f"view{a}", str(what)),
                ViewDetections.from_arrays(arrays, f"view{b}", str(what)),
            )
        self.view1, self.view2 = views
        self.noise_rate = float(
            self._noise.get("noise_rate", 0.0) if noise_rate is None else noise_rate
        )

    def __repr__(self) -> str:
        return (
            f"FramePair(index={self.index}, name={self.name!r}, n1={len(self.view1)}, "
            f"n2={len(self.view2)}, covisible={len(self.gt_pairs)}, noise_rate={self.noise_rate})"
        )

    def _file(self, name: str) -> Path:
        path = self.path / name
        if not path.is_file():
            raise DatasetError(f"{path}: missing record file")
        return path

    @cached_property
    def record(self) -> dict:
        """The parsed ``record.json``."""
        path = self._file(layout.RECORD_JSON)
        try:
            return json.loads(path.read_text(encoding="utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise DatasetError(f"{path}: unreadable record ({exc})") from exc

    @property
    def time(self) -> float:
        """Simulation time of the snapshot, seconds (NaN when the source does not give it)."""
        value = self.record.get("time")
        return float("nan") if value is None else float(value)

    @property
    def sequence_id(self) -> str | None:
        """The sequence this frame belongs to (the record name of its frame 0), or None for a
        record that is no sequence's frame (formats before 7)."""
        sequence = self.record.get("sequence")
        return None if sequence is None else str(sequence["id"])

    @property
    def frame(self) -> int:
        """0-based index of this frame in its sequence (0 for a record of no sequence)."""
        sequence = self.record.get("sequence")
        return 0 if sequence is None else int(sequence["frame"])

    @property
    def odometry(self) -> tuple | None:
        """Per view (in this pair's view order) its ``OdometryPose``: the observer's pose
        relative to its own pose at frame 0 as its dead reckoning reports it (x forward, y left,
        metres; yaw, radians; ``cadsim.sensing.odometry``), or None (no sequence)."""
        if self.record.get("sequence") is None:
            return None
        if self._odometry is not None:
            return self._odometry
        from cadsim.sensing.odometry import OdometryPose

        observers = self.record["observers"]
        return tuple(
            OdometryPose.from_dict(observers[v - 1]["odometry"]) for v in self.view_numbers
        )

    def with_odometry(self, poses: Sequence) -> FramePair:
        """This pair with ``poses`` (one ``OdometryPose`` per view, in this pair's view order)
        as its ``odometry`` instead of the stored one (a run's redraw:
        :func:`cadsim.dataset.sequence_odometry.redraw_odometry`); ValueError for a record of
        no sequence or another number of poses."""
        if self.record.get("sequence") is None:
            raise ValueError(f"{self.path}: not a sequence frame: it has no odometry to replace")
        if len(poses) != len(self.view_numbers):
            raise ValueError(
                f"poses: expected {len(self.view_numbers)} odometry poses, got {len(poses)}"
            )
        pair = self._derived((self.view1, self.view2), self.noise_rate, self._localisation)
        pair._odometry = tuple(poses)
        return pair

    @property
    def cues(self) -> tuple[str, ...]:
        """What the detections carry for matchers (``cadsim.dataset.cues``): camera records
        ``position, class, appearance, pixels``; box-only records ``position, class, size,
        heading`` (features = the box feature vector, no pixels). A pair built in memory
        without a record: the camera cues."""
        if not (self.path / layout.RECORD_JSON).is_file():
            return CAMERA_CUES
        return record_cues(self.record)

    @property
    def has_images(self) -> bool:
        """Whether the record has colour, depth and instance images (imported records do not)."""
        return layout.view_png(self.view_numbers[0]) in self._record_files

    @cached_property
    def cameras(self) -> tuple[Camera, Camera] | None:
        """The two observers' cameras (world poses, intrinsics), or None when the record has none."""
        obs = self._observers
        if any(o.get("camera") is None for o in obs):
            return None
        return Camera.from_dict(obs[0]["camera"]), Camera.from_dict(obs[1]["camera"])

    @property
    def _observers(self) -> tuple[dict, dict]:
        """The record's observer entries of this pair's two views."""
        obs = self.record["observers"]
        a, b = self.view_numbers
        if not (isinstance(obs, list) and max(a, b) <= len(obs)):
            raise DatasetError(
                f"{self.path / layout.RECORD_JSON}: observers: expected at least {max(a, b)} "
                "entries"
            )
        return obs[a - 1], obs[b - 1]

    @property
    def observer_kinds(self) -> tuple[str, str]:
        """Per view "vehicle" or "roadside" (a pole-mounted camera with an exactly known pose)."""
        return tuple(o.get("kind", "vehicle") for o in self._observers)

    @cached_property
    def observer_poses(self) -> tuple[ObserverPose, ObserverPose] | None:
        """The two observers' true world poses: the carrying object's bounding-box centre (world
        metres) and heading (radians CCW from +x); a camera on no object: its own. None for
        imported records, which carry no true poses."""
        obs = self._observers
        if any(o.get("pose") is None for o in obs):
            return None
        return ObserverPose.from_dict(obs[0]["pose"]), ObserverPose.from_dict(obs[1]["pose"])

    @cached_property
    def camera_extrinsics(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Per view, the 4×4 transform from the camera's OpenCV frame to its observer's body
        frame (x forward, y left, z up, origin at the body's centre): the camera mount. None
        without cameras and poses (imported records)."""
        if self.cameras is None or self.observer_poses is None:
            return None
        return tuple(
            pose.camera_extrinsics(cam)
            for pose, cam in zip(self.observer_poses, self.cameras, strict=True)
        )

    @cached_property
    def camera_to_world(self) -> tuple[np.ndarray, np.ndarray]:
        """Per view, the 4×4 transform from the camera's OpenCV frame to the world frame (true
        pose): ``camera_to_world[0] @ [p, 1]`` puts a view-1 position into the world. None
        without cameras (imported records)."""
        if self.cameras is None:
            return None
        return camera_to_world(self.cameras[0]), camera_to_world(self.cameras[1])

    @cached_property
    def difficulty(self) -> dict:
        """The pair's difficulty factors (:mod:`cadsim.dataset.difficulty`; truth, never a
        matcher's input): as the record stores them, else (imported records) what its truth
        allows, computed here. They describe the pair as recorded: a copy with fewer detections
        (:meth:`select`, a thinning level) or another prior keeps its record's factors and level,
        so a pair is at one level under every condition."""
        from cadsim.dataset.difficulty import difficulty_factors

        stored = self.record.get("difficulty")
        if isinstance(stored, dict):
            return dict(stored)
        v1, v2 = self.view1, self.view2
        return difficulty_factors(
            v1.positions, v2.positions, v1.true_classes, v2.true_classes, self.gt_pairs,
            self.camera_to_world,
        )  # fmt: skip

    @property
    def observer_ids(self) -> tuple[str, str]:
        obs = self._observers
        return obs[0]["id"], obs[1]["id"]

    @cached_property
    def objects(self) -> list[WorldObject]:
        """Every object of the snapshot (world frame); instance images index this list."""
        return [WorldObject.from_dict(d) for d in self.record["objects"]]

    @cached_property
    def gt_pairs(self) -> np.ndarray:
        return ground_truth_pairs(self.view1, self.view2)

    @cached_property
    def lidar(self):
        """The two views' LiDAR sweeps (:class:`cadsim.dataset.lidar_points.LidarView`: points in
        each LiDAR's frame, its pose, the objects hit as ground truth), or None when the record
        has no ``lidar.npz``."""
        if layout.LIDAR_NPZ not in self._record_files:
            return None
        from cadsim.dataset.lidar_points import check_lidar_arrays, read_lidar_view

        what = str(self.path / layout.LIDAR_NPZ)
        arrays = self._npz(layout.LIDAR_NPZ)
        try:
            check_lidar_arrays(arrays, max(self.view_numbers), len(self.record["objects"]), what)
        except ValueError as exc:
            raise DatasetError(str(exc).splitlines()[0]) from None
        return tuple(read_lidar_view(arrays, v) for v in self.view_numbers)

    def _png(self, name: str) -> np.ndarray:
        return decode_png(self._file(name).read_bytes(), str(self.path / name))

    def _npz(self, name: str) -> dict[str, np.ndarray]:
        return load_npz(str(self._file(name)), str(self.path / name))

    @cached_property
    def color1(self) -> np.ndarray:
        """(H, W, 3) uint8 RGB of view 1 (of the record's view ``view_numbers[0]``)."""
        return self._png(layout.view_png(self.view_numbers[0]))

    @cached_property
    def color2(self) -> np.ndarray:
        return self._png(layout.view_png(self.view_numbers[1]))

    @cached_property
    def _depth(self) -> dict[str, np.ndarray]:
        return self._npz(layout.DEPTH_NPZ)

    @property
    def depth1(self) -> np.ndarray:
        """(H, W) float32 clean depth of view 1, metres along the optical axis, 0 = no hit."""
        return self._depth[f"depth{self.view_numbers[0]}"]

    @property
    def depth2(self) -> np.ndarray:
        return self._depth[f"depth{self.view_numbers[1]}"]

    @cached_property
    def _instance(self) -> dict[str, np.ndarray]:
        return self._npz(layout.INSTANCE_NPZ)

    @property
    def instance1(self) -> np.ndarray:
        """(H, W) int32 index into ``objects`` of view 1, -1 = none."""
        return self._instance[f"instance{self.view_numbers[0]}"]

    @property
    def instance2(self) -> np.ndarray:
        return self._instance[f"instance{self.view_numbers[1]}"]

    def problem(self):
        """The matching problem as ``matchers.Problem``: positions (metres, each camera's frame)
        and features of both views, the box centres in pixels (``pixels1``/``pixels2``, for
        matchers that compare objects in the image; None for box-only records, which have no
        image, :attr:`cues`), and the localisation prior (world positions + stated sigma,
        :meth:`prior`) when the record has one."""
        from matchers.core.problem import Problem

        pixels = "pixels" in self.cues
        prior = self.prior()
        world1, world2, sigma = (None, None, None) if prior is None else prior
        loc = self.localisation
        return Problem(
            self.view1.positions,
            self._sent_view2[0],
            self.view1.features,
            self.view2.features,
            meta={
                "pair": self.index,
                "name": self.name,
                "noise_rate": self.noise_rate,
                "localisation": None if loc is None else dataclasses.asdict(loc[0]),
                **_headings(self.view1, self.view2),
            },
            pixels1=_box_centres(self.view1.boxes) if pixels else None,
            pixels2=_box_centres(self.view2.boxes) if pixels else None,
            world1=world1,
            world2=world2,
            world_sigma=sigma,
            # the detector's reported classes only: the true ones never reach a matcher
            classes1=_reported(self.view1),
            classes2=_reported(self.view2),
        )

    @property
    def localisation(self) -> tuple[LocalisationConfig, tuple[int, int]] | None:
        """The pose-error parameters and the two views' seeds the prior is drawn with: the
        record's own (its scenario's ``[localisation]`` table, seeds from the dataset's root
        seed), or those given to :meth:`localise`. None when the prior is stored (imported data)
        or the record has none (a pair built in memory)."""
        if self._localisation != "record":
            return self._localisation
        if self.view1.world is not None or not (self.path / layout.RECORD_JSON).is_file():
            return None  # stored prior, or a pair built in memory without a record
        prior = self.record.get("prior") or {}
        if prior.get("kind") != "pose_error" or self.cameras is None:
            return None
        config = LocalisationConfig(
            **{k: prior[k] for k in ("position_sigma_m", "yaw_sigma_deg", "preset") if k in prior}
        )
        obs = self._observers
        return config, (int(obs[0]["localisation_seed"]), int(obs[1]["localisation_seed"]))

    def prior(self) -> tuple[np.ndarray, np.ndarray, float] | None:
        """The localisation prior: (world1 (n, 3), world2 (m, 3), stated sigma in metres) — each
        view's detections in the world frame (x, y horizontal, z up) through that observer's own
        noisy pose — or None when the record has none. Simulated records: the current detections
        (after any ``redetect``/``select``) through each camera, with its observer's pose error
        applied about the observer's body origin (``cadsim.sensing.localisation``); sigma =
        position sigma, at least 0.5 m. Imported
        records: the stored positions and the source's stated sigma."""
        if self.view1.world is not None and self.view2.world is not None:
            return self.view1.world, self.view2.world, float(self.record["prior"]["world_sigma_m"])
        errors = self._pose_errors()
        if errors is None:
            return None
        sent, offset = self._sent_view2
        worlds = []
        for k, (positions, camera, pose, error) in enumerate(zip((self.view1.positions, sent), self.cameras, self.observer_poses, errors, strict=True)):  # fmt: skip
            shift = offset if k else np.zeros(3)  # the sender's pose when it sent (latency)
            world = camera.camera_to_world(positions) + shift
            worlds.append(perturbed_world(world, np.asarray(pose.position) + shift, error))
        return worlds[0], worlds[1], self.localisation[0].stated_sigma_m

    def pose_errors(self) -> tuple[PoseError, PoseError] | None:
        """Each view's drawn localisation error (``PoseError``: dx, dy metres, dyaw radians,
        about its observer's body origin) — what its broadcast pose is off by — or None without
        a simulated prior (none, stored, ``denied``). The exporters write it as the reported
        pose."""
        return self._pose_errors()

    def _pose_errors(self) -> tuple[PoseError, PoseError] | None:
        """Each view's drawn pose error (about its observer's body origin), or None when the
        record has no simulated prior (none, stored, or ``denied``)."""
        loc = self.localisation
        if loc is None or self.cameras is None:
            return None
        config, seeds = loc
        model = None if config.preset is None else gnss_model(config.preset)
        if model is not None and not model.given:
            return None  # denied: the vehicles have no pose to share
        latency = config.latency_s
        errors = []
        for k, (seed, vehicle, kind) in enumerate(zip(seeds[:2], self.observer_ids, self.observer_kinds, strict=True)):  # fmt: skip
            if kind == "roadside":  # a surveyed pole: its pose is exact
                errors.append(PoseError(0.0, 0.0, 0.0))
            elif model is None:
                errors.append(config.draw_error(np.random.default_rng(seed)))
            else:
                episode_seed = seeds[2] if len(seeds) > 2 else self.sim_seed
                when = self.time - (latency if k else 0.0)
                if not np.isfinite(self.time):  # imported before importers gave every record one
                    if model.walk_m_per_sqrt_s > 0:
                        raise ValueError(
                            f"{self.path / layout.RECORD_JSON}: time: null, and a GNSS preset's walk needs it: import "
                            "the source again (importers now give a record without a time 0 s)"
                        )
                    when = 0.0  # no walk: the time changes nothing
                errors.append(draw_gnss_error(model, episode_seed, vehicle, when, seed))
        return errors[0], errors[1]

    def broadcast_relative_pose(self) -> np.ndarray | None:
        """4x4 transform from view 2's camera frame into view 1's that the two observers' own
        noisy (broadcast) poses imply, pose₁⁻¹ · pose₂ — each camera's true placement (view 2's
        at the time its message was made) with its observer's pose error applied — in the frames
        of :meth:`true_relative_pose`: what a vehicle knows with no matching at all. Uses the
        poses only, never a detection. None without a simulated prior (none, stored, denied)."""
        errors = self._pose_errors()
        if errors is None:
            return None
        _, offset = self._sent_view2
        to_world = []
        for k, (camera, pose, error) in enumerate(zip(self.cameras, self.observer_poses, errors, strict=True)):  # fmt: skip
            shift = offset if k else np.zeros(3)
            c, s = np.cos(error.dyaw), np.sin(error.dyaw)
            turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
            pivot = np.asarray(pose.position, dtype=float) + shift
            pivot[2] = 0.0  # the yaw error turns about the vertical through the body origin
            origin = np.asarray(camera.position, dtype=float) + shift
            out = np.eye(4)
            out[:3, :3] = turn @ camera.rotation_cam_to_world()
            out[:3, 3] = turn @ (origin - pivot) + pivot + np.array([error.dx, error.dy, 0.0])
            to_world.append(out)
        return np.linalg.inv(to_world[0]) @ to_world[1]

    @cached_property
    def _sent_view2(self) -> tuple[np.ndarray, np.ndarray]:
        """View 2's detections as the other vehicle's message reports them under the prior's
        latency (:mod:`cadsim.sensing.latency`): ((m, 3) positions in its camera frame, metres;
        (3,) world offset of its pose when it sent from its pose at the snapshot). No latency:
        the detections as they are and a zero offset. ValueError for a record without object
        velocities (format version < 3) under a latency."""
        loc = self.localisation
        latency = 0.0 if loc is None else loc[0].latency_s
        if not latency:
            return self.view2.positions, np.zeros(3)
        version = int(self.record.get("format_version", 0))
        if version < MIN_VELOCITY_FORMAT:
            raise ValueError(
                f"{self.path}: localisation preset {loc[0].preset!r} has a message latency of "
                f"{latency * 1000:g} ms, which needs object velocities (dataset format version "
                f"{MIN_VELOCITY_FORMAT}); this record is version {version} — regenerate it"
            )
        by_id = {o.id: o.velocity for o in self.objects}
        sender = by_id.get(self.observer_ids[1], (0.0, 0.0, 0.0))
        rotation = self.cameras[1].rotation_cam_to_world()
        velocities = velocities_of(self.view2.object_ids, by_id)
        positions = delayed_positions(self.view2.positions, velocities, sender, rotation, latency)
        return positions, sender_offset(sender, latency)

    def true_relative_pose(self) -> np.ndarray | None:
        """4x4 rigid transform from view 2's camera frame — as the other vehicle's message
        reports it, at the snapshot time minus the prior's latency (:meth:`_sent_view2`) — into
        view 1's camera frame (OpenCV axes, metres): what matching can recover. None for a
        record without camera poses (imported data) and for a pair built in memory."""
        if not (self.path / layout.RECORD_JSON).is_file() or self.cameras is None:
            return None
        _, offset = self._sent_view2
        to_world = []
        for k, camera in enumerate(self.cameras):
            pose = np.eye(4)
            pose[:3, :3] = camera.rotation_cam_to_world()
            pose[:3, 3] = np.asarray(camera.position, dtype=float) + (offset if k else 0.0)
            to_world.append(pose)
        return np.linalg.inv(to_world[0]) @ to_world[1]

    def localise(
        self, position_sigma_m: float, yaw_sigma_deg: float, seed: int | None
    ) -> FramePair:
        """This pair with its localisation prior re-drawn: each observer's pose error has
        standard deviations ``position_sigma_m`` (metres per ground axis) and ``yaw_sigma_deg``,
        seeded by the run seed ``seed`` and the record's identity, its simulation seed included
        (:func:`cadsim.dataset.seeds.redraw_seed`: another split never shares the draw). Nothing
        is re-rendered or re-detected. Same arguments ⇒ the same prior; for one seed the error
        scales with the sigmas; ``seed=None`` and the scenario's sigmas ⇒ the record's own prior.
        ``ValueError`` for a record whose prior is stored (imported) or that has no cameras.

        >>> pair.localise(2.5, 2.5 * 0.2 / 1.2, seed=0).prior()[2]   # doctest: +SKIP
        2.5
        """
        config = LocalisationConfig(position_sigma_m=position_sigma_m, yaw_sigma_deg=yaw_sigma_deg)
        return self._redrawn(config, self._view_seeds(seed))

    def localise_preset(self, preset: str, seed: int | None) -> FramePair:
        """This pair with its localisation prior re-drawn by the GNSS-like model ``preset``
        (:mod:`cadsim.sensing.gnss_error`: ``exact``, ``rtk``, ``gnss-open-sky``, ``gnss-urban``,
        ``denied`` — no prior), seeded by the run seed and the record's identity (simulation
        seed, episode, slot, view) for the per-view draws and by (seed, simulation seed, episode)
        for the episode's bias and drift (:mod:`cadsim.dataset.seeds`). ``seed=None`` and the
        scenario's own preset give back the record's own prior. ``ValueError`` as
        :meth:`localise`."""
        config = LocalisationConfig(preset=preset)
        if seed is None:  # the record's own: the episode's bias and drift from its simulation seed
            return self._redrawn(config, self._view_seeds(None) + (self.sim_seed,))
        episode = (redraw_episode_seed(seed, self.sim_seed, self.episode),)
        return self._redrawn(config, self._view_seeds(seed) + episode)

    def _view_seeds(self, seed: int | None) -> tuple[int, int]:
        """The two views' localisation seeds of run ``seed`` (None: the record's own)."""
        if seed is None:
            return tuple(int(o["localisation_seed"]) for o in self._observers)
        return tuple(
            redraw_seed(LOCALISATION_STREAM, seed, self.sim_seed, self.episode, self.slot, v)
            for v in self.view_numbers
        )

    def _redrawn(self, config: LocalisationConfig, seeds: tuple[int, ...]) -> FramePair:
        """This pair with its prior drawn from ``config`` and ``seeds``; ValueError for a stored
        (imported) prior or a record without cameras."""
        if self.view1.world is not None:
            raise ValueError(
                f"{self.path}: the localisation prior is stored with this (imported) record and "
                "cannot be re-drawn"
            )
        if self.cameras is None:
            raise ValueError(f"{self.path}: record has no camera poses to localise from")
        return self._derived((self.view1, self.view2), self.noise_rate, (config, seeds))

    def of_views(self, i: int, j: int) -> FramePair:
        """The pair of views ``i`` and ``j`` (1-based) of this pair's record (an N-view
        snapshot), with the record's own detections and prior; the parsed record is shared."""
        pair = FramePair(
            self.path, self.index, self._entry, self._noise, self._detection,
            record_files=self._record_files, view_numbers=(i, j),
        )  # fmt: skip
        if "record" in self.__dict__:
            pair.__dict__["record"] = self.__dict__["record"]
        return pair

    def select(self, rows1, rows2) -> FramePair:
        """This pair with only the detections at `rows1` of view 1 and `rows2` of view 2 (integer
        indices, in that order); ground truth follows the kept objects. Images are shared."""
        views = (self.view1.take(rows1), self.view2.take(rows2))
        return self._derived(views, self.noise_rate, self._localisation)

    def _derived(
        self, views: tuple[ViewDetections, ViewDetections], noise_rate: float, localisation
    ) -> FramePair:
        """A copy with other detections / prior parameters, sharing what was loaded."""
        pair = FramePair(
            self.path,
            self.index,
            self._entry,
            self._noise,
            self._detection,
            views,
            noise_rate,
            record_files=self._record_files,
            localisation=localisation,
            view_numbers=self.view_numbers,
        )
        pair._odometry = self._odometry
        shared = ("record", "color1", "color2", "_depth", "_instance", "objects", "cameras")
        shared += ("observer_poses", "camera_extrinsics", "camera_to_world")
        for name in shared:
            if name in self.__dict__:
                pair.__dict__[name] = self.__dict__[name]
        return pair

    def redetect(self, noise_rate: float, seed: int | None) -> FramePair:
        """This pair re-detected at depth-noise rate ``noise_rate`` (σ = noise_rate · d²): noise
        seeded by the run seed ``seed`` and the record's identity, its simulation seed included
        (:func:`cadsim.dataset.seeds.redraw_seed`), applied to the stored clean depth, then
        detection; nothing is re-rendered. Same arguments ⇒ identical detections; rate 0 ⇒
        clean-depth detections; ``seed=None`` and the dataset's noise rate ⇒ the stored detections. Features are
        the stored ones (they depend on colour, instance map and the record's attribute errors,
        ``attribute_seed``, not on depth), so only positions are re-estimated."""
        return self.redetect_rates([noise_rate], seed)[0]

    def redetect_rates(self, noise_rates: Sequence[float], seed: int | None) -> list[FramePair]:
        """``[self.redetect(rate, seed) for rate in noise_rates]`` (the same bits), at a fraction
        of the cost: which objects are detected, their pixels and features are decided once per
        view (:func:`cadsim.sensing.detection.plan_detections`, kept on this pair), the seeded
        unit noise field is drawn once per view (every rate scales the same field), and only the
        pixels of detected objects are made noisy."""
        from cadsim.sensing.depth_noise import noisy_depth_values, unit_noise

        rates = [float(r) for r in noise_rates]
        for rate in rates:
            if not np.isfinite(rate) or rate < 0:
                raise ValueError(f"noise_rate: expected a finite value >= 0, got {rate!r}")
        noise_cfg, plans = self._detection_plans
        per_view = []
        for v, depth, plan, observer in zip(
            self.view_numbers, (self.depth1, self.depth2), plans, self._observers, strict=True
        ):
            clean = np.asarray(depth, dtype=np.float64).ravel()[plan.pixels]
            unit = None
            if any(rate > 0 for rate in rates):
                rng = np.random.default_rng(self._noise_seed(seed, v, observer))
                unit = unit_noise(depth.shape, noise_cfg, rng).ravel()[plan.pixels]
            per_view.append(
                [
                    ViewDetections.from_detections(
                        plan.locate(noisy_depth_values(clean, rate, unit))
                    )
                    for rate in rates
                ]
            )
        return [
            self._derived((view1, view2), rate, self._localisation)
            for rate, view1, view2 in zip(rates, *per_view, strict=True)
        ]

    def _noise_seed(self, seed: int | None, view: int, observer: dict) -> int:
        """Depth-noise seed of view ``view`` in run ``seed`` (None: the record's own)."""
        if seed is None:
            return int(observer["noise_seed"])
        return redraw_seed(NOISE_STREAM, seed, self.sim_seed, self.episode, self.slot, view)

    @cached_property
    def _detection_plans(self) -> tuple[NoiseConfig, tuple[DetectionPlan, DetectionPlan]]:
        """The dataset's noise configuration and, per view, what its detector decides without the
        noisy depth (from the stored clean depth, instance map and attribute seed; the current
        detections' features are reused, so colour is decoded only for an object they lack)."""
        from cadsim.sensing.depth_noise import NoiseConfig, check_depth
        from cadsim.sensing.detection import DetectionConfig, plan_detections

        if not self.has_images:
            raise ValueError(f"{self.path}: record has no depth images to re-detect from")
        try:
            noise_cfg = NoiseConfig(**self._noise)
            det_cfg = DetectionConfig(**self._detection)
        except (TypeError, ValueError) as exc:
            manifest = self.path.parent.parent / layout.MANIFEST
            raise DatasetError(
                f"{manifest}: generation.noise / generation.detection rejected ({exc})"
            ) from None
        plans = []
        for observer, color, depth, instance, camera, stored in (
            (
                self._observers[0],
                "color1",
                self.depth1,
                self.instance1,
                self.cameras[0],
                self.view1,
            ),
            (
                self._observers[1],
                "color2",
                self.depth2,
                self.instance2,
                self.cameras[1],
                self.view2,
            ),
        ):
            check_depth(depth)
            # The attribute errors are the record's own, whatever the noise seed.
            attributes = np.random.default_rng(observer["attribute_seed"])
            plans.append(
                plan_detections(
                    instance,
                    depth,
                    self.objects,
                    camera,
                    det_cfg,
                    lambda name=color: getattr(self, name),
                    attribute_rng=attributes,
                    known_features=dict(zip(stored.object_ids, stored.features, strict=True)),
                )
            )
        return noise_cfg, (plans[0], plans[1])


def _reported(view: ViewDetections) -> tuple[str, ...] | None:
    """The classes a view's detector reported (None where the record does not say)."""
    return None if view.reported_classes is None else tuple(view.reported_classes)


def _headings(view1, view2) -> dict:
    """``{"headings": (h1, h2)}`` of two box-only views (radians, each view's frame; what a
    box-level matcher such as ``v2x_reg`` aligns), {} when a view has none."""
    h1, h2 = getattr(view1, "headings", None), getattr(view2, "headings", None)
    if h1 is None or h2 is None:
        return {}
    return {"headings": (np.asarray(h1, dtype=float), np.asarray(h2, dtype=float))}


def _box_centres(boxes: np.ndarray) -> np.ndarray:
    """(k, 2) centres (u, v) in pixels of (k, 4) boxes (u0, v0, u1, v1)."""
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    return (boxes[:, :2] + boxes[:, 2:]) / 2
