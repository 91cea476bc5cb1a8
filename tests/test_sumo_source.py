"""The SUMO traffic source on the default scenario (generated net + random demand) and on an
externally written scenario shipped with SUMO. libsumo runs one simulation per process, so every
simulation here runs in a fresh (spawned) process."""

from __future__ import annotations

import itertools
import multiprocessing
import os
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from cadsim.camera import Camera
from cadsim.sources.sumo.network import RoadNetwork
from cadsim.sources.sumo.static_scene import SIGNAL_COLORS
from cadsim.world import WorldObject

ROOT = Path(__file__).resolve().parents[1]
# The dense CAD scenario: street-level cameras along the vehicles' headings, heavy traffic (the
# default CAD scenario's observer geometry is checked on generated pairs in test_generate_cad.py).
DEFAULT = ROOT / "scenarios" / "cad-dense.toml"
GAME_CROSS = ROOT / "scenarios" / "sumo-game-cross.toml"
VEHICLES = {"car", "van", "bus", "truck", "bicycle"}


def _collect(scenario: str, seed: int, workdir: str, count: int) -> dict:
    """Fresh process: the first ``count`` snapshots with their observer pairs."""
    from cadsim.scenario import load_scenario
    from cadsim.sources import make_source

    source = make_source(load_scenario(scenario), seed, Path(workdir))
    snapshots = []
    with source:
        for snap in itertools.islice(source.snapshots(), count):
            pairs = source.observer_pairs(snap)
            snapshots.append(
                {
                    "time": snap.time,
                    "objects": [o.as_dict() for o in snap.objects],
                    "meta": snap.meta,
                    "pairs": [
                        {
                            "ids": [p.observer1_id, p.observer2_id],
                            "cameras": [p.camera1.as_dict(), p.camera2.as_dict()],
                            "meta": p.meta,
                        }
                        for p in pairs
                    ],
                }
            )
    return {"snapshots": snapshots, "net": str(source.run.net), "junctions": source.junctions}


def _external_checks(scenario: str, workdir: str) -> dict:
    """Fresh process: snapshots of an external scenario, what its folder looks like before and
    after, and whether a second simulation in the same process is refused."""
    import sumo

    from cadsim.scenario import load_scenario
    from cadsim.sources import make_source

    game = Path(sumo.SUMO_HOME) / "tools" / "game"
    before = sorted(os.listdir(game))
    loaded = load_scenario(scenario)
    first = make_source(loaded, 3, Path(workdir))
    second = make_source(loaded, 4, Path(workdir))
    with first:
        try:
            second.start()
            refused = ""
        except RuntimeError as exc:
            refused = str(exc)
    result = _collect(scenario, 3, workdir, 4)
    with second:  # starts fine once the first is closed
        next(second.snapshots())
    with first:  # and a closed source starts again
        restarted = next(first.snapshots()).time
    result.update(
        refused=refused, restarted=restarted, before=before, after=sorted(os.listdir(game))
    )
    return result


def in_fresh_processes(calls: list[tuple]) -> list:
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(1, mp_context=context, max_tasks_per_child=1) as pool:
        futures = [pool.submit(fn, *args) for fn, *args in calls]
        return [f.result(timeout=300) for f in futures]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    work = tmp_path_factory.mktemp("sumo-work")
    args = (str(DEFAULT), 7, str(work), 5)
    first = in_fresh_processes([(_collect, *args)])[0]
    folders_first = sorted(p.name for p in work.iterdir())
    again, other = in_fresh_processes(
        [(_collect, *args), (_collect, str(DEFAULT), 8, str(work), 2)]
    )
    return {
        "first": first,
        "again": again,
        "other": other,
        "folders_first": folders_first,
        "folders_end": sorted(p.name for p in work.iterdir()),
        "runs_left": sorted(p.name for p in (work / "runs").iterdir()),
        "network": RoadNetwork(first["net"]),
    }


def objects_of(snapshot: dict) -> list[WorldObject]:
    return [WorldObject.from_dict(d) for d in snapshot["objects"]]


# --------------------------------------------------------------------------- default scenario


def test_the_net_is_built_once_and_demand_lives_in_each_run_folder(runs):
    first = runs["folders_first"]
    assert sum(f.startswith("net-") for f in first) == 1
    end = runs["folders_end"]
    # Another seed, other processes: the same net, nothing else cached (demand is drawn in
    # process into each simulation's private run folder, removed on close).
    assert [f for f in end if f.startswith("net-")] == [f for f in first if f.startswith("net-")]
    assert not any(f.startswith("demand-") for f in end)
    assert not any(f.startswith(".") for f in end)  # no half-built folders left
    assert runs["runs_left"] == []  # each simulation's private folder is removed on close


def test_snapshots_follow_the_sampling_schedule(runs):
    assert [s["time"] for s in runs["first"]["snapshots"]] == pytest.approx(
        [150, 152, 154, 156, 158]
    )


