"""Reading a frame-pair dataset. Imports neither SUMO nor pyrender (``redetect`` imports the
depth-noise and detection modules, which need only numpy/scipy/OpenCV)."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterator, Sequence
from functools import cached_property
from pathlib import Path

import numpy as np

from cadsim.camera import Camera
from cadsim.dataset import layout
from cadsim.dataset.checksum import dataset_checksum, record_dir_checksum
from cadsim.dataset.detections import ViewDetections, ground_truth_pairs
from cadsim.dataset.encoding import decode_png, load_npz
from cadsim.dataset.manifest import DatasetError, read_manifest
from cadsim.dataset.seeds import noise_seed
from cadsim.world import WorldObject


class FramePair:
    """One frame pair of a dataset: two views' detections plus ground truth.

    index: position in the dataset. episode, slot: the record's identity; sim_seed: its
    simulation's seed. view1, view2: ``ViewDetections`` (positions in each observer's camera
    frame, metres). gt_pairs: (k, 2) int64 (i, j) indices of the same object in view1/view2.
    cameras: the two ``Camera``s (world frame poses). noise_rate: the depth-noise rate the current
    detections were made at. Images (color1/2, clean depth1/2, instance1/2) load on first use.
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
    ) -> None:
        self.path = Path(path)
        self.index = int(index)
        self.name: str = entry["name"]
        self.episode = int(entry["episode"])
        self.slot = int(entry["slot"])
        self.sim_seed = int(entry["sim_seed"])
        self.checksum: str = entry["checksum"]
        self._entry = entry
        self._noise = dict(noise)
        self._detection = dict(detection)
        if views is None:
            what = self.path / layout.DETECTIONS_NPZ
            arrays = load_npz(str(self._file(layout.DETECTIONS_NPZ)), str(what))
            views = (
                ViewDetections.from_arrays(arrays, "view1", str(what)),
                ViewDetections.from_arrays(arrays, "view2", str(what)),
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
        """Simulation time of the snapshot, seconds."""
        return float(self.record["time"])

    @cached_property
    def cameras(self) -> tuple[Camera, Camera]:
        obs = self.record["observers"]
        return Camera.from_dict(obs[0]["camera"]), Camera.from_dict(obs[1]["camera"])

    @property
    def observer_ids(self) -> tuple[str, str]:
        obs = self.record["observers"]
        return obs[0]["id"], obs[1]["id"]

    @cached_property
    def objects(self) -> list[WorldObject]:
        """Every object of the snapshot (world frame); instance images index this list."""
        return [WorldObject.from_dict(d) for d in self.record["objects"]]

    @cached_property
    def gt_pairs(self) -> np.ndarray:
        return ground_truth_pairs(self.view1, self.view2)

    def _png(self, name: str) -> np.ndarray:
        return decode_png(self._file(name).read_bytes(), str(self.path / name))

    def _npz(self, name: str) -> dict[str, np.ndarray]:
        return load_npz(str(self._file(name)), str(self.path / name))

    @cached_property
    def color1(self) -> np.ndarray:
        """(H, W, 3) uint8 RGB of view 1."""
        return self._png(layout.VIEW1_PNG)

    @cached_property
    def color2(self) -> np.ndarray:
        return self._png(layout.VIEW2_PNG)

    @cached_property
    def _depth(self) -> dict[str, np.ndarray]:
        return self._npz(layout.DEPTH_NPZ)

    @property
    def depth1(self) -> np.ndarray:
        """(H, W) float32 clean depth of view 1, metres along the optical axis, 0 = no hit."""
        return self._depth["depth1"]

    @property
    def depth2(self) -> np.ndarray:
        return self._depth["depth2"]

    @cached_property
    def _instance(self) -> dict[str, np.ndarray]:
        return self._npz(layout.INSTANCE_NPZ)

    @property
    def instance1(self) -> np.ndarray:
        """(H, W) int32 index into ``objects`` of view 1, -1 = none."""
        return self._instance["instance1"]

    @property
    def instance2(self) -> np.ndarray:
        return self._instance["instance2"]

    def problem(self):
        """The matching problem (positions and features of both views), as ``matchers.Problem``."""
        from matchers.problem import Problem

        return Problem(
            self.view1.positions,
            self.view2.positions,
            self.view1.features,
            self.view2.features,
            meta={"pair": self.index, "name": self.name, "noise_rate": self.noise_rate},
        )

    def select(self, rows1, rows2) -> FramePair:
        """This pair with only the detections at `rows1` of view 1 and `rows2` of view 2 (integer
        indices, in that order); ground truth follows the kept objects. Images are shared."""
        views = (self.view1.take(rows1), self.view2.take(rows2))
        return self._with_views(views, self.noise_rate)

    def _with_views(
        self, views: tuple[ViewDetections, ViewDetections], noise_rate: float
    ) -> FramePair:
        pair = FramePair(
            self.path, self.index, self._entry, self._noise, self._detection, views, noise_rate
        )
        for name in ("record", "color1", "color2", "_depth", "_instance", "objects", "cameras"):
            if name in self.__dict__:
                pair.__dict__[name] = self.__dict__[name]
        return pair

    def redetect(self, noise_rate: float, seed: int) -> FramePair:
        """This pair re-detected at depth-noise rate ``noise_rate`` (σ = noise_rate · d²): noise
        seeded by (seed, episode, slot, view) applied to the stored clean depth, then detection;
        nothing is re-rendered. Same arguments ⇒ identical detections; rate 0 ⇒ clean-depth
        detections; the dataset's root seed and noise rate ⇒ the stored detections."""
        from cadsim.render.view import RenderedView
        from cadsim.sensing.depth_noise import NoiseConfig, apply_depth_noise
        from cadsim.sensing.detection import DetectionConfig, detect

        if not np.isfinite(noise_rate) or noise_rate < 0:
            raise ValueError(f"noise_rate: expected a finite value >= 0, got {noise_rate!r}")
        noise_cfg = dataclasses.replace(NoiseConfig(**self._noise), noise_rate=float(noise_rate))
        det_cfg = DetectionConfig(**self._detection)
        views = []
        for v, color, depth, instance, camera in (
            (1, self.color1, self.depth1, self.instance1, self.cameras[0]),
            (2, self.color2, self.depth2, self.instance2, self.cameras[1]),
        ):
            rng = np.random.default_rng(noise_seed(seed, self.episode, self.slot, v))
            noisy = apply_depth_noise(depth, noise_cfg, rng)
            det = detect(RenderedView(color, depth, instance), noisy, self.objects, camera, det_cfg)
            views.append(ViewDetections.from_detections(det))
        return self._with_views(tuple(views), noise_rate)


class Dataset(Sequence[FramePair]):
    """A frame-pair dataset written by ``cadsim generate``.

    ``len(ds)``, ``ds[k]`` (a ``FramePair``), iteration in dataset order, ``ds.manifest`` (the
    parsed manifest.json), ``ds.checksum`` (hash over the records' checksums). ``verify()``
    re-hashes every record. Raises ``DatasetError`` for a missing or incomplete dataset.
    """

    def __init__(self, path: str | Path, verify: bool = False) -> None:
        self.path = Path(path)
        self.manifest = read_manifest(self.path)
        if not self.manifest["complete"]:
            raise DatasetError(
                f"{self.path}: generation did not finish; run the same `cadsim generate` command "
                "again to resume it"
            )
        self._records: list[dict] = self.manifest["records"]
        self.checksum: str = self.manifest["checksum"]
        gen = self.manifest["generation"]
        self.noise_config: dict = dict(gen.get("noise") or {})
        self.detection_config: dict = dict(gen.get("detection") or {})
        if verify:
            self.verify()

    def __repr__(self) -> str:
        return f"Dataset({str(self.path)!r}, pairs={len(self)}, checksum={self.checksum[:12]})"

    @property
    def scenario_name(self) -> str:
        return self.manifest["scenario"]["name"]

    def __len__(self) -> int:
        return len(self._records)

    def __getitem__(self, k: int) -> FramePair:  # type: ignore[override]
        if isinstance(k, slice):
            return [self[i] for i in range(*k.indices(len(self)))]
        n = len(self)
        if not isinstance(k, int | np.integer):
            raise TypeError(f"Dataset index must be an int, got {type(k).__name__}")
        if not -n <= k < n:
            raise IndexError(f"pair {k} out of range for a dataset of {n} pairs")
        k = int(k) % n
        entry = self._records[k]
        record_dir = self.path / layout.PAIRS_DIR / entry["name"]
        if not record_dir.is_dir():
            raise DatasetError(f"{record_dir}: record listed in the manifest is missing")
        return FramePair(record_dir, k, entry, self.noise_config, self.detection_config)

    def __iter__(self) -> Iterator[FramePair]:
        for k in range(len(self)):
            yield self[k]

    def verify(self) -> None:
        """Re-hash every record and the dataset; ``DatasetError`` naming the first mismatch."""
        for entry in self._records:
            record_dir = self.path / layout.PAIRS_DIR / entry["name"]
            missing = [n for n in layout.RECORD_FILES if not (record_dir / n).is_file()]
            if missing:
                raise DatasetError(f"{record_dir}: missing record files {missing}")
            actual = record_dir_checksum(record_dir, layout.RECORD_FILES)
            if actual != entry["checksum"]:
                raise DatasetError(f"{record_dir}: checksum mismatch (record modified or corrupt)")
        if dataset_checksum(r["checksum"] for r in self._records) != self.checksum:
            raise DatasetError(f"{self.path / layout.MANIFEST}: dataset checksum mismatch")
