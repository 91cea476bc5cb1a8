"""End to end on the real CAD scenario: SUMO → render → noise → detect → dataset, on the CPU.

Two pairs with one worker (through the CLI) and with two workers must give identical datasets;
the pairs follow the default scenario's observer geometry and carry the observers' true poses.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cadsim.cli import main
from cadsim.dataset import Dataset
from cadsim.generation.pipeline import generate_dataset
from cadsim.observer_pose import ObserverPose
from cadsim.sources.frustum_overlap import frustum_overlap
from cadsim.sources.observer_pairs import arm_relation

pytestmark = [pytest.mark.slow, pytest.mark.render]

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "cad-intersection.toml"


@pytest.fixture(scope="module")
def cad(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("cad") / "w1"
    args = ["generate", str(SCENARIO), "--out", str(out), "--pairs", "2", "--workers", "1"]
    assert main([*args, "--no-progress"]) == 0
    return out


def test_two_workers_give_the_same_dataset(cad, tmp_path):
    out = tmp_path / "w2"
    result = generate_dataset(SCENARIO, out, pairs=2, workers=2, progress=False)
    assert result.pairs == 2
    for name in [r["name"] for r in Dataset(cad).manifest["records"]]:
        for f in sorted((cad / "pairs" / name).iterdir()):
            assert (out / "pairs" / name / f.name).read_bytes() == f.read_bytes(), f.name
    assert Dataset(out).checksum == Dataset(cad).checksum
    assert not (out / ".work").exists()


def test_cad_pairs_satisfy_the_acceptance_rule_and_geometry(cad):
    ds = Dataset(cad, verify=True)
    assert len(ds) == 2 and ds.manifest["scenario"]["name"] == "cad-intersection"
    assert (
        ds.manifest["versions"]["libsumo"]
        and ds.manifest["scenario"]["text"] == SCENARIO.read_text()
    )
    for pair in ds:
        k = len(pair.gt_pairs)
        assert k >= 3 and len(pair.view1) > k and len(pair.view2) > k
        assert pair.color1.shape == (600, 800, 3) and pair.depth1.shape == (600, 800)
        assert all(pair.observer_ids)  # cameras ride on vehicles ...
        for view, obs in zip((pair.view1, pair.view2), pair.observer_ids, strict=True):
            assert obs not in view.object_ids  # ... which do not see themselves
        # Clean-depth positions lie near the objects' true centres, in each camera's frame.
        clean = pair.redetect(0.0, seed=0)
        objects = {o.id: o for o in pair.objects}
        for view, cam in zip((clean.view1, clean.view2), pair.cameras, strict=True):
            truth = cam.world_to_camera(np.array([objects[i].center for i in view.object_ids]))
            err = np.linalg.norm(view.positions - truth, axis=1)
            assert np.median(err) < 1.5, err


def test_cad_pairs_follow_the_default_observer_geometry_and_carry_true_poses(cad):
    ds = Dataset(cad)
    observed = set()
    for pair in ds:
        meta = pair.record["meta"]["pair"]
        centre = np.array(pair.record["meta"]["snapshot"]["junctions"][meta["junction"]])
        objects = {o.id: o for o in pair.objects}
        carriers = [objects[i] for i in pair.observer_ids]
        assert meta["relation"] == arm_relation(carriers[0].yaw, carriers[1].yaw)
        assert meta["relation"] in ("opposite", "adjacent")
        assert meta["shared_area_m2"] >= 900.0
        assert frustum_overlap(*pair.cameras, 50.0) == pytest.approx(
            meta["shared_area_m2"], abs=1e-2
        )
        assert all(5.0 <= d <= 30.0 for d in meta["distances"])
        for carrier, cam, pose, extrinsics, to_world in zip(
            carriers, pair.cameras, pair.observer_poses, pair.camera_extrinsics,
            pair.camera_to_world, strict=True,
        ):  # fmt: skip
            # Roof camera aimed at the junction centre.
            assert cam.position[2] == pytest.approx(carrier.center[2] + carrier.size[2] / 2 + 0.05)
            axis = cam.world_to_camera(np.array([[*centre, cam.position[2]]]))[0]
            assert abs(axis[0]) < 1e-6 and axis[2] > 0
            # True pose = the carrier's; the mount puts the camera on it.
            assert pose == ObserverPose.of_carrier(carrier)
            np.testing.assert_allclose(pose.body_to_world() @ extrinsics, to_world, atol=1e-9)
            assert extrinsics[0, 3] == pytest.approx(carrier.size[0] / 2 + 0.05)
        observed.add(frozenset(pair.observer_ids))
    assert len(observed) == len(ds)  # distinct_observers: no pair of vehicles twice
