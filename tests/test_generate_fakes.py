"""Fake pipeline stages for the generation/dataset tests (no tests here).

A seeded random world (no SUMO), a z-buffered box "renderer" (no OpenGL), additive d² depth
noise and an instance-mask detector. They implement the same interfaces as the real stages so
``cadsim.generation.pipeline`` runs unchanged; they are importable by name, so spawn workers load them too.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from cadsim.camera import Camera
from cadsim.generation.pipeline import Stages
from cadsim.render.view import RenderedView
from cadsim.sources.base import ObserverPair, ObserverSet, TrafficSource
from cadsim.world import Snapshot, WorldObject

FAKE_STAGES = Stages(
    source="test_generate_fakes:make_source",
    renderer="test_generate_fakes:FakeRenderer",
    noise_config="test_generate_fakes:FakeNoiseConfig",
    apply_noise="test_generate_fakes:apply_noise",
    detection_config="test_generate_fakes:FakeDetectionConfig",
    detect="test_generate_fakes:detect",
)

# Set by in-process tests: raise at the first snapshot with time >= this (simulated crash).
# The environment variable CADSIM_FAKE_DELAY_S slows each snapshot down (for kill tests).
FAIL_AT_TIME: float | None = None

_SIZES = {"car": (4.5, 1.8, 1.5), "van": (5.2, 2.0, 2.2), "person": (0.5, 0.5, 1.8)}
_PALETTE = ((0.8, 0.1, 0.1), (0.9, 0.9, 0.9), (0.1, 0.2, 0.7))


@dataclass
class FakeScenario:
    path: str = "fake.toml"
    text: str = "# fake scenario\n"
    name: str = "fake"
    seed: int = 11
    pairs: int = 4
    traffic: dict = field(default_factory=lambda: {"source": "fake", "snapshots": 10})
    camera: dict = field(default_factory=lambda: {"width": 160, "height": 120, "hfov_deg": 90.0})
    observers: dict = field(default_factory=dict)
    noise: dict = field(default_factory=lambda: {"noise_rate": 0.01})
    detection: dict = field(default_factory=lambda: {"min_pixels": 6})
    sampling: dict = field(default_factory=lambda: {"pairs_per_episode": 2})
    sequence: dict | None = None


class FakeSource(TrafficSource):
    def __init__(self, scenario: FakeScenario, seed: int, workdir: Path) -> None:
        self.scenario, self.seed, self.workdir = scenario, seed, workdir
        self.started = False

    def start(self) -> None:
        self.started = True

    def close(self) -> None:
        self.started = False

    def snapshots(self):
        assert self.started, "source used outside its context manager"
        if self.scenario.traffic.get("moving"):
            yield from self._moving_snapshots()
            return
        rng = np.random.default_rng(self.seed)
        for step in range(int(self.scenario.traffic.get("snapshots", 10))):
            t = 2.0 * step
            if FAIL_AT_TIME is not None and t >= FAIL_AT_TIME:
                raise RuntimeError(f"injected failure at t={t}")
            time.sleep(float(os.environ.get("CADSIM_FAKE_DELAY_S", "0")))
            n = int(rng.integers(6, 14))
            classes = rng.choice(list(_SIZES), size=n)
            xy = rng.uniform(-18.0, 18.0, size=(n, 2))
            colours = rng.integers(0, len(_PALETTE), size=n)
            objects = [
                WorldObject(
                    id=f"veh{step}_{k}" if k % 3 else f"ped{k}",
                    cls=str(c),
                    shape="box",
                    center=(float(x), float(y), _SIZES[c][2] / 2),
                    yaw=float(rng.uniform(-np.pi, np.pi)),
                    size=_SIZES[c],
                    color=_PALETTE[colours[k]],
                )
                for k, (c, (x, y)) in enumerate(zip(classes, xy, strict=True))
            ]
            objects.append(
                WorldObject("obs1", "car", "box", (-30.0, 0.0, 0.75), 0.0, _SIZES["car"], (0, 0, 0))
            )
            objects.append(
                WorldObject(
                    "obs2", "car", "box", (0.0, -30.0, 0.75), 1.57, _SIZES["car"], (0, 0, 0)
                )
            )
            objects.append(
                WorldObject("b0", "building", "box", (3, 40, 5), 0.0, (8, 8, 10), (0.5,) * 3, False)
            )
            yield Snapshot(time=t, objects=objects, meta={"step": step})

    def _moving_snapshots(self):
        """``traffic.moving``: one set of objects (ids kept across snapshots) moving at constant
        velocities, observer obs1 driving along +x and obs2 along +y at ``observer_speed`` m/s
        (obs2 gone from ``leave_at`` s on); snapshots every ``[sampling] interval`` s."""
        traffic = self.scenario.traffic
        rng = np.random.default_rng(self.seed)
        n = 12
        classes = rng.choice(list(_SIZES), size=n)
        xy = rng.uniform(-15.0, 15.0, size=(n, 2))
        velocity = rng.uniform(-1.0, 1.0, size=(n, 2))
        colours = rng.integers(0, len(_PALETTE), size=n)
        yaws = rng.uniform(-np.pi, np.pi, size=n)
        interval = float((self.scenario.sampling or {}).get("interval", 2.0))
        speed = float(traffic.get("observer_speed", 5.0))
        leave_at = traffic.get("leave_at")
        for step in range(int(traffic.get("snapshots", 10))):
            t = interval * step
            if FAIL_AT_TIME is not None and t >= FAIL_AT_TIME:
                raise RuntimeError(f"injected failure at t={t}")
            time.sleep(float(os.environ.get("CADSIM_FAKE_DELAY_S", "0")))
            objects = [
                WorldObject(
                    id=f"veh{k}" if k % 3 else f"ped{k}",
                    cls=str(c),
                    shape="box",
                    center=(float(x + vx * t), float(y + vy * t), _SIZES[c][2] / 2),
                    yaw=float(yaws[k]),
                    size=_SIZES[c],
                    color=_PALETTE[colours[k]],
                    velocity=(float(vx), float(vy), 0.0),
                )
                for k, (c, (x, y), (vx, vy)) in enumerate(zip(classes, xy, velocity, strict=True))
            ]
            objects.append(
                WorldObject(
                    "obs1",
                    "car",
                    "box",
                    (-40.0 + speed * t, 0.0, 0.75),
                    0.0,
                    _SIZES["car"],
                    (0, 0, 0),
                )  # fmt: skip
            )
            if leave_at is None or t < float(leave_at):
                objects.append(
                    WorldObject(
                        "obs2",
                        "car",
                        "box",
                        (0.0, -40.0 + 0.5 * speed * t, 0.75),
                        1.57,
                        _SIZES["car"],
                        (0, 0, 0),
                    )  # fmt: skip
                )
            yield Snapshot(time=t, objects=objects, meta={"step": step})

    def observer_pairs(self, snapshot: Snapshot) -> list[ObserverPair]:
        cam = self.scenario.camera
        size = {k: cam[k] for k in ("width", "height", "hfov_deg")}
        if self.scenario.traffic.get("moving"):
            by_id = snapshot.by_id()
            if "obs1" not in by_id or "obs2" not in by_id:
                return []
            o1, o2 = by_id["obs1"].center, by_id["obs2"].center
            return [
                ObserverPair(
                    Camera((o1[0] + 2.5, o1[1], 1.6), 0.0, **size),
                    Camera((o2[0], o2[1] + 2.5, 1.6), np.pi / 2, **size),
                    "obs1",
                    "obs2",
                    {"junction": "J0"},
                )
            ]
        away = ObserverPair(  # looking away from each other: never acceptable
            Camera((-30.0, 0.0, 1.6), np.pi, **size), Camera((0.0, -30.0, 1.6), -np.pi / 2, **size)
        )
        towards = ObserverPair(
            Camera((-30.0, 0.0, 1.6), 0.0, **size),
            Camera((0.0, -30.0, 1.6), np.pi / 2, **size),
            "obs1",
            "obs2",
            {"junction": "J0"},
        )
        swapped = ObserverPair(towards.camera2, towards.camera1, "obs2", "obs1", {"junction": "J0"})
        return [away, towards, swapped]

    def observer_sets(self, snapshot: Snapshot) -> list[ObserverSet]:
        """N views (``observers`` ``count`` <= 2 vehicles, then ``roadside_units`` <= 2): the
        two vehicles facing the scene, and roadside units 3 m up on the other two sides."""
        count = int(self.scenario.observers.get("count", 2))
        units = int(self.scenario.observers.get("roadside_units", 0))
        towards = self.observer_pairs(snapshot)[1]
        cam = self.scenario.camera
        size = {k: cam[k] for k in ("width", "height", "hfov_deg")}
        vehicles = [(towards.camera1, "obs1"), (towards.camera2, "obs2")][:count]
        poles = [
            (Camera((30.0, 0.0, 3.0), np.pi, **size), "rsu:J0:0"),
            (Camera((0.0, 30.0, 3.0), -np.pi / 2, **size), "rsu:J0:1"),
        ][:units]
        views = vehicles + poles
        kinds = ("vehicle",) * len(vehicles) + ("roadside",) * len(poles)
        cameras, ids = tuple(c for c, _ in views), tuple(i for _, i in views)
        return [ObserverSet(cameras, ids, kinds, {"junction": "J0"})]


def make_source(scenario, seed: int, workdir: Path) -> FakeSource:
    return FakeSource(scenario, seed, workdir)


class FakeRenderer:
    """Each object drawn as a camera-facing square of its height, nearest on top."""

    def __init__(self, width: int, height: int) -> None:
        self.width, self.height = width, height

    def render(self, snapshot: Snapshot, camera: Camera, exclude_ids=()) -> RenderedView:
        h, w = self.height, self.width
        color = np.full((h, w, 3), 180, np.uint8)
        depth = np.zeros((h, w), np.float32)
        instance = np.full((h, w), -1, np.int32)
        keep = [i for i, o in enumerate(snapshot.objects) if o.id not in set(exclude_ids)]
        pts = camera.world_to_camera(np.array([snapshot.objects[i].center for i in keep]))
        for k in np.argsort(-pts[:, 2]):
            z = pts[k, 2]
            if z < 0.5:
                continue
            obj = snapshot.objects[keep[k]]
            u, v = camera.project(pts[k : k + 1])[0]
            half = camera.fx * obj.size[2] / z / 2
            u0, u1 = int(max(0, u - half)), int(min(w, u + half + 1))
            v0, v1 = int(max(0, v - half)), int(min(h, v + half + 1))
            if u0 >= u1 or v0 >= v1:
                continue
            depth[v0:v1, u0:u1] = z
            instance[v0:v1, u0:u1] = keep[k]
            color[v0:v1, u0:u1] = (np.array(obj.color) * 255).astype(np.uint8)
        return RenderedView(color, depth, instance)


@dataclass(frozen=True)
class FakeNoiseConfig:
    noise_rate: float = 0.0


def apply_noise(depth: np.ndarray, config: FakeNoiseConfig, rng) -> np.ndarray:
    noise = rng.standard_normal(depth.shape) * config.noise_rate * depth.astype(np.float64) ** 2
    return np.where(depth > 0, depth + noise, 0.0).astype(np.float32)


@dataclass(frozen=True)
class FakeDetectionConfig:
    min_pixels: int = 6


def detect(
    view: RenderedView, noisy_depth, objects, camera: Camera, config: FakeDetectionConfig,
    attribute_rng=None,
):  # fmt: skip
    classes = sorted(_SIZES)
    rows = []
    for idx in np.unique(view.instance[view.instance >= 0]):
        obj = objects[idx]
        vs, us = np.nonzero(view.instance == idx)
        if not obj.target or len(us) < config.min_pixels:
            continue
        uv = np.array([[us.mean() + 0.5, vs.mean() + 0.5]])
        d = float(np.median(noisy_depth[vs, us]))
        onehot = np.eye(len(classes))[classes.index(obj.cls)]
        feat = np.concatenate([view.color[vs, us].mean(axis=0) / 255.0, onehot])
        box = (us.min(), vs.min(), us.max() + 1.0, vs.max() + 1.0)
        rows.append((camera.back_project(uv, [d])[0], box, feat, obj.id, obj.cls, len(us)))
    return SimpleNamespace(
        positions=np.array([r[0] for r in rows]).reshape(-1, 3),
        boxes=np.array([r[1] for r in rows], float).reshape(-1, 4),
        features=np.array([r[2] for r in rows], np.float32).reshape(len(rows), 3 + len(classes)),
        object_ids=[r[3] for r in rows],
        true_classes=[r[4] for r in rows],
        reported_classes=[r[4] for r in rows],  # a truthful fake detector
        pixels=np.array([r[5] for r in rows], np.int64),
    )
