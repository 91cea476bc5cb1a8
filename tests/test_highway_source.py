"""The highway-env traffic source: determinism, stable ids, observers, static scene, config errors."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import cadsim.sources.highway.schema  # noqa: F401 - registers [traffic] source = "highway-env"
from cadsim.scenario import ScenarioError, load_scenario
from cadsim.sources.highway.config import highway_config
from cadsim.sources.highway.source import HighwaySource

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "highway-intersection.toml"
# Short env episodes (10 s) so that a run of 30 snapshots (0.5 s apart) crosses env resets.
ENV = {
    "initial_vehicle_count": 12,
    "spawn_probability": 0.8,
    "duration": 10,
    "policy_frequency": 2,
    "simulation_frequency": 10,
}


def _scenario(**traffic):
    s = load_scenario(SCENARIO)
    sampling = {**s.sampling, "warm_up": 1.0, "interval": 0.5}
    return dataclasses.replace(
        s, traffic={**s.traffic, "env": dict(ENV), **traffic}, sampling=sampling
    )


def _run(seed: int, n: int, **traffic) -> list:
    with HighwaySource(highway_config(_scenario(max_snapshots=n, **traffic)), seed) as src:
        return [(s, src.observer_pairs(s)) for s in src.snapshots()]


@pytest.fixture(scope="module")
def run_a():
    return _run(11, 30)


def _dump(run) -> list:
    return [
        (
            s.time,
            [o.as_dict() for o in s.objects],
            s.meta,
            [
                (p.camera1.as_dict(), p.camera2.as_dict(), p.observer1_id, p.observer2_id, p.meta)
                for p in pairs
            ],
        )  # fmt: skip
        for s, pairs in run
    ]


def test_same_seed_same_snapshots(run_a):
    again = _run(11, 30)
    assert _dump(again) == _dump(run_a)
    other = _run(12, 5)
    assert _dump(other) != _dump(run_a[:5])


def test_ids_stable_while_in_scene(run_a):
    max_speed = 20.0  # m/s, above highway-env's MDP and IDM target speeds
    appearances: dict[str, list[int]] = {}
    episode_of: dict[str, int] = {}
    for k, (s, _) in enumerate(run_a):
        for o in s.objects:
            if o.id.startswith("veh"):
                appearances.setdefault(o.id, []).append(k)
                assert episode_of.setdefault(o.id, s.meta["episode"]) == s.meta["episode"]
    # an id is present in one unbroken run of snapshots: once gone, never reused
    assert all(ks == list(range(ks[0], ks[-1] + 1)) for ks in appearances.values())
    resets = forward = backward = 0
    for (s0, _), (s1, _) in zip(run_a, run_a[1:], strict=False):
        v0 = {o.id: o for o in s0.objects if o.id.startswith("veh")}
        v1 = {o.id: o for o in s1.objects if o.id.startswith("veh")}
        if s1.meta["episode"] != s0.meta["episode"]:
            resets += 1
            assert not set(v0) & set(v1)  # a reset makes new vehicles
            continue
        assert len(set(v0) & set(v1)) >= len(v1) - 3  # only a few vehicles enter per step
        dt = s1.time - s0.time
        for vid in set(v0) & set(v1):
            a, b = v0[vid], v1[vid]
            assert np.hypot(b.center[0] - a.center[0], b.center[1] - a.center[1]) <= max_speed * dt
            assert (a.cls, a.size, a.color) == (b.cls, b.size, b.color)
            # The converted yaw points where the vehicle goes (checks the heading sign). Only
            # mostly: highway-env lets IDM vehicles roll backwards (Vehicle.MIN_SPEED < 0).
            step = np.subtract(b.center[:2], a.center[:2])
            if np.hypot(*step) > 1.0:
                mid = np.arctan2(np.sin(a.yaw) + np.sin(b.yaw), np.cos(a.yaw) + np.cos(b.yaw))
                cos = np.dot(step / np.hypot(*step), [np.cos(mid), np.sin(mid)])
                assert abs(cos) > np.cos(np.radians(30))
                forward += cos > 0
                backward += cos < 0
    assert resets >= 1  # the run covers an env reset
    assert forward > 100 and forward > 10 * backward


def test_snapshot_contents(run_a):
    classes = set()
    colors = []
    for s, _ in run_a:
        ids = [o.id for o in s.objects]
        assert len(ids) == len(set(ids))
        classes |= {o.cls for o in s.objects}
        colors += [o.color for o in s.objects if o.id.startswith("veh")]
        for o in s.objects:
            if o.id.startswith("veh"):
                assert o.center[2] == pytest.approx(o.size[2] / 2)
        assert set(s.meta["controlled"]) <= set(ids)
    assert {"car", "traffic_light", "sign", "building", "road"} <= classes
    assert len(set(colors)) < len(colors)  # the palette repeats: look-alike vehicles occur
    static = [o for o in run_a[0][0].objects if not o.id.startswith("veh")]
    assert sum(o.cls == "building" for o in static) == 4
    assert sum(o.cls == "traffic_light" for o in static) == 4
    signs = {o.id: o.variant for o in static if o.cls == "sign"}
    assert sorted(signs.values()) == ["priority_road", "priority_road", "yield", "yield"]
    assert all(not o.target for o in static if o.cls in ("building", "road"))


def test_buildings_stay_off_the_road(run_a):
    s = run_a[0][0]
    for b in (o for o in s.objects if o.cls == "building"):
        c, sn = np.cos(b.yaw), np.sin(b.yaw)
        half = np.array(b.size[:2]) / 2
        corners = [
            np.array(b.center[:2])
            + np.array([c, sn]) * i * half[0]
            + np.array([-sn, c]) * j * half[1]
            for i in (-1, 1)
            for j in (-1, 1)
        ]
        # arms run along the world axes, carriageways 8 m wide: keep every corner clear of |x|,|y| <= 4
        assert all(min(abs(p[0]), abs(p[1])) > 4.0 for p in corners)


def test_observer_pairs(run_a):
    n = 0
    for s, pairs in run_a:
        approaches = s.meta["approaches"]
        objects = s.by_id()
        for p in pairs:
            n += 1
            a1, d1 = approaches[p.observer1_id]["arm"], approaches[p.observer1_id]["distance"]
            a2, d2 = approaches[p.observer2_id]["arm"], approaches[p.observer2_id]["distance"]
            assert a1 != a2 and p.meta["arms"] == [a1, a2] and p.meta["junction"] == "intersection"
            c1, c2 = objects[p.observer1_id].center, objects[p.observer2_id].center
            assert np.hypot(c1[0] - c2[0], c1[1] - c2[1]) >= 5.0
            for cam, vid, d in ((p.camera1, p.observer1_id, d1), (p.camera2, p.observer2_id, d2)):
                assert 2.0 <= d <= 40.0
                assert objects[vid].cls in ("car", "van", "bus", "truck")
                assert cam.yaw == pytest.approx(objects[vid].yaw)
                assert cam.position[2] >= objects[vid].size[2]  # on the roof
                # the junction centre lies ahead of an approaching observer
                ahead = cam.world_to_camera(np.array([[0.0, 0.0, cam.position[2]]]))[0]
                assert ahead[2] > 0 and abs(ahead[0]) < 6.0
        assert len(pairs) <= 4
    assert n > 20


def _write(tmp_path: Path, old: str, new: str) -> Path:
    text = SCENARIO.read_text()
    assert old in text
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            "max_candidates = 4",
            "max_candiates = 4",
            r"bad.toml: traffic.max_candiates: unknown key",
        ),
        (
            'env_id = "intersection-v2"',
            'env_id = "intersection-multi-agent-v1"',
            r"traffic.env_id: .*single-agent",
        ),  # noqa: E501
        (
            'env_id = "intersection-v2"',
            'env_id = "intersection-v0"',
            r"traffic.env_id: .*not the deprecated intersection-v0",
        ),
        (
            "size = [4.5, 1.8, 1.5]",
            "size = [4.5, 1.8]",
            r"traffic.kinds\[0\].size: is \[4.5, 1.8\]",
        ),
        ('cls = "van"', 'kind = "van"', r"traffic.kinds\[1\].kind: unknown key"),
        ('"#1e3c8c"]', '"navy"]', r"traffic.vehicle_colors: .*'#rrggbb'"),
        (
            "building_setback = 4.0",
            "building_setback = -1.0",
            r"traffic.scene.building_setback: is -1.0",
        ),
        (
            "policy_weights = [0.2, 0.5, 0.3]",
            "policy_weights = [0.2, 0.5]",
            r"traffic.policy_weights",
        ),
    ],
)
def test_malformed_scenario_named_in_error(tmp_path, old, new, message):
    with pytest.raises(ScenarioError, match=message):
        load_scenario(_write(tmp_path, old, new))


@pytest.mark.parametrize(
    ("traffic", "sampling", "message"),
    [
        (
            {"env": {**ENV, "spawn_probabilty": 0.5}},
            {},
            r"traffic.env.spawn_probabilty: unknown config key of intersection-v2",
        ),  # noqa: E501
        ({"env_id": "intersection-v9"}, {}, r"traffic.env_id: .*registered highway-env id"),
        (
            {},
            {"interval": 0.7},
            r"sampling.interval: is 0.7 s; expected a multiple of the highway-env step \(0.5 s",
        ),  # noqa: E501
        ({}, {"interval": 0.0}, r"sampling.interval: is 0 s; expected .* at least 0.5 s"),
        (
            {"env": {**ENV, "simulation_frequency": 15}},
            {},
            r"traffic.env.simulation_frequency: is 15 Hz; expected a multiple of policy_frequency \(2 Hz\)",
        ),  # noqa: E501
    ],
)
def test_env_errors_at_start(traffic, sampling, message):
    s = _scenario(**traffic)
    s = dataclasses.replace(s, sampling={**s.sampling, **sampling})
    src = HighwaySource(highway_config(s), 0)
    with pytest.raises(ScenarioError, match=message):
        src.start()
    src.close()


def test_observer_settings_checked():
    s = _scenario()
    with pytest.raises(ScenarioError, match=r"observers.junctions: is \['C'\]"):
        highway_config(dataclasses.replace(s, observers={**s.observers, "junctions": ["C"]}))
    with pytest.raises(ScenarioError, match=r"observers.min_distance: is 50.0"):
        highway_config(dataclasses.replace(s, observers={**s.observers, "min_distance": 50.0}))
