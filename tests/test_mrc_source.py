"""The MRC arena source on its own (no rendering): determinism, motion, collisions, cameras, config."""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cadsim.scenario import ScenarioError, load_scenario
from cadsim.sources import make_source
from cadsim.sources.arena.config import parse_arena
from cadsim.sources.arena.motion import ArenaMotion, MotionParams, sample_free_positions
from cadsim.sources.arena.source import GROUND_ID, ArenaSource, Schedule

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "mrc-arena.toml"


@pytest.fixture(scope="module")
def traffic() -> dict:
    with SCENARIO.open("rb") as f:
        return tomllib.load(f)["traffic"]


def load_arena_source(traffic: dict, seed: int) -> ArenaSource:
    return ArenaSource(parse_arena(traffic), seed, Schedule(warm_up=2.0, interval=4.0))


def take(source: ArenaSource, n: int):
    out = []
    for snap in source.snapshots():
        out.append(snap)
        if len(out) == n:
            return out
    return out


def footprint_radius(obj) -> float:
    return 0.5 * float(np.hypot(obj.size[0], obj.size[1]))


def test_same_seed_same_snapshots_and_pairs(traffic):
    a, b = load_arena_source(traffic, 5), load_arena_source(traffic, 5)
    snaps_a, snaps_b = take(a, 6), take(b, 6)
    assert [[o.as_dict() for o in s.objects] for s in snaps_a] == [
        [o.as_dict() for o in s.objects] for s in snaps_b
    ]
    assert [s.time for s in snaps_a] == [s.time for s in snaps_b]
    assert a.observer_pairs(snaps_a[4]) == b.observer_pairs(snaps_b[4])
    # Iterating again replays the same run; another seed gives another one.
    assert [o.as_dict() for o in take(a, 3)[2].objects] == [o.as_dict() for o in snaps_a[2].objects]
    other = take(load_arena_source(traffic, 6), 1)[0]
    assert [o.center for o in other.objects] != [o.center for o in snaps_a[0].objects]


def test_snapshot_contents(traffic):
    cfg = parse_arena(traffic)
    snap = take(load_arena_source(traffic, 1), 1)[0]
    by_cls: dict[str, list] = {}
    for o in snap.objects:
        by_cls.setdefault(o.cls, []).append(o)
    assert len(by_cls["robot"]) == cfg.n_robots == 13
    assert {o.variant for o in by_cls["robot"]} == {"tab:red", "tab:green", "tab:blue"}
    assert all(o.shape == "robot" and o.target for o in by_cls["robot"])
    assert {"box", "cone", "person"} <= set(by_cls)
    assert [o.target for o in by_cls["floor"] + by_cls["wall"]] == [False] * 5
    # Every object stands on the floor: centre height = half its height.
    for o in snap.objects:
        if o.target:
            assert o.center[2] == pytest.approx(o.size[2] / 2)
    assert len({o.id for o in snap.objects}) == len(snap.objects)


def test_robots_move_and_stay_apart_and_inside(traffic):
    cfg = parse_arena(traffic)
    snaps = take(load_arena_source(traffic, 3), 25)
    half = np.asarray(cfg.size) / 2
    movers = [o.id for o in snaps[0].objects if o.cls in ("robot", "person")]
    xy = np.array([[s.by_id()[i].center[:2] for i in movers] for s in snaps])  # (t, n, 2)
    step = np.linalg.norm(np.diff(xy, axis=0), axis=2)
    assert np.median(step) > 0.2  # metres per 4 s interval: the team moves
    assert (step.max(axis=0) > 0.1).all()  # and every mover moves at some point
    for s in snaps:
        solid = [o for o in s.objects if o.target]
        c = np.array([o.center[:2] for o in solid])
        r = np.array([footprint_radius(o) for o in solid])
        gap = np.linalg.norm(c[:, None] - c[None], axis=2) - r[:, None] - r[None]
        np.fill_diagonal(gap, np.inf)
        assert gap.min() >= cfg.motion.clearance - 1e-9
        assert np.all(np.abs(c) <= half - r[:, None] + 1e-9)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31), n=st.integers(2, 14), n_static=st.integers(0, 4))
def test_motion_never_overlaps(seed, n, n_static):
    """Collision-free by construction, whatever the crowding and speeds."""
    rng = np.random.default_rng(seed)
    half = np.array([3.0, 2.5])
    radius = rng.uniform(0.15, 0.35, n)
    static_r = rng.uniform(0.1, 0.4, n_static)
    params = MotionParams(clearance=0.1)
    static_xy = sample_free_positions(rng, static_r, half, 0.1)
    pos = sample_free_positions(rng, radius, half, 0.1, static_xy, static_r)
    m = ArenaMotion(
        rng, params, half, pos, rng.uniform(-np.pi, np.pi, n), radius, rng.uniform(0.1, 1.0, n),
        np.full(n, np.pi), np.zeros(n, bool), half - 0.5, static_xy, static_r,
    )  # fmt: skip
    need = radius[:, None] + radius[None] + params.clearance
    for _ in range(120):
        m.step()
        d = np.linalg.norm(m.pos[:, None] - m.pos[None], axis=2)
        np.fill_diagonal(d, np.inf)
        assert (d >= need - 1e-9).all()
        ds = np.linalg.norm(m.pos[:, None] - static_xy[None], axis=2)
        assert (ds >= radius[:, None] + static_r[None] + params.clearance - 1e-9).all()
        assert (np.abs(m.pos) <= half - radius[:, None] + 1e-9).all()


