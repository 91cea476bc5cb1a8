"""The SUMO traffic source: one seeded libsumo simulation, sampled into world snapshots.

Per snapshot: every vehicle, bicycle and person (pose converted once, in ``cadsim.sources.sumo.frames``),
the traffic lights with their current signal, and the static scene (road surface, buildings,
signs; ``cadsim.sources.sumo.static_scene``). ``snapshot.meta["approaches"]`` records, for each vehicle that
may carry a camera, the junction it approaches, on which arm, and how far away it is; observer
pairs are chosen from it (``cadsim.sources.observer_pairs``).

libsumo runs one simulation per process; a second SumoSource may start only after the first is
closed.
"""

from __future__ import annotations

import contextlib
import logging
import os
import shutil
import tempfile
import weakref
import zlib
from collections.abc import Iterator
from pathlib import Path

import libsumo
import numpy as np

from cadsim.object_sizes import draw_size
from cadsim.scenario import Scenario, ScenarioError
from cadsim.sources.base import ObserverPair, ObserverSet, TrafficSource
from cadsim.sources.observer_pairs import mount_camera, observer_pairs
from cadsim.sources.observer_sets import observer_sets
from cadsim.sources.sumo.build import ToolFailed
from cadsim.sources.sumo.command import sumo_run
from cadsim.sources.sumo.confinement import ConfinementError
from cadsim.sources.sumo.frames import front_to_center, speed_to_velocity, sumo_color
from cadsim.sources.sumo.network import RoadNetwork
from cadsim.sources.sumo.options import OptionError
from cadsim.sources.sumo.static_scene import Region, build_static_scene, hex_to_rgb
from cadsim.world import Snapshot, WorldObject

log = logging.getLogger(__name__)

# SUMO reports this colour for objects that have none of their own.
SUMO_DEFAULT_COLOR = (255, 255, 0, 255)
# SUMO vehicle class -> (cls, shape). Unlisted classes are cars.
VEHICLE_CLASSES = {
    "delivery": ("van", "van"),
    "bus": ("bus", "bus"),
    "coach": ("bus", "bus"),
    "truck": ("truck", "truck"),
    "trailer": ("truck", "truck"),
    "bicycle": ("bicycle", "bicycle"),
    "moped": ("motorcycle", "bicycle"),
    "motorcycle": ("motorcycle", "bicycle"),
    "scooter": ("motorcycle", "bicycle"),
    "tram": ("tram", "bus"),
    "rail_urban": ("tram", "bus"),
    "rail": ("train", "bus"),
    "rail_electric": ("train", "bus"),
    "rail_fast": ("train", "bus"),
}
VAN_SHAPES = {"delivery", "passenger/van"}

_active: list[SumoSource] = []  # the simulation running in this process (at most one)


@contextlib.contextmanager
def working_directory(folder: Path) -> Iterator[None]:
    """Run the block with the process's working directory in ``folder``. libsumo runs in this
    process: while it starts (and opens its outputs), a relative path SUMO resolves against the
    working directory lands in the run folder. The worker runs one simulation at a time."""
    previous = os.getcwd()
    os.chdir(folder)
    try:
        yield
    finally:
        os.chdir(previous)


def vehicle_class(vclass: str, gui_shape: str) -> tuple[str, str]:
    """(cls, shape) of a SUMO vehicle from its vClass and guiShape."""
    if gui_shape in VAN_SHAPES:
        return "van", "van"
    return VEHICLE_CLASSES.get(vclass, ("car", "car"))


