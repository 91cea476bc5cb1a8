"""Observer geometry: the frustum-overlap rule on hand-built cameras, arm relations, camera aim,
the new ``[observers]`` keys' validation, and that a table without them chooses exactly the pairs
the rule chose before they existed."""

from __future__ import annotations

from itertools import combinations
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cadsim.camera import Camera
from cadsim.scenario import OBSERVERS, CameraConfig, ScenarioError, load_scenario
from cadsim.sources.base import ObserverPair
from cadsim.sources.frustum_overlap import (
    convex_intersection,
    frustum_overlap,
    ground_footprint,
    polygon_area,
)
from cadsim.sources.observer_pairs import arm_relation, mount_camera, observer_pairs
from cadsim.world import Snapshot, WorldObject

GAME_CROSS = "$SUMO_HOME/tools/game/cross.sumocfg"


def cam(x: float, y: float, yaw_deg: float, hfov: float = 90.0) -> Camera:
    return Camera((x, y, 1.6), np.radians(yaw_deg), hfov_deg=hfov)


# --------------------------------------------------------------------------- frustum overlap


def test_facing_cameras_share_the_diamond_between_them():
    # Two 90° wedges facing each other 30 m apart meet in a square of diagonal 30 m: 450 m².
    assert frustum_overlap(cam(0, 0, 0), cam(30, 0, 180), 40.0) == pytest.approx(450.0)
    # Beyond the range the diamond is cut: at 10 m range they do not reach each other's wedge.
    assert frustum_overlap(cam(0, 0, 0), cam(30, 0, 180), 10.0) == 0.0


def test_back_to_back_and_side_by_side_looking_apart_do_not_overlap():
    assert frustum_overlap(cam(0, 0, 0), cam(-5, 0, 180), 50.0) == 0.0
    assert frustum_overlap(cam(0, 0, 0), cam(0, 0, 180), 50.0) == 0.0
    assert frustum_overlap(cam(0, 0, 90), cam(0, -10, -90), 50.0) == 0.0


def test_a_camera_overlaps_itself_by_its_whole_footprint():
    c = cam(3, -2, 37)
    sector = np.pi * 40.0**2 / 4.0  # a 90° sector of radius 40 m
    assert polygon_area(ground_footprint(c, 40.0)) == pytest.approx(sector, rel=0.005)
    assert frustum_overlap(c, c, 40.0) == pytest.approx(polygon_area(ground_footprint(c, 40.0)))


def test_perpendicular_cameras_looking_at_one_point_share_a_quadrant():
    # Both wedges contain the quarter plane x >= 0, y >= 0 near the origin ... seen from (0, -20)
    # looking north and (-20, 0) looking east: the shared part is bounded and grows with range.
    near = frustum_overlap(cam(0, -20, 90), cam(-20, 0, 0), 30.0)
    far = frustum_overlap(cam(0, -20, 90), cam(-20, 0, 0), 60.0)
    assert 0.0 < near < far


@settings(max_examples=40, deadline=None)
@given(
    st.floats(-50, 50), st.floats(-50, 50), st.floats(-180, 180),
    st.floats(-50, 50), st.floats(-50, 50), st.floats(-180, 180),
    st.floats(-180, 180), st.floats(-30, 30), st.floats(-30, 30),
)  # fmt: skip
def test_overlap_is_symmetric_bounded_and_invariant_to_a_rigid_motion(
    x1, y1, a1, x2, y2, a2, turn, dx, dy
):
    c1, c2 = cam(x1, y1, a1), cam(x2, y2, a2)
    area = frustum_overlap(c1, c2, 40.0)
    assert area == pytest.approx(frustum_overlap(c2, c1, 40.0), abs=1e-6)
    assert 0.0 <= area <= polygon_area(ground_footprint(c1, 40.0)) + 1e-6
    r = np.radians(turn)
    rot = np.array([[np.cos(r), -np.sin(r)], [np.sin(r), np.cos(r)]])

    def moved(c: Camera, yaw: float) -> Camera:
        x, y = rot @ c.position[:2] + (dx, dy)
        return cam(x, y, yaw + turn)

    assert frustum_overlap(moved(c1, a1), moved(c2, a2), 40.0) == pytest.approx(area, abs=1e-4)


def test_convex_intersection_of_squares():
    square = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    assert polygon_area(convex_intersection(square, square + 1.0)) == pytest.approx(1.0)
    assert polygon_area(convex_intersection(square, square + 3.0)) == 0.0
    inner = square * 0.5 + 0.5
    assert polygon_area(convex_intersection(square, inner)) == pytest.approx(1.0)