def test_snapshots_hold_every_kind_of_object(runs):
    classes = Counter()
    for snap in runs["first"]["snapshots"]:
        objects = objects_of(snap)
        classes.update(o.cls for o in objects)
        ids = [o.id for o in objects]
        assert len(ids) == len(set(ids))
        for o in objects:
            assert all(0.0 <= c <= 1.0 for c in o.color)
            assert all(s > 0 for s in o.size)
            assert o.target == (o.cls not in ("building", "road", "ground"))
            if o.cls in VEHICLES:
                assert o.shape == o.cls and o.variant  # variant = the SUMO vType
            if o.cls == "person":
                # adults' statures, each person's own (cadsim.object_sizes: 1.71 m, sd 0.095 m,
                # around its vType's height, within 2.5 sd)
                assert o.shape == "person" and 1.4 < o.size[2] < 2.05
    assert VEHICLES | {"person", "traffic_light", "sign", "building", "road", "ground"} <= set(
        classes
    )
    snap = objects_of(runs["first"]["snapshots"][0])
    lights = [o for o in snap if o.cls == "traffic_light"]
    assert len(lights) == 4 and all(o.shape == "traffic_light" for o in lights)
    for light in lights:
        assert light.state in "GgyYurRsoO" and light.color == SIGNAL_COLORS[light.state]
    assert len([o for o in snap if o.cls == "sign"]) == 8
    assert len([o for o in snap if o.cls == "building"]) >= 16


def test_pedestrians_are_near_the_junction_when_sampling_starts(runs):
    # The warm-up must let walkers reach the junction, or the cameras never see one (DESIGN §5).
    snap = objects_of(runs["first"]["snapshots"][0])
    centre = np.mean([o.center[:2] for o in snap if o.cls == "traffic_light"], axis=0)
    near = [o for o in snap if o.cls == "person" and np.hypot(*(o.center[:2] - centre)) < 40.0]
    assert len(near) >= 5


def test_identical_looking_vehicles_occur(runs):
    snap = objects_of(runs["first"]["snapshots"][0])
    # look-alikes share class and colour; their sizes differ within the class's spread, as real
    # cars of one colour do (each vehicle draws its own size: cadsim.object_sizes)
    looks = Counter((o.cls, o.color) for o in snap if o.cls in VEHICLES)
    assert max(looks.values()) >= 2


def test_approaching_vehicles_sit_on_their_lanes_facing_the_junction(runs):
    net = runs["network"].net
    checked = 0
    for snap in runs["first"]["snapshots"]:
        objects = {o.id: o for o in objects_of(snap)}
        for oid, approach in snap["meta"]["approaches"].items():
            edge = net.getEdge(approach["edge"])
            if edge.getLength() - approach["distance"] < 10:
                continue  # partly inside the junction's entry
            o = objects[oid]
            best = min(
                _lateral_and_heading(np.array(lane.getShape())[:, :2], np.array(o.center[:2]))
                for lane in edge.getLanes()
            )
            assert best[0] < 0.05
            assert np.cos(o.yaw - best[1]) > 0.9999
            # The junction is ahead.
            to_junction = np.array(edge.getToNode().getCoord()[:2]) - o.center[:2]
            assert to_junction @ [np.cos(o.yaw), np.sin(o.yaw)] > 0
            checked += 1
    assert checked >= 10


def _lateral_and_heading(shape: np.ndarray, p: np.ndarray) -> tuple[float, float]:
    a, b = shape[0], shape[-1]
    d = (b - a) / np.linalg.norm(b - a)
    rel = p - a
    return abs(rel[0] * d[1] - rel[1] * d[0]), float(np.arctan2(d[1], d[0]))


def test_buildings_stand_clear_of_every_lane_and_of_each_other(runs):
    net = runs["network"].net
    snap = objects_of(runs["first"]["snapshots"][0])
    buildings = [o for o in snap if o.cls == "building"]
    points, radius = [], []
    for edge in net.getEdges(withInternal=True):
        for lane in edge.getLanes():
            shape = np.array(lane.getShape())[:, :2]
            for a, b in itertools.pairwise(shape):
                t = np.linspace(0, 1, max(2, int(np.linalg.norm(b - a) / 0.5)))[:, None]
                points.append(a + t * (b - a))
                radius.append(np.full(len(t), lane.getWidth() / 2))
    points, radius = np.concatenate(points), np.concatenate(radius)
    for o in buildings:
        local = _to_local(o, points)
        inside = (np.abs(local[:, 0]) < o.size[0] / 2 + radius) & (
            np.abs(local[:, 1]) < o.size[1] / 2 + radius
        )
        assert not inside.any(), o.id
    grid = np.stack(
        np.meshgrid(np.linspace(-0.45, 0.45, 7), np.linspace(-0.45, 0.45, 7)), -1
    ).reshape(-1, 2)
    for a in buildings:
        samples = _to_world(a, grid * a.size[:2])
        for b in buildings:
            if b is not a:
                local = _to_local(b, samples)
                assert not (
                    (np.abs(local[:, 0]) < b.size[0] / 2) & (np.abs(local[:, 1]) < b.size[1] / 2)
                ).any()


