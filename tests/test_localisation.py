"""The localisation prior in simulation: the ``[localisation]`` table, the seeded pose error (rigid,
scaling with sigma), and the reader filling ``Problem.world1/world2/world_sigma`` at read time —
the record's own draw, ``localise`` re-draws, and ``pose`` exact on a noise-free prior."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.distance import pdist
from test_generate_fakes import FAKE_STAGES, FakeScenario

from cadsim.dataset import Dataset
from cadsim.generation.pipeline import generate_dataset
from cadsim.scenario import ScenarioError, load_scenario
from cadsim.sensing.localisation import MIN_STATED_SIGMA_M, LocalisationConfig
from cadsim.sensing.pose_error import PoseError, perturbed_world
from matchers.core.registry import get

REPO = Path(__file__).resolve().parents[1]


@dataclasses.dataclass
class LocalisedScenario(FakeScenario):
    localisation: dict = dataclasses.field(default_factory=dict)


def _generate(tmp_path_factory, name: str, **scenario) -> Dataset:
    out = tmp_path_factory.mktemp("loc") / name
    generate_dataset(
        LocalisedScenario(**scenario), out, pairs=3, workers=1, stages=FAKE_STAGES, progress=False
    )
    return Dataset(out)


@pytest.fixture(scope="module")
def default_prior(tmp_path_factory) -> Dataset:
    return _generate(tmp_path_factory, "default")


@pytest.fixture(scope="module")
def exact(tmp_path_factory) -> Dataset:
    """No depth noise, no pose error: the prior is each detection through its true camera."""
    return _generate(
        tmp_path_factory,
        "exact",
        noise={"noise_rate": 0.0},
        localisation={"position_sigma_m": 0.0, "yaw_sigma_deg": 0.0},
    )


def test_table_is_validated_like_every_key(tmp_path):
    base = (REPO / "scenarios" / "cad-intersection.toml").read_text()
    vtypes = REPO / "scenarios" / "cad-vtypes.add.xml"
    (tmp_path / vtypes.name).write_bytes(vtypes.read_bytes())
    good = tmp_path / "good.toml"
    good.write_text(base + "\n[localisation]\nposition_sigma_m = 2.5\nyaw_sigma_deg = 0\n")
    assert load_scenario(good).localisation == {"position_sigma_m": 2.5, "yaw_sigma_deg": 0}
    for body, key in (
        ("position_sigma_m = -1", "localisation.position_sigma_m"),
        ('yaw_sigma_deg = "a"', "localisation.yaw_sigma_deg"),
        ("gps = 1", "localisation.gps"),
    ):
        bad = tmp_path / "bad.toml"
        bad.write_text(base + f"\n[localisation]\n{body}\n")
        with pytest.raises(ScenarioError, match=key.replace(".", r"\.")):
            load_scenario(bad)
    assert (
        LocalisationConfig().position_sigma_m == 1.2 and LocalisationConfig().yaw_sigma_deg == 0.2
    )
    assert LocalisationConfig(0.0, 0.0).stated_sigma_m == MIN_STATED_SIGMA_M
    assert LocalisationConfig(2.5, 0.4).stated_sigma_m == 2.5


def test_pose_error_is_seeded_rigid_and_scales_with_sigma():
    world = np.random.default_rng(3).normal(0, 20, (9, 3))
    pivot = np.array([5.0, -2.0, 1.6])
    one = LocalisationConfig(1.0, 0.5).draw_error(np.random.default_rng(7))
    same = LocalisationConfig(1.0, 0.5).draw_error(np.random.default_rng(7))
    other = LocalisationConfig(1.0, 0.5).draw_error(np.random.default_rng(8))
    assert isinstance(one, PoseError) and one == same and one != other
    two = LocalisationConfig(2.0, 1.0).draw_error(np.random.default_rng(7))
    assert (two.dx, two.dy, two.dyaw) == pytest.approx((2 * one.dx, 2 * one.dy, 2 * one.dyaw))
    moved = perturbed_world(world, pivot, one)
    np.testing.assert_allclose(pdist(moved), pdist(world))  # one rigid transform per view
    np.testing.assert_array_equal(moved[:, 2], world[:, 2])  # height untouched
    # Yaw-free errors: the shift is exactly (dx, dy), and twice the sigma moves twice as far.
    flat1 = LocalisationConfig(1.0, 0.0).draw_error(np.random.default_rng(7))
    flat2 = LocalisationConfig(2.0, 0.0).draw_error(np.random.default_rng(7))
    d1 = perturbed_world(world, pivot, flat1) - world
    d2 = perturbed_world(world, pivot, flat2) - world
    np.testing.assert_allclose(d1[:, :2], np.broadcast_to([flat1.dx, flat1.dy], (9, 2)))
    np.testing.assert_allclose(d2, 2 * d1)
    zero = LocalisationConfig(0.0, 0.0).draw_error(np.random.default_rng(7))
    np.testing.assert_array_equal(perturbed_world(world, pivot, zero), world)


def test_record_stores_parameters_and_seeds_not_positions(default_prior):
    pair = default_prior[0]
    record = json.loads((pair.path / "record.json").read_text())
    assert record["format_version"] == 5
    assert record["prior"] == {"kind": "pose_error", "position_sigma_m": 1.2, "yaw_sigma_deg": 0.2}
    seeds = [o["localisation_seed"] for o in record["observers"]]
    assert len(set(seeds)) == 2
    assert default_prior.manifest["generation"]["localisation"] == {}
    config, used = pair.localisation
    assert config == LocalisationConfig() and used == tuple(seeds)


def test_reader_fills_the_problem_and_localise_redraws(default_prior):
    pair = default_prior[1]
    problem = pair.problem()
    world1, world2, sigma = pair.prior()
    np.testing.assert_array_equal(problem.world1, world1)
    assert problem.world_sigma == sigma == 1.2
    # Each view's prior is that view's detections moved rigidly off the true camera placement.
    true1 = pair.cameras[0].camera_to_world(pair.view1.positions)
    np.testing.assert_allclose(pdist(world1[:, :2]), pdist(true1[:, :2]), atol=1e-9)
    assert np.abs(world1 - true1).max() > 0.01
    # No run seed and the scenario's sigmas give back the record's own draw.
    again = pair.localise(1.2, 0.2, seed=None).prior()
    np.testing.assert_array_equal(again[0], world1)
    np.testing.assert_array_equal(again[1], world2)
    # Another seed draws another error; the same seed, the same one.
    a, b = pair.localise(1.2, 0.2, seed=5).prior(), pair.localise(1.2, 0.2, seed=5).prior()
    np.testing.assert_array_equal(a[0], b[0])
    assert np.abs(a[0] - world1).max() > 1e-6
    # Without heading error, the displacement from the truth scales with the position sigma.
    small = pair.localise(1.0, 0.0, seed=5).prior()[0] - true1
    large = pair.localise(3.0, 0.0, seed=5).prior()[0] - true1
    np.testing.assert_allclose(large, 3 * small, atol=1e-9)
    exact = pair.localise(0.0, 0.0, seed=5).prior()
    np.testing.assert_allclose(exact[0], true1)
    assert exact[2] == MIN_STATED_SIGMA_M  # a stated sigma is never 0
    # Re-detection keeps the pair's prior parameters and places the new detections.
    noisier = pair.localise(2.0, 0.1, seed=5).redetect(0.02, seed=1)
    assert noisier.localisation[0] == LocalisationConfig(2.0, 0.1)
    assert noisier.prior()[0].shape == (len(noisier.view1), 3)


def test_pose_is_exact_on_a_noise_free_prior_through_the_reader(exact):
    pose = get("pose")
    found = 0
    for pair in exact:
        problem = pair.problem()
        assert problem.world_sigma == MIN_STATED_SIGMA_M
        matching = pose(problem, threshold=0.5)
        predicted = {tuple(p) for p in np.asarray(matching.pairs).tolist()}
        assert predicted == {tuple(p) for p in pair.gt_pairs.tolist()}
        found += len(predicted)
    assert found >= 9  # three pairs with at least three covisible objects each