def test_arm_relation_from_headings():
    assert arm_relation(0.0, np.pi) == "opposite"
    assert arm_relation(0.1, -np.pi + 0.2) == "opposite"
    assert arm_relation(0.0, np.pi / 2) == "adjacent"
    assert arm_relation(np.pi / 2, -np.pi / 2 + 0.1) == "opposite"
    assert arm_relation(0.0, 0.3) == "parallel"


# --------------------------------------------------------------------------- pair rules

ROAD = (4.6, 1.8, 1.5)


def car(oid: str, x: float, y: float, yaw_deg: float, cls: str = "car") -> WorldObject:
    return WorldObject(oid, cls, cls, (x, y, 0.75), np.radians(yaw_deg), ROAD, (1, 1, 1))


def junction_snapshot() -> Snapshot:
    """A four-arm junction at the origin: cars 15 m out on each arm heading inwards, and a second
    car further back on the south arm."""
    objects = [
        car("s", 2.0, -15.0, 90), car("n", -2.0, 15.0, -90),
        car("e", 15.0, 2.0, 180), car("w", -15.0, -2.0, 0), car("s2", 2.0, -35.0, 90),
    ]  # fmt: skip
    arm = {"s": "S", "n": "N", "e": "E", "w": "W", "s2": "S"}
    distance = {"s": 8.0, "n": 8.0, "e": 8.0, "w": 8.0, "s2": 28.0}
    approaches = {
        o.id: {"junction": "J", "arm": arm[o.id], "edge": arm[o.id] + "in", "distance": distance[o.id]}
        for o in objects
    }  # fmt: skip
    return Snapshot(5.0, objects, {"approaches": approaches, "junctions": {"J": [0.0, 0.0]}})


def rules(**keys) -> dict:
    table = {k: v.default for k, v in OBSERVERS.fields.items()}
    table["classes"] = ["car", "van", "bus", "truck"]
    return table | keys


def ids(pairs: list[ObserverPair]) -> list[tuple[str, str]]:
    return [(p.observer1_id, p.observer2_id) for p in pairs]


def test_arm_relations_keep_only_the_allowed_pairs():
    snap, camera = junction_snapshot(), CameraConfig()
    everything = observer_pairs(snap, camera, rules())
    assert len(everything) == 10 - 1  # every pair of different arms (s, s2 share one)
    opposite = observer_pairs(snap, camera, rules(arm_relations=["opposite"]))
    assert {frozenset(p) for p in ids(opposite)} == {
        frozenset(p) for p in [("n", "s"), ("e", "w"), ("n", "s2")]
    }
    assert all(p.meta["relation"] == "opposite" for p in opposite)
    adjacent = observer_pairs(snap, camera, rules(arm_relations=["adjacent"]))
    assert len(adjacent) == 6 and all(p.meta["relation"] == "adjacent" for p in adjacent)
    assert observer_pairs(snap, camera, rules(arm_relations=["parallel"])) == []


def test_shared_area_keeps_pairs_whose_cameras_look_at_the_same_ground():
    snap, camera = junction_snapshot(), CameraConfig()
    pairs = observer_pairs(snap, camera, rules(min_shared_area_m2=500.0, overlap_range_m=50.0))
    assert pairs
    for p in pairs:
        area = frustum_overlap(p.camera1, p.camera2, 50.0)
        assert area >= 500.0 and p.meta["shared_area_m2"] == pytest.approx(area, abs=1e-3)
    every = observer_pairs(snap, camera, rules(min_shared_area_m2=1e-9, overlap_range_m=50.0))
    rejected = set(ids(every)) - set(ids(pairs))
    assert rejected == {("e", "w"), ("n", "s")}  # facing, 25 m apart: they share only ~310 m²
    assert all(p.meta["shared_area_m2"] < 500.0 for p in every if (p.observer1_id, p.observer2_id) in rejected)  # fmt: skip


def test_cameras_aim_at_the_junction_centre_when_asked():
    snap, camera = junction_snapshot(), CameraConfig(mount_height="roof")
    for p in observer_pairs(snap, camera, rules(aim="junction")):
        for c in (p.camera1, p.camera2):
            ahead = c.world_to_camera(np.array([[0.0, 0.0, c.position[2]]]))[0]
            assert abs(ahead[0]) < 1e-9 and ahead[2] > 0  # the centre is on the optical axis
            assert c.position[2] == pytest.approx(1.5 + 0.05)  # roof of a 1.5 m car
    with pytest.raises(ValueError, match="no centre for junction 'J'"):
        observer_pairs(Snapshot(0.0, snap.objects, {"approaches": snap.meta["approaches"]}),
                       camera, rules(aim="junction"))  # fmt: skip


