"""The GNSS-like localisation error: a bias shared by a vehicle's views in one episode, a bounded
random walk, heading error independent of position error, outliers at their rate, presets
validated like every scenario key, and `denied` giving no prior."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cadsim.sensing.gnss_error import (
    PRESETS,
    WALK_STEP_S,
    GnssErrorModel,
    draw_error,
    episode_draws,
    preset,
)
from cadsim.sensing.localisation import MIN_STATED_SIGMA_M, LocalisationConfig


def test_the_bias_is_shared_within_an_episode_and_differs_between_vehicles_and_episodes():
    model = GnssErrorModel(bias_m=2.0, heading_bias_deg=1.0)  # no walk, no per-view noise
    a = draw_error(model, 11, "veh3", 10.0, view_seed=1)
    b = draw_error(model, 11, "veh3", 250.0, view_seed=99)  # later, another view's seed
    assert (a.dx, a.dy, a.dyaw) == (b.dx, b.dy, b.dyaw)
    other_vehicle = draw_error(model, 11, "veh4", 10.0, view_seed=1)
    other_episode = draw_error(model, 12, "veh3", 10.0, view_seed=1)
    assert (a.dx, a.dy) != (other_vehicle.dx, other_vehicle.dy)
    assert (a.dx, a.dy) != (other_episode.dx, other_episode.dy)


def test_the_random_walk_drifts_slowly_with_increments_of_its_stated_size():
    model = GnssErrorModel(walk_m_per_sqrt_s=0.2)
    times = np.arange(0.0, 400.0, WALK_STEP_S)
    steps = []
    for vehicle in range(40):
        path = np.array([episode_draws(model, 5, f"v{vehicle}", t)[0] for t in times])
        steps.append(np.diff(path, axis=0))
    steps = np.concatenate(steps)
    assert steps.std() == pytest.approx(0.2 * np.sqrt(WALK_STEP_S), rel=0.05)
    assert np.abs(steps).max() < 6 * 0.2  # bounded: no jumps from the walk itself
    # between grid points the walk is linear, so it is continuous in time
    a, _ = episode_draws(model, 5, "v0", 10.0)
    b, _ = episode_draws(model, 5, "v0", 10.5)
    c, _ = episode_draws(model, 5, "v0", 11.0)
    assert np.allclose(b, (a + c) / 2)


def test_heading_error_is_independent_of_position_error():
    model = GnssErrorModel(bias_m=2.0, noise_m=1.0, heading_bias_deg=1.0, heading_noise_deg=0.5)
    draws = [draw_error(model, e, "v", 30.0, view_seed=e + 7) for e in range(3000)]
    dx = np.array([d.dx for d in draws])
    yaw = np.array([d.dyaw for d in draws])
    assert abs(np.corrcoef(dx, yaw)[0, 1]) < 0.06
    assert abs(np.corrcoef(np.hypot(dx, [d.dy for d in draws]), np.abs(yaw))[0, 1]) < 0.06
    assert np.degrees(yaw).std() == pytest.approx(np.hypot(1.0, 0.5), rel=0.1)


def test_outliers_jump_by_their_size_at_their_rate():
    model = GnssErrorModel(outlier_rate=0.1, outlier_m=8.0)
    size = np.array(
        [np.hypot(*dataclasses.astuple(draw_error(model, 1, "v", 0.0, s))[:2]) for s in range(5000)]
    )
    jumped = size > 1.0
    assert np.allclose(size[jumped], 8.0)
    rate = jumped.mean()
    assert abs(rate - 0.1) < 3 * np.sqrt(0.1 * 0.9 / len(size))


def test_presets_are_validated_and_ordered_by_how_good_the_receiver_is():
    with pytest.raises(ValueError, match=r"\[localisation\] preset: expected one of exact, rtk"):
        LocalisationConfig(preset="gps")
    with pytest.raises(ValueError, match="preset: expected one of"):
        preset("gps")
    with pytest.raises(ValueError, match="outlier_rate"):
        GnssErrorModel(outlier_rate=1.5)
    assert set(PRESETS) == {"exact", "rtk", "gnss-open-sky", "gnss-urban", "denied"}
    order = [PRESETS[n] for n in ("exact", "rtk", "gnss-open-sky", "gnss-urban")]
    assert [m.bias_m for m in order] == sorted(m.bias_m for m in order)
    assert not PRESETS["denied"].given and all(m.given for m in order)
    exact = draw_error(PRESETS["exact"], 3, "v", 100.0, 4)
    assert (exact.dx, exact.dy, exact.dyaw) == (0.0, 0.0, 0.0)
    # the stated sigma is the receiver's report, floored as the i.i.d. model's
    assert LocalisationConfig(preset="gnss-urban").stated_sigma_m == 3.2
    assert LocalisationConfig(preset="rtk").stated_sigma_m == MIN_STATED_SIGMA_M


def test_a_record_without_a_preset_stores_exactly_what_it_did_before():
    assert LocalisationConfig().as_record() == {"position_sigma_m": 1.2, "yaw_sigma_deg": 0.2}
    assert LocalisationConfig(preset="rtk").as_record()["preset"] == "rtk"


def _generated(tmp_path, localisation: dict, seed: int = 11):
    from test_generate_fakes import FAKE_STAGES, FakeScenario

    from cadsim.dataset import Dataset
    from cadsim.generation.pipeline import generate_dataset

    @dataclasses.dataclass
    class Scenario(FakeScenario):
        localisation: dict = dataclasses.field(default_factory=dict)

    out = tmp_path / "ds"
    scenario = Scenario(noise={"noise_rate": 0.0}, localisation=localisation)
    generate_dataset(
        scenario, out, pairs=3, seed=seed, workers=1, stages=FAKE_STAGES, progress=False
    )
    return Dataset(out)


def test_a_preset_dataset_draws_its_prior_from_the_gnss_model_and_denied_gives_none(tmp_path):
    urban = _generated(tmp_path / "u", {"preset": "gnss-urban"})
    pair = urban[0]
    assert pair.record["prior"]["preset"] == "gnss-urban"
    world1, world2, stated = pair.prior()
    assert stated == 3.2 and world1.shape == (len(pair.view1), 3)
    truth = [
        pair.camera_to_world[0][:3, :3] @ p + pair.camera_to_world[0][:3, 3]
        for p in pair.view1.positions
    ]
    assert not np.allclose(world1, truth)  # the error is applied
    denied = _generated(tmp_path / "d", {"preset": "denied"})
    assert denied[0].prior() is None and denied[0].problem().world1 is None


def test_under_denied_a_prior_matcher_declares_nothing_and_the_run_succeeds(tmp_path):
    from eval.core.cache import ResultCache
    from eval.core.executor import SerialExecutor
    from eval.core.runner import Runner, requests_for
    from eval.core.tasks import MatcherSpec

    denied = _generated(tmp_path, {"preset": "denied"})
    runner = Runner(ResultCache(tmp_path / "cache"), SerialExecutor(), progress=False)
    runs = runner.run(
        requests_for(
            [(str(denied.path), denied.checksum)], [MatcherSpec("pose"), MatcherSpec("sm")], [0]
        )
    )
    pose = next(r for r in runs if r.spec.matcher.name == "pose")
    sm = next(r for r in runs if r.spec.matcher.name == "sm")
    assert all(len(o.assigned) == 0 and not o.scores.any() for o in pose.outcomes)
    assert any(len(o.assigned) for o in sm.outcomes)  # the others run as usual


def test_re_drawing_with_no_seed_and_own_preset_gives_back_the_records_prior(tmp_path):
    urban = _generated(tmp_path, {"preset": "gnss-urban"})
    root = int(urban.manifest["seeds"]["root"])
    for pair in urban:
        own = pair.prior()
        again = pair.localise_preset("gnss-urban", seed=None).prior()
        assert np.array_equal(own[0], again[0]) and np.array_equal(own[1], again[1])
        for run in (0, root):  # a run's draw is never the record's own, not even at the root
            other = pair.localise_preset("gnss-urban", seed=run).prior()
            assert not np.array_equal(own[0], other[0])
        assert pair.localise_preset("denied", seed=0).prior() is None


def test_evaluate_with_a_preset_re_draws_every_prior_and_denied_keeps_the_rows(tmp_path, capsys):
    import pandas as pd

    from cadsim.cli import main

    data = _generated(tmp_path / "t", {})
    val = _generated(tmp_path / "v", {}, seed=1011)
    common = ["--val", str(val.path), "--matchers", "pose,sm", "--runs", "1", "--workers", "1"]
    common += ["--cache", str(tmp_path / "cache"), "--no-progress"]
    out = tmp_path / "denied"
    assert (
        main(["evaluate", str(data.path), *common, "--localisation", "denied", "--out", str(out)])
        == 0
    )
    table = pd.read_csv(out / "table1.csv").set_index("matcher")
    assert table.loc["pose", "f1_mean"] == 0.0 and table.loc["sm", "f1_mean"] > 0
    own = tmp_path / "own"
    assert main(["evaluate", str(data.path), *common, "--out", str(own)]) == 0
    assert pd.read_csv(own / "table1.csv").set_index("matcher").loc["pose", "f1_mean"] > 0
    with pytest.raises(SystemExit) as stop:  # a usage error, one line naming the choices
        main(["evaluate", str(data.path), *common, "--localisation", "gps", "--out", str(own)])
    assert stop.value.code == 2 and "expected one of exact" in capsys.readouterr().err


def test_a_validation_and_a_test_split_never_share_a_runs_localisation_draw(tmp_path):
    """Seed scheme 2: a run's redraw is seeded by the run seed *and* the record's simulation
    seed (which carries the dataset's root seed), so two splits made with different seeds see
    different GNSS errors in the same run, record for record."""
    test = _generated(tmp_path / "test", {"preset": "gnss-urban"}, seed=11)
    val = _generated(tmp_path / "val", {"preset": "gnss-urban"}, seed=1011)
    for a, b in zip(test, val, strict=True):
        assert (a.episode, a.slot) == (b.episode, b.slot)
        ra, rb = a.localise_preset("gnss-urban", seed=0), b.localise_preset("gnss-urban", seed=0)
        assert set(ra.localisation[1]).isdisjoint(rb.localisation[1])  # per-view + episode seeds
        errors = []
        for pair in (ra, rb):
            world1 = pair.prior()[0]
            true1 = pair.cameras[0].camera_to_world(pair.view1.positions)
            errors.append((world1 - true1).mean(axis=0))
        assert not np.allclose(errors[0], errors[1], atol=1e-6)
        # ... and the depth noise of a run differs too
        assert a._noise_seed(0, 1, a._observers[0]) != b._noise_seed(0, 1, b._observers[0])


def test_the_calibration_statistic_grows_with_the_presets_error(tmp_path):
    from eval.studies.v2x.gnss_calibration import match_disagreement, summary

    data = _generated(tmp_path, {})
    exact = match_disagreement([data.path], "exact")
    open_sky = match_disagreement([data.path], "gnss-open-sky")
    urban = match_disagreement([data.path], "gnss-urban")
    assert len(exact) == len(open_sky) == sum(len(p.gt_pairs) for p in data) > 0
    assert np.median(exact) < 0.3  # exact poses: only the detections' own error
    assert np.median(exact) + 0.3 < np.median(open_sky) < np.median(urban)
    assert summary(open_sky)["matches"] == len(open_sky) and np.isnan(summary([])["median_m"])
