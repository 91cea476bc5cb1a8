"""The MRC arena rendered: what the side and overhead cameras see, real occlusion, consistent 3-D
positions across the two views, reproducible datasets, and `cadsim show` on them."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cadsim.cli import main as cadsim_main
from cadsim.dataset import Dataset
from cadsim.generation.pipeline import generate_dataset
from cadsim.scenario import load_scenario
from cadsim.sensing.depth_noise import NoiseConfig, apply_depth_noise
from cadsim.sensing.detection import DetectionConfig, detect
from cadsim.sources import make_source

pytestmark = pytest.mark.render

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "mrc-arena.toml"
N_SNAPSHOTS = 8


@pytest.fixture(scope="module")
def scenario():
    return load_scenario(SCENARIO)


@pytest.fixture(scope="module")
def rendered(scenario, tmp_path_factory):
    """(snapshot, observer pair, [side view, overhead view]) for the first candidate pair of
    N_SNAPSHOTS snapshots of one seeded arena run."""
    from cadsim.render import Renderer

    source = make_source(scenario, 7, tmp_path_factory.mktemp("arena"))
    out = []
    with Renderer(640, 480) as renderer, source:
        for snap in source.snapshots():
            pair = source.observer_pairs(snap)[0]
            views = [
                renderer.render(snap, pair.camera1, [pair.observer1_id]),
                renderer.render(snap, pair.camera2, []),
            ]
            out.append((snap, pair, views))
            if len(out) == N_SNAPSHOTS:
                break
    return out


def _detections(scenario, snap, pair, views, noise_rate: float, seed: int):
    noise = NoiseConfig(**{**scenario.noise, "noise_rate": noise_rate})
    config = DetectionConfig(**scenario.detection)
    cams = (pair.camera1, pair.camera2)
    return [
        detect(v, apply_depth_noise(v.depth, noise, np.random.default_rng([seed, k])), snap.objects, c, config)
        for k, (v, c) in enumerate(zip(views, cams, strict=True))
    ]  # fmt: skip


def test_overhead_sees_more_robots_than_side(scenario, rendered):
    counts = np.array(
        [
            [d.true_classes.count("robot") for d in _detections(scenario, *item, 0.0, 0)]
            for item in rendered
        ]
    )
    side, overhead = counts.mean(axis=0)
    assert overhead > side + 1.0
    assert (counts[:, 0] >= 1).all()  # the side camera does look at the team


def _in_frustum(camera, centres: np.ndarray, max_depth: float):
    pc = camera.world_to_camera(centres)
    ok = (pc[:, 2] > 0.3) & (pc[:, 2] < max_depth)
    uv = camera.project(np.where(ok[:, None], pc, 1.0))
    ok &= (uv >= 0).all(axis=1) & (uv[:, 0] < camera.width) & (uv[:, 1] < camera.height)
    return ok, uv, pc[:, 2]


def test_side_view_occlusion_is_real(scenario, rendered):
    """Robots that the side camera faces but does not detect are hidden behind other robots: the
    rendered instance map shows a nearer robot at their centre pixel. Such hiding is much rarer
    from above."""
    max_depth = scenario.detection["max_depth_m"]
    hidden = {0: 0, 1: 0}  # view -> robots in frustum, undetected, covered by a nearer robot
    missed = {0: [], 1: []}  # view -> fraction of robots in frustum that are not detected
    for snap, pair, views in rendered:
        dets = _detections(scenario, snap, pair, views, 0.0, 0)
        robots = [
            (i, o)
            for i, o in enumerate(snap.objects)
            if o.cls == "robot" and o.id != pair.observer1_id
        ]
        centres = np.array([o.center for _, o in robots])
        for v, (view, cam, det) in enumerate(
            zip(views, (pair.camera1, pair.camera2), dets, strict=True)
        ):
            ok, uv, depth = _in_frustum(cam, centres, max_depth)
            undetected = np.array([o.id not in det.object_ids for _, o in robots])
            missed[v].append((ok & undetected).sum() / max(ok.sum(), 1))
            for k in np.flatnonzero(ok & undetected):
                col, row = np.floor(uv[k]).astype(int)
                j = view.instance[row, col]
                if j >= 0 and snap.objects[j].cls == "robot" and j != robots[k][0]:
                    assert view.depth[row, col] < depth[k]  # the occluder is in front
                    hidden[v] += 1
    assert hidden[0] >= 3
    assert np.mean(missed[0]) > np.mean(missed[1]) + 0.1


def test_side_positions_land_on_overhead_positions(scenario, rendered):
    """Covisible robots: side-view positions mapped to the world with camera 1's pose agree with
    overhead-view positions mapped with camera 2's, up to the detector's shape bias (half the
    robot's box diagonal) plus three depth-noise standard deviations."""
    medians = {}
    for rate in (0.0, scenario.noise["noise_rate"], 0.01):
        errors = []
        for s, (snap, pair, views) in enumerate(rendered):
            d1, d2 = _detections(scenario, snap, pair, views, rate, s)
            by_id = snap.by_id()
            for i, oid in enumerate(d1.object_ids):
                if oid not in d2.object_ids or by_id[oid].cls != "robot":
                    continue
                p1, p2 = d1.positions[i], d2.positions[d2.object_ids.index(oid)]
                w1 = pair.camera1.camera_to_world(p1[None])[0]
                w2 = pair.camera2.camera_to_world(p2[None])[0]
                sigma = rate * np.hypot(p1[2] ** 2, p2[2] ** 2)
                bias = 0.5 * np.linalg.norm(by_id[oid].size)
                assert np.linalg.norm(w1 - w2) <= bias + 3 * sigma, (rate, oid)
                errors.append(np.linalg.norm(w1 - w2))
        assert len(errors) >= 10
        medians[rate] = np.median(errors)
    assert medians[0.0] < 0.1
    assert medians[0.01] > medians[0.0]


def test_identical_seeds_identical_records_and_show(tmp_path, capsys):
    a = generate_dataset(SCENARIO, tmp_path / "a", pairs=2, workers=1, progress=False)
    b = generate_dataset(SCENARIO, tmp_path / "b", pairs=2, workers=1, progress=False)
    c = generate_dataset(SCENARIO, tmp_path / "c", pairs=2, seed=99, workers=1, progress=False)
    assert a.pairs == b.pairs == 2
    assert a.checksum == b.checksum
    assert c.checksum != a.checksum
    ds = Dataset(tmp_path / "a", verify=True)
    for pair in ds:
        assert len(pair.gt_pairs) >= 3
        assert len(pair.view1) > len(pair.gt_pairs) and len(pair.view2) > len(pair.gt_pairs)
        assert pair.observer_ids[0] == "ground-robot"
        assert pair.cameras[1].position[2] > 3.0  # overhead camera flies
        assert pair.cameras[0].position[2] < 0.5  # side camera sits low
    png = tmp_path / "pair1.png"
    assert cadsim_main(["show", str(tmp_path / "a"), "--pair", "1", "--out", str(png)]) == 0
    assert png.stat().st_size > 10_000
    capsys.readouterr()
    assert cadsim_main(["info", str(tmp_path / "a"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert len(info["pairs"]) == 2