def _rule_before_issue_13(snapshot: Snapshot, camera: CameraConfig, observers: dict) -> list:
    """The observer-pair rule as it was before the geometry keys existed (the reference)."""
    objects = snapshot.by_id()
    allowed = set(observers["classes"])
    lo, hi = observers["min_distance"], observers["max_distance"]
    by_junction: dict[str, list] = {}
    for oid, approach in sorted(snapshot.meta.get("approaches", {}).items()):
        obj = objects.get(oid)
        if obj is None or obj.cls not in allowed or not lo <= approach["distance"] <= hi:
            continue
        by_junction.setdefault(approach["junction"], []).append((oid, approach))
    candidates = []
    for junction in sorted(by_junction):
        for (id1, a1), (id2, a2) in combinations(by_junction[junction], 2):
            if a1["arm"] == a2["arm"]:
                continue
            o1, o2 = objects[id1], objects[id2]
            gap = float(np.hypot(o1.center[0] - o2.center[0], o1.center[1] - o2.center[1]))
            if gap < observers["min_separation"]:
                continue
            candidates.append(
                ((junction, a1["distance"] + a2["distance"], id1, id2), o1, o2, a1, a2)
            )
    candidates.sort(key=lambda c: c[0])
    return [
        ObserverPair(
            mount_camera(o1, camera), mount_camera(o2, camera), o1.id, o2.id,
            {"junction": a1["junction"], "arms": [a1["arm"], a2["arm"]],
             "edges": [a1["edge"], a2["edge"]],
             "distances": [float(a1["distance"]), float(a2["distance"])],
             "time": float(snapshot.time)},
        )
        for _, o1, o2, a1, a2 in candidates
    ]  # fmt: skip


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([1.6, "roof"]))
def test_a_table_without_the_new_keys_chooses_exactly_the_old_pairs(seed, mount):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(0, 14))
    classes = rng.choice(["car", "van", "bus", "truck", "bicycle"], size=n)
    objects = [
        WorldObject(f"v{k}", str(c), str(c), (*rng.uniform(-60, 60, 2), 0.9),
                    float(rng.uniform(-np.pi, np.pi)), (4.6, 1.8, 1.8), (1, 1, 1))
        for k, c in enumerate(classes)
    ]  # fmt: skip
    approaches = {
        o.id: {"junction": str(rng.choice(["A", "B"])), "arm": str(rng.choice(["1", "2", "3"])),
               "edge": "e", "distance": float(rng.uniform(0, 60))}
        for o in objects if rng.random() < 0.9
    }  # fmt: skip
    snap = Snapshot(float(seed % 100), objects, {"approaches": approaches})
    camera = CameraConfig(mount_height=mount)
    table = rules(max_distance=float(rng.uniform(5, 60)), min_separation=float(rng.uniform(0, 20)))
    assert observer_pairs(snap, camera, table) == _rule_before_issue_13(snap, camera, table)


# --------------------------------------------------------------------------- validation


def _scenario(tmp_path: Path, observers: str) -> Path:
    path = tmp_path / "s.toml"
    path.write_text(
        f'[traffic]\nsource = "sumo"\nsumocfg = "{GAME_CROSS}"\n[observers]\n{observers}'
    )
    return path


@pytest.mark.parametrize(
    ("body", "key", "words"),
    [
        ('arm_relations = ["opposite", "diagonal"]', "observers.arm_relations", ['"adjacent"']),
        ('arm_relations = ["opposite", "opposite"]', "observers.arm_relations", ["distinct"]),
        ("arm_relations = [1]", "observers.arm_relations[0]", ["wrong type"]),
        ('aim = "north"', "observers.aim", ["'heading', 'junction'"]),
        ("min_shared_area_m2 = -1", "observers.min_shared_area_m2", [">= 0"]),
        ("overlap_range_m = 0", "observers.overlap_range_m", ["> 0"]),
        ('overlap_range_m = "far"', "observers.overlap_range_m", ["wrong type", "a number"]),
    ],
)
def test_new_observer_keys_are_validated(tmp_path, body, key, words):
    path = _scenario(tmp_path, body + "\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert info.value.key == key and str(info.value).startswith(str(path.resolve()))
    for word in words:
        assert word in str(info.value)


def test_new_observer_keys_load(tmp_path):
    s = load_scenario(_scenario(tmp_path, 'arm_relations = ["adjacent"]\naim = "junction"\n'
                                          "min_shared_area_m2 = 500\noverlap_range_m = 40\n"))  # fmt: skip
    assert s.observers["arm_relations"] == ["adjacent"] and s.observers["aim"] == "junction"
    assert s.observers["min_shared_area_m2"] == 500.0 and s.observers["overlap_range_m"] == 40.0