class SumoSource(TrafficSource):
    """A SUMO simulation of ``scenario`` with ``seed``; generated nets/routes are cached in
    ``workdir``. Building the network and the static scene happens here (errors surface early);
    the simulation starts in :meth:`start`."""

    def __init__(self, scenario: Scenario, seed: int, workdir: Path) -> None:
        self.scenario = scenario
        self.seed = int(seed)
        self.workdir = Path(workdir)
        traffic = scenario.traffic
        self._prepare_run()
        self.network = RoadNetwork(self.run.net)
        self.junctions = self._observed_junctions()
        self.static = build_static_scene(
            self.network, self.junctions, traffic["scene"], scenario.seed
        )
        centres = np.array([self.network.junction_xy(j) for j in self.junctions])
        self.region = Region(centres, traffic["scene"]["radius"])
        self._vehicle_colors = [hex_to_rgb(c) for c in traffic["vehicle_colors"]]
        self._person_colors = [hex_to_rgb(c) for c in traffic["person_colors"]]
        self._types: dict[str, tuple[str, str, tuple]] = {}
        self._sizes: dict[str, tuple[float, float, float]] = {}  # object id -> its drawn size
        self._running = False
        log.debug("sumo %s", " ".join(self.run.args))

    def _prepare_run(self) -> None:
        """Build net/demand (cached) and this simulation's private run folder."""
        (self.workdir / "runs").mkdir(parents=True, exist_ok=True)
        self.run_dir = Path(tempfile.mkdtemp(dir=self.workdir / "runs", prefix=f"seed{self.seed}-"))
        self._cleanup = weakref.finalize(self, shutil.rmtree, self.run_dir, True)
        try:
            self.run = sumo_run(
                self.scenario.traffic,
                self.seed,
                self.workdir,
                self.run_dir,
                self.scenario.sampling["max_time"],
            )
        except (OptionError, ConfinementError, ToolFailed) as exc:
            traffic = self.scenario.traffic
            key = next(f"traffic.{k}" for k in ("sumocfg", "net", "network") if traffic[k])
            raise ScenarioError(self.scenario.path, key, str(exc)) from None

    def _observed_junctions(self) -> list[str]:
        traffic = self.scenario.traffic
        key = next(f"traffic.{k}" for k in ("sumocfg", "net", "network") if traffic[k] is not None)
        usable = self.network.junction_arms
        if not usable:
            raise ScenarioError(
                self.scenario.path,
                key,
                f"the network {self.run.net} has no junction that vehicles can approach on two "
                "different arms",
                "a net with at least one junction joining three or more roads",
            )
        wanted = self.scenario.observers["junctions"]
        for j in wanted:
            if j not in usable:
                raise ScenarioError(
                    self.scenario.path,
                    "observers.junctions",
                    f"{j!r} is not a junction two vehicles can approach in {self.run.net}",
                    "ids among " + ", ".join(list(usable)[:20]),
                )
        return sorted(wanted) if wanted else list(usable)

    # ---------------------------------------------------------------------------------------

    def start(self) -> None:
        if self._running:
            return
        if not self.run_dir.exists():  # closed before: a new run folder
            self._prepare_run()
        if _active:
            raise RuntimeError(
                "libsumo runs one simulation per process: close the running SumoSource first "
                "(or run this one in another process)"
            )
        try:
            with working_directory(self.run_dir):  # whatever SUMO resolves against it lands here
                libsumo.start(["sumo", *self.run.args])
        except libsumo.TraCIException as exc:
            log.debug("sumo arguments: %s", self.run.args)
            raise ScenarioError(
                self.scenario.path, "traffic", f"sumo failed to start ({exc})"
            ) from None
        _active.append(self)
        self._running = True
        self._sizes = {}

    def close(self) -> None:
        if self._running:
            libsumo.close()
            _active.remove(self)
            self._running = False
        self._cleanup()

    def snapshots(self) -> Iterator[Snapshot]:
        """Snapshots at begin + warm_up + k * interval until the demand (or max_time) ends."""
        self.start()
        sampling = self.scenario.sampling
        sim = libsumo.simulation
        begin = sim.getTime()
        end = sim.getEndTime()
        k = 0
        while True:
            target = begin + sampling["warm_up"] + k * sampling["interval"]
            while sim.getTime() < target - 1e-6:
                if end > 0 and sim.getTime() >= end - 1e-6:
                    return
                if sim.getTime() > begin and sim.getMinExpectedNumber() <= 0:
                    return
                libsumo.simulationStep()
                self._resize_departed()
            yield self.snapshot()
            k += 1

    def observer_pairs(self, snapshot: Snapshot) -> list[ObserverPair]:
        return observer_pairs(snapshot, self.scenario.camera, self.scenario.observers)

    def follow_pair(self, snapshot: Snapshot, pair: ObserverPair) -> ObserverPair | None:
        """The pair's two vehicles at ``snapshot``, cameras mounted as ``observer_pairs`` does
        (aimed at the pair's junction with ``aim = "junction"``), wherever they now are (past
        the junction too); None once either has left the simulation or the scene's radius."""
        objects = snapshot.by_id()
        carriers = [objects.get(pair.observer1_id), objects.get(pair.observer2_id)]
        if any(c is None for c in carriers):
            return None
        look_at = None
        if self.scenario.observers.get("aim", "heading") == "junction":
            centres = snapshot.meta.get("junctions", {})
            junction = pair.meta.get("junction")
            if junction not in centres:
                return None
            look_at = np.asarray(centres[junction], float)[:2]
        cam1, cam2 = (mount_camera(c, self.scenario.camera, look_at) for c in carriers)
        meta = {"junction": pair.meta.get("junction"), "time": float(snapshot.time)}
        return ObserverPair(cam1, cam2, pair.observer1_id, pair.observer2_id, meta)

    def observer_sets(self, snapshot: Snapshot) -> list[ObserverSet]:
        return observer_sets(snapshot, self.scenario.camera, self.scenario.observers)

    # ---------------------------------------------------------------------------------------

    def snapshot(self) -> Snapshot:
        """The current simulation state as a Snapshot."""
        vehicles, approaches = self._vehicles()
        objects = vehicles + self._persons()
        states = {}
        for head in self.static.lights:
            if head.tls not in states:
                states[head.tls] = libsumo.trafficlight.getRedYellowGreenState(head.tls)
        objects += [head.at_state(states[head.tls]) for head in self.static.lights]
        objects += self.static.objects
        meta = {
            "source": "sumo",
            "seed": self.seed,
            "approaches": approaches,
            "junctions": {
                j: [float(v) for v in self.network.junction_xy(j)] for j in self.junctions
            },
        }
        return Snapshot(time=float(libsumo.simulation.getTime()), objects=objects, meta=meta)

    def _type_info(self, type_id: str) -> tuple[str, str, tuple]:
        if type_id not in self._types:
            vt = libsumo.vehicletype
            self._types[type_id] = (
                vt.getVehicleClass(type_id),
                vt.getShapeClass(type_id),
                vt.getColor(type_id),
            )
        return self._types[type_id]

    def _resize_departed(self) -> None:
        """Give every vehicle and person that departed in the last step its own drawn size, in
        SUMO too, so that car following and the world objects agree on it."""
        for sumo_id in libsumo.simulation.getDepartedIDList():
            with contextlib.suppress(libsumo.TraCIException):  # already arrived
                self._vehicle_size(sumo_id)
        for sumo_id in libsumo.simulation.getDepartedPersonIDList():
            with contextlib.suppress(libsumo.TraCIException):
                self._person_size(sumo_id)

    def _vehicle_size(self, sumo_id: str) -> tuple[float, float, float]:
        """The vehicle's (length, width, height) metres: its vType's size as the mean, its class's
        spread (``cadsim.object_sizes``), drawn once from the simulation seed and its id."""
        oid = f"veh:{sumo_id}"
        if oid not in self._sizes:
            v, vt = libsumo.vehicle, libsumo.vehicletype
            type_id = v.getTypeID(sumo_id)
            vclass, gui_shape, _ = self._type_info(type_id)
            cls, _ = vehicle_class(vclass, gui_shape)
            mean = (vt.getLength(type_id), vt.getWidth(type_id), vt.getHeight(type_id))
            size = draw_size(self.seed, oid, cls, mean)
            v.setLength(sumo_id, size[0])
            v.setWidth(sumo_id, size[1])
            v.setHeight(sumo_id, size[2])
            self._sizes[oid] = size
        return self._sizes[oid]

    def _person_size(self, sumo_id: str) -> tuple[float, float, float]:
        """A person's drawn (depth, shoulder breadth, stature) metres, as :meth:`_vehicle_size`."""
        oid = f"person:{sumo_id}"
        if oid not in self._sizes:
            p, vt = libsumo.person, libsumo.vehicletype
            type_id = p.getTypeID(sumo_id)
            mean = (vt.getLength(type_id), vt.getWidth(type_id), vt.getHeight(type_id))
            size = draw_size(self.seed, oid, "person", mean)
            p.setLength(sumo_id, size[0])
            p.setWidth(sumo_id, size[1])
            p.setHeight(sumo_id, size[2])
            self._sizes[oid] = size
        return self._sizes[oid]

    def _color(self, oid: str, own: tuple, type_color: tuple, palette: list) -> tuple:
        for rgba in (own, type_color):
            if tuple(rgba) != SUMO_DEFAULT_COLOR:
                return sumo_color(rgba)
        return palette[zlib.crc32(oid.encode()) % len(palette)]

    def _vehicles(self) -> tuple[list[WorldObject], dict]:
        v = libsumo.vehicle
        ids = sorted(v.getIDList())
        if not ids:
            return [], {}
        front = np.array([v.getPosition3D(i) for i in ids], float)
        angle = np.array([v.getAngle(i) for i in ids], float)
        size = np.array([self._vehicle_size(i) for i in ids], float)
        center, yaw = front_to_center(front, angle, size[:, 0], size[:, 2])
        velocity = speed_to_velocity([v.getSpeed(i) for i in ids], yaw)
        inside = self.region.contains(center[:, :2])
        observer_classes = set(self.scenario.observers["classes"])
        max_distance = self.scenario.observers["max_distance"]
        wanted = set(self.junctions)
        objects, approaches = [], {}
        for k in np.flatnonzero(inside):
            sumo_id = ids[k]
            type_id = v.getTypeID(sumo_id)
            vclass, gui_shape, type_color = self._type_info(type_id)
            cls, shape = vehicle_class(vclass, gui_shape)
            oid = f"veh:{sumo_id}"
            objects.append(
                WorldObject(
                    id=oid,
                    cls=cls,
                    shape=shape,
                    center=tuple(float(c) for c in center[k]),
                    yaw=float(yaw[k]),
                    size=tuple(float(s) for s in size[k]),
                    color=self._color(oid, v.getColor(sumo_id), type_color, self._vehicle_colors),
                    variant=type_id,
                    velocity=tuple(float(c) for c in velocity[k]),
                )
            )
            if cls in observer_classes:
                approach = self.network.approach(
                    v.getRoute(sumo_id),
                    v.getRouteIndex(sumo_id),
                    v.getLaneID(sumo_id),
                    v.getLanePosition(sumo_id),
                    max_distance,
                    wanted,
                )
                if approach is not None:
                    approaches[oid] = approach.as_dict()
        return objects, approaches

    def _persons(self) -> list[WorldObject]:
        p = libsumo.person
        ids = sorted(i for i in p.getIDList() if not p.getVehicle(i))
        if not ids:
            return []
        front = np.array([p.getPosition3D(i) for i in ids], float)
        angle = np.array([p.getAngle(i) for i in ids], float)
        size = np.array([self._person_size(i) for i in ids], float)
        center, yaw = front_to_center(front, angle, size[:, 0], size[:, 2])
        velocity = speed_to_velocity([p.getSpeed(i) for i in ids], yaw)
        objects = []
        for k in np.flatnonzero(self.region.contains(center[:, :2])):
            sumo_id = ids[k]
            type_id = p.getTypeID(sumo_id)
            _, _, type_color = self._type_info(type_id)
            oid = f"person:{sumo_id}"
            objects.append(
                WorldObject(
                    id=oid,
                    cls="person",
                    shape="person",
                    center=tuple(float(c) for c in center[k]),
                    yaw=float(yaw[k]),
                    size=tuple(float(s) for s in size[k]),
                    color=self._color(oid, p.getColor(sumo_id), type_color, self._person_colors),
                    variant=type_id,
                    velocity=tuple(float(c) for c in velocity[k]),
                )
            )
        return objects