def test_blocked_robot_finds_a_way_round():
    """Two robots heading straight at each other do not deadlock."""
    rng = np.random.default_rng(0)
    half = np.array([3.0, 3.0])
    pos = np.array([[-0.5, 0.0], [0.5, 0.0]])
    m = ArenaMotion(
        rng, MotionParams(), half, pos, np.array([0.0, np.pi]), np.full(2, 0.3), np.full(2, 0.3),
        np.full(2, np.pi / 2), np.zeros(2, bool), half - 0.5, np.zeros((0, 2)), np.zeros(0),
    )  # fmt: skip
    m.waypoint = np.array([[2.0, 0.0], [-2.0, 0.0]])  # through each other
    start = m.pos.copy()
    m.advance(20.0)
    assert (np.linalg.norm(m.pos - start, axis=1) > 0.5).all()


def test_cameras_look_where_intended(traffic):
    cfg = parse_arena(traffic)
    source = load_arena_source(traffic, 11)
    floor_xy = np.stack(np.meshgrid(np.linspace(-3, 3, 13), np.linspace(-2, 2, 9)), -1).reshape(
        -1, 2
    )
    floor = np.column_stack([floor_xy, np.zeros(len(floor_xy))])
    for snap in take(source, 12):
        robot = snap.by_id()[GROUND_ID]
        pairs = source.observer_pairs(snap)
        assert len(pairs) == cfg.aerial.candidates
        for pair in pairs:
            side, top = pair.camera1, pair.camera2
            assert pair.observer1_id == GROUND_ID
            assert side.position[2] == pytest.approx(cfg.ground.camera_height)
            assert side.yaw == pytest.approx(robot.yaw)
            # The side camera faces the arena centre within the look jitter: the centre is in
            # front of it and inside the image horizontally.
            c = side.world_to_camera(np.zeros((1, 3)))[0]
            assert c[2] > 0
            u = side.project(c[None])[0, 0]
            assert 0 <= u < side.width
            # The overhead camera's principal point lands on its floor target, which lies ahead
            # of the side camera, and it looks down steeply from the configured altitude.
            target = np.append(pair.meta["aerial_target"], 0.0)
            uv = top.project(top.world_to_camera(target[None]))[0]
            np.testing.assert_allclose(uv, [top.width / 2, top.height / 2], atol=1e-6)
            assert cfg.aerial.altitude[0] <= top.position[2] <= cfg.aerial.altitude[1]
            lo, hi = np.radians(cfg.aerial.pitch_deg)
            assert lo - 1e-9 <= top.pitch <= hi + 1e-9
            assert side.world_to_camera(target[None])[0, 2] > 0
            # Footprints overlap partially: some floor points are seen by both, not all.
            seen = [_in_image(cam, floor) for cam in (side, top)]
            both = seen[0] & seen[1]
            assert both.any() and (seen[1] & ~seen[0]).any()


def _in_image(cam, world: np.ndarray) -> np.ndarray:
    pc = cam.world_to_camera(world)
    front = pc[:, 2] > 0.2
    uv = cam.project(np.where(front[:, None], pc, 1.0))
    return front & (uv >= 0).all(1) & (uv[:, 0] < cam.width) & (uv[:, 1] < cam.height)


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda t: t.update(colour=1), "traffic.colour: unknown key"),
        (lambda t: t.update(size=[8.0]), "traffic.size: is [8.0]; expected a list of 2 numbers"),
        (lambda t: t["robots"][0].update(count="4"), "robots[0].count: has the wrong type"),
        (lambda t: t["robots"][1].update(variant="plaid"), "robots[1].variant: is 'plaid'"),
        (lambda t: t["robots"][0].pop("count"), "traffic.robots[0].count: missing"),
        (lambda t: t["robots"].append(3), "traffic.robots[3]: has the wrong type"),
        (lambda t: t.pop("robots"), "traffic.robots: missing"),
        (
            lambda t: t["objects"][0].update(cls="tree"),
            "objects[0].cls: is 'tree'; expected one of",
        ),
        (lambda t: t["motion"].update(dt=0), "traffic.motion.dt: is 0.0; expected a number > 0"),
        (lambda t: t["ground_observer"].update(variant="tab:pink"), "variant of one of the"),
        (lambda t: t["aerial_observer"].update(pitch_deg=[-50, -70]), "min <= max"),
        (lambda t: t["aerial_observer"].update(pitch_deg=[-50, 10]), "angles in [-90, 0)"),
        (lambda t: t["aerial_observer"].update(zoom=2), "traffic.aerial_observer.zoom: unknown"),
    ],
)
def test_bad_arena_tables_are_named(traffic, edit, message):
    bad = copy.deepcopy(traffic)
    edit(bad)
    with pytest.raises(ScenarioError) as err:
        parse_arena(bad, "scenarios/x.toml")
    assert str(err.value).startswith("scenarios/x.toml: traffic.")
    assert message in str(err.value)


def test_crowded_arena_is_reported(traffic):
    crowded = copy.deepcopy(traffic)
    crowded["size"] = [2.0, 2.0]
    crowded["ground_observer"]["ring_margin"] = 0.3
    with pytest.raises(ValueError, match="crowded"):
        take(load_arena_source(crowded, 0), 1)


def test_scenario_file_drives_the_schedule(tmp_path):
    text = SCENARIO.read_text().replace("max_time = 400.0", "max_time = 20.0")
    path = tmp_path / "short.toml"
    path.write_text(text)
    scenario = load_scenario(path)
    with make_source(scenario, 4, tmp_path / "work") as source:
        times = [s.time for s in source.snapshots()]
    assert times == [2.0, 6.0, 10.0, 14.0, 18.0]
    assert isinstance(source, ArenaSource)


def test_malformed_scenario_file_names_file_and_key(tmp_path):
    text = SCENARIO.read_text().replace("hfov_deg = 60.0", "hfov_deg = 'wide'", 1)
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    assert err.value.path == path
    assert err.value.key == "traffic.ground_observer.hfov_deg"