def _to_local(o: WorldObject, points: np.ndarray) -> np.ndarray:
    c, s = np.cos(o.yaw), np.sin(o.yaw)
    d = points - np.array(o.center[:2])
    return np.column_stack([d[:, 0] * c + d[:, 1] * s, -d[:, 0] * s + d[:, 1] * c])


def _to_world(o: WorldObject, local: np.ndarray) -> np.ndarray:
    c, s = np.cos(o.yaw), np.sin(o.yaw)
    return local @ np.array([[c, s], [-s, c]]) + np.array(o.center[:2])


def test_lights_and_signs_stand_beside_the_approaches_facing_the_traffic(runs):
    net = runs["network"].net
    snap = objects_of(runs["first"]["snapshots"][0])
    for o in snap:
        if o.cls not in ("traffic_light", "sign"):
            continue
        edge_id = o.id.split(":")[2]
        lane = net.getEdge(edge_id).getLanes()[0]
        shape = np.array(lane.getShape())[:, :2]
        heading = np.arctan2(*(shape[-1] - shape[0])[::-1])
        assert np.cos(o.yaw - (heading + np.pi)) > 0.999  # faces oncoming traffic
        lateral, _ = _lateral_and_heading(shape, np.array(o.center[:2]))
        assert lane.getWidth() / 2 < lateral < lane.getWidth() / 2 + 1.0  # beside the kerb
        if o.cls == "traffic_light":
            assert np.linalg.norm(np.array(o.center[:2]) - shape[-1]) < 2.0  # at the stop line
        elif o.id.endswith(":in"):
            assert o.variant == "traffic_signals"
            assert np.linalg.norm(np.array(o.center[:2]) - shape[-1]) == pytest.approx(
                20.0, abs=1.0
            )
        else:
            assert (o.variant, o.state) == ("speed_limit", "50")


def test_observer_pairs_follow_the_rules(runs):
    total = 0
    for snap in runs["first"]["snapshots"]:
        objects = {o.id: o for o in objects_of(snap)}
        approaches = snap["meta"]["approaches"]
        junction = np.array(snap["meta"]["junctions"]["A0"])
        keys = []
        for pair in snap["pairs"]:
            a1, a2 = (approaches[i] for i in pair["ids"])
            assert a1["junction"] == a2["junction"] == pair["meta"]["junction"] == "A0"
            assert a1["arm"] != a2["arm"]
            assert max(a1["distance"], a2["distance"]) <= 40.0
            for oid, cam_dict in zip(pair["ids"], pair["cameras"], strict=True):
                o, cam = objects[oid], Camera.from_dict(cam_dict)
                assert o.cls in ("car", "van", "bus", "truck")
                assert cam.position[2] == pytest.approx(1.6)
                assert cam.yaw == pytest.approx(o.yaw) and cam.pitch == 0.0
                assert (cam.width, cam.height, cam.hfov_deg) == (640, 480, 90.0)
                ahead = np.array(o.center[:2]) + (o.size[0] / 2 + 0.05) * np.array(
                    [np.cos(o.yaw), np.sin(o.yaw)]
                )
                np.testing.assert_allclose(cam.position[:2], ahead, atol=1e-9)
                assert cam.world_to_camera([[*junction, 1.0]])[0, 2] > 0  # junction in front
            keys.append(a1["distance"] + a2["distance"])
        assert keys == sorted(keys)
        total += len(snap["pairs"])
    assert total >= 5


def test_same_seed_gives_identical_snapshots_and_another_seed_differs(runs):
    assert runs["again"]["snapshots"] == runs["first"]["snapshots"]
    first_cars = [o for o in runs["first"]["snapshots"][0]["objects"] if o["id"].startswith("veh:")]
    other_cars = [o for o in runs["other"]["snapshots"][0]["objects"] if o["id"].startswith("veh:")]
    assert first_cars != other_cars


# --------------------------------------------------------------------------- external scenario


def test_external_sumo_scenario_runs_unedited_and_yields_observer_pairs(tmp_path):
    (result,) = in_fresh_processes([(_external_checks, str(GAME_CROSS), str(tmp_path))])
    assert "one simulation per process" in result["refused"]
    assert result["restarted"] == 30.0
    assert result["after"] == result["before"]  # nothing written into SUMO's scenario folder
    assert result["junctions"] == ["0"]
    snaps = result["snapshots"]
    assert [s["time"] for s in snaps] == pytest.approx([30, 32, 34, 36])
    assert sum(len(s["pairs"]) for s in snaps) > 0
    for snap in snaps:
        objects = objects_of(snap)
        classes = {o.cls for o in objects}
        assert {"car", "traffic_light", "sign", "building", "road"} <= classes
        for pair in snap["pairs"]:
            assert pair["meta"]["junction"] == "0"
            assert len(set(pair["meta"]["arms"])) == 2
