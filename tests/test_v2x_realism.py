"""V2X realism: object velocities and message latency, preset specs (scale, latency), detector
errors (misses, clutter, jitter) and appearance realism (illumination, exposure)."""

from __future__ import annotations

import hashlib
import json
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from cadsim.camera import Camera
from cadsim.render.appearance import AppearanceConfig, exposed
from cadsim.sensing.detection import DetectionConfig, plan_detections
from cadsim.sensing.detector_errors import error_stream, miss_probability
from cadsim.sensing.gnss_error import PRESETS, model_of, parse_spec
from cadsim.sensing.latency import delayed_positions, sender_offset, velocities_of
from cadsim.sensing.localisation import LocalisationConfig
from cadsim.sources.sumo.frames import speed_to_velocity
from cadsim.world import WorldObject

ROOT = Path(__file__).resolve().parents[1]


# -- velocity and latency ------------------------------------------------------------------------


def test_velocity_is_recorded_and_read_back_and_defaults_to_standing_still():
    car = WorldObject("c", "car", "car", (1.0, 2.0, 0.75), 0.3, (4.6, 1.8, 1.5), (1, 1, 1))
    assert car.velocity == (0.0, 0.0, 0.0)
    moving = replace(car, velocity=(3.0, -4.0, 0.0))
    assert WorldObject.from_dict(moving.as_dict()) == moving
    old = moving.as_dict()
    del old["velocity"]  # a format-version-2 record
    assert WorldObject.from_dict(old).velocity == (0.0, 0.0, 0.0)


def test_sumo_speed_becomes_a_world_velocity_along_the_heading():
    v = speed_to_velocity([10.0, 2.0], [0.0, np.pi / 2])
    np.testing.assert_allclose(v, [[10.0, 0.0, 0.0], [0.0, 2.0, 0.0]], atol=1e-12)


@pytest.mark.parametrize("latency_s", [0.1, 0.3])
def test_latency_moves_each_object_by_its_velocity_times_the_latency(latency_s):
    rng = np.random.default_rng(0)
    camera = Camera((5.0, -3.0, 1.6), yaw=0.7, pitch=-0.05)
    world = rng.uniform(-20, 20, (6, 3)) + [30.0, 0.0, 0.0]
    local = camera.world_to_camera(world)
    velocities = rng.normal(0, 8, (6, 3))
    sender = np.array([6.0, 1.0, 0.0])
    delayed = delayed_positions(
        local, velocities, sender, camera.rotation_cam_to_world(), latency_s
    )
    # seen from where the sender was Δt ago: every object where it was Δt ago
    then = camera.camera_to_world(delayed) + sender_offset(sender, latency_s)
    np.testing.assert_allclose(then, world - velocities * latency_s, atol=1e-9)
    # no latency: nothing moves; an unknown id (clutter) stands still
    assert delayed_positions(local, velocities, sender, np.eye(3), 0.0) is not None
    np.testing.assert_array_equal(
        delayed_positions(local, velocities, sender, camera.rotation_cam_to_world(), 0.0), local
    )
    np.testing.assert_array_equal(
        velocities_of(["a", "clutter:1"], {"a": (1.0, 2.0, 0.0)}), [[1, 2, 0], [0, 0, 0]]
    )


# -- preset specs -------------------------------------------------------------------------------


def test_preset_specs_scale_the_errors_and_set_the_latency():
    assert parse_spec("gnss-urban") == ("gnss-urban", 1.0, None)
    assert parse_spec("gnss-urban*2.5+300ms") == ("gnss-urban", 2.5, 300.0)
    urban = PRESETS["gnss-urban"]
    doubled = model_of("gnss-urban*2")
    assert (
        doubled.bias_m == 2 * urban.bias_m
        and doubled.heading_noise_deg == 2 * urban.heading_noise_deg
    )
    assert doubled.outlier_rate == urban.outlier_rate and doubled.latency_ms == urban.latency_ms
    assert model_of("gnss-urban*0").bias_m == 0 and model_of("gnss-urban+0ms").latency_ms == 0
    assert LocalisationConfig(preset="gnss-urban").latency_s == pytest.approx(0.1)
    assert LocalisationConfig(preset="gnss-open-sky").latency_s == 0.0
    assert LocalisationConfig().latency_s == 0.0  # the i.i.d. model: no latency
    for bad in ("gnss-urban*", "gnss-urban+3s", "gps*2", "gnss-urban*-1"):
        with pytest.raises(ValueError, match=r"\*SCALE and/or \+LATENCYms"):
            parse_spec(bad)


# -- detector errors ----------------------------------------------------------------------------


def _scene(n: int = 12):
    """A synthetic view: ``n`` boxes side by side at growing depth on a wall 40 m away."""
    camera = Camera((0.0, 0.0, 1.5), yaw=0.0, width=240, height=120)
    instance = np.full((120, 240), -1, dtype=np.int32)
    depth = np.full((120, 240), 40.0, dtype=np.float32)
    objects = []
    for k in range(n):
        x0 = 4 + 19 * k
        instance[50:80, x0 : x0 + 15] = k
        depth[50:80, x0 : x0 + 15] = 5.0 + 3 * k
        objects.append(
            WorldObject(
                f"o{k}", "car", "car", (5.0 + 3 * k, 0.0, 0.75), 0.0, (4.0, 1.8, 1.5), (1, 1, 1)
            )
        )
    color = np.random.default_rng(3).integers(0, 255, (120, 240, 3), dtype=np.uint8)
    return camera, instance, depth, objects, color


def _plan(config: DetectionConfig, seed: int = 5):
    camera, instance, depth, objects, color = _scene()
    loose = replace(config, min_visible_fraction=0.0, max_truncation=1.0, min_pixels=20)
    return plan_detections(
        instance,
        depth,
        objects,
        camera,
        loose,
        lambda: color,
        attribute_rng=np.random.default_rng(seed),
    )


def test_detector_errors_are_off_by_default_and_seeded():
    clean = _plan(DetectionConfig())
    assert not DetectionConfig().has_errors and len(clean) == 12
    noisy = DetectionConfig(miss_near=0.3, false_positives=3.0, centre_jitter=0.1)
    a, b, c = _plan(noisy, 5), _plan(noisy, 5), _plan(noisy, 6)
    assert [o.id for o in a.objects] == [o.id for o in b.objects]
    np.testing.assert_array_equal(a.centres, b.centres)
    np.testing.assert_array_equal(a.features, b.features)
    assert [o.id for o in a.objects] != [o.id for o in c.objects] or not np.array_equal(
        a.centres, c.centres
    )
    # the error stream is a child of the attribute stream, which it does not advance
    rng = np.random.default_rng(5)
    error_stream(rng)
    assert rng.random() == np.random.default_rng(5).random()


def test_misses_grow_with_distance_and_occlusion_and_happen_at_their_rate():
    p = miss_probability([0.0, 40.0, 80.0, 80.0], [1.0, 1.0, 1.0, 0.0], 0.1, 0.4, 0.5, 80.0)
    np.testing.assert_allclose(p, [0.1, 0.3, 0.5, 1.0])
    kept = [
        len([o for o in _plan(DetectionConfig(miss_near=0.25), s).objects if o.id.startswith("o")])
        for s in range(200)
    ]
    assert abs(np.mean(kept) / 12 - 0.75) < 0.03


def test_clutter_is_never_a_true_pair_and_jitter_moves_centres_by_the_box_size():
    plans = [_plan(DetectionConfig(false_positives=2.0), s) for s in range(40)]
    clutter = [o.id for p in plans for o in p.objects if o.id.startswith("clutter:")]
    assert 40 < len(clutter) < 130  # Poisson(2) per view, a few dropped for lack of depth
    assert len(set(clutter)) == len(clutter)  # its own id: no other view can share it
    clean = _plan(DetectionConfig())
    jittered = _plan(DetectionConfig(centre_jitter=0.2))
    moved = (jittered.centres - clean.centres) / (clean.boxes[:, 2:] - clean.boxes[:, :2])
    assert 0.1 < moved.std() < 0.3
    np.testing.assert_array_equal(jittered.boxes, clean.boxes)


def test_detector_keys_are_validated_like_every_key():
    with pytest.raises(ValueError, match=r"\[detection\] miss_far must be <= 1.0"):
        DetectionConfig(miss_far=1.5)
    with pytest.raises(ValueError, match=r"\[detection\] false_positives must be >= 0.0"):
        DetectionConfig(false_positives=-1.0)


# -- appearance ---------------------------------------------------------------------------------


def test_appearance_draws_one_light_per_episode_and_a_gain_per_camera():
    config = AppearanceConfig(exposure_sigma=0.5, white_balance_sigma=0.1)
    assert config.lighting(7) == config.lighting(7) != config.lighting(8)
    light = config.lighting(7)
    assert 20.0 <= light.sun_elevation_deg <= 70.0 and 0.3 <= light.ambient <= 0.55
    gains = config.camera_gains(np.random.default_rng(1))
    assert np.all(gains > 0) and not np.allclose(gains, 1.0)
    np.testing.assert_array_equal(AppearanceConfig().camera_gains(np.random.default_rng(1)), 1.0)
    image = np.random.default_rng(0).integers(0, 255, (8, 8, 3), dtype=np.uint8)
    np.testing.assert_array_equal(exposed(image, np.ones(3)), image)
    brighter = exposed(image, np.array([2.0, 2.0, 2.0]))
    assert np.all(brighter >= image) and brighter.mean() > image.mean()
    with pytest.raises(ValueError, match=r"\[appearance\] ambient: expected low <= high"):
        AppearanceConfig(ambient=(0.6, 0.2))


# -- generated data -----------------------------------------------------------------------------

# e00000_s00 of a 2-pair cad-intersection dataset. Re-pinned for per-object sizes (size model 2,
# cadsim.object_sizes): every vehicle, person, sign and signal pole now has its own size, so the
# images, depth, instance maps and detections of the record changed once; they are pinned again
# here so that any later change shows. Detections' features and positions do not go through BLAS
# (the same bytes on every CPU), and a two-view scenario's records are unchanged by N-view
# snapshots (docs/multi-agent.md). Re-pinned again for the demand drawn in process (demand model
# 1, cadsim/sources/sumo/demand.py) and one pair per episode: other traffic, other images.
# Re-pinned for cad-v2x's appearance model in cad-intersection (issue 56): colour and the
# features change; depth and instance maps do not.
# detections.npz re-pinned for attributes measured from the view (cadsim.sensing.attribute_noise:
# sizes from the mask and depth, estimated headings, the centre shift from the estimates).
CAD_FIRST_RECORD_SHA256 = {
    "view1.png": "6f42fd9feeaa95b2e10249d07ba9f6d6928648a3c63f7788ad85c6ce024cd7c3",
    "view2.png": "ed5e1c8233569380d737d14c4d0f8a28b0d724b17ae5a606392adf3557816ca0",
    "depth.npz": "5d0ac9c6677c33723c645824aadd502e47ca481810a4bbf76a34a28ad376b532",
    "instance.npz": "c0b105fd9d6ef6d6ce8a62eb65030c05ce49db46057de8a982b61c6d7335cf06",
    # format 5 stores true_classes and reported_classes (was: classes)
    "detections.npz": "eeff6bd60f3b7b7df1b272932946ff169227d78f4d83bff0bdb27153473c1565",
}


@pytest.fixture(scope="module")
def v2x_pair(tmp_path_factory):
    """3 pairs of cad-v2x, and of the same scenario without its [appearance] table."""
    from cadsim.generation.pipeline import generate_dataset
    from cadsim.scenario import load_scenario

    tmp = tmp_path_factory.mktemp("v2x")
    text = (ROOT / "scenarios" / "cad-v2x.toml").read_text()
    plain = tmp / "cad-v2x-plain.toml"
    start = text.index("[appearance]")
    end = text.index("\n[", start)  # the next table
    plain.write_text(text[:start] + text[end + 1 :])
    shutil.copy(ROOT / "scenarios" / "cad-vtypes.add.xml", tmp / "cad-vtypes.add.xml")
    made = {}
    for name, path in (("realism", ROOT / "scenarios" / "cad-v2x.toml"), ("plain", plain)):
        generate_dataset(load_scenario(path), tmp / name, pairs=3, workers=1, progress=False)
        made[name] = tmp / name
    return made


def test_existing_scenarios_render_and_detect_as_pinned(tmp_path):
    from cadsim.generation.pipeline import generate_dataset
    from cadsim.scenario import load_scenario

    scenario = load_scenario(ROOT / "scenarios" / "cad-intersection.toml")
    generate_dataset(scenario, tmp_path / "cad", pairs=2, workers=1, progress=False)
    record = tmp_path / "cad" / "pairs" / "e00000_s00"
    for name, digest in CAD_FIRST_RECORD_SHA256.items():
        assert hashlib.sha256((record / name).read_bytes()).hexdigest() == digest, name
    objects = json.loads((record / "record.json").read_text())["objects"]
    speeds = [np.hypot(*o["velocity"][:2]) for o in objects]
    assert all(len(o["velocity"]) == 3 for o in objects) and max(speeds) > 1.0  # traffic moves


def test_appearance_realism_makes_matched_pairs_look_less_alike(v2x_pair):
    # the same records (same seeds, same geometry); only the light and the cameras differ, so
    # a true pair's feature distance grows (4 pairs, measured: 0.38 -> 0.56 mean)
    from cadsim.dataset import Dataset

    spread = {}
    for name, path in v2x_pair.items():
        distances = []
        for pair in Dataset(path):
            f1, f2 = (np.asarray(v.features, float) for v in (pair.view1, pair.view2))
            f1 /= np.linalg.norm(f1, axis=1, keepdims=True)
            f2 /= np.linalg.norm(f2, axis=1, keepdims=True)
            distances += [1 - f1[i] @ f2[j] for i, j in pair.gt_pairs]
        spread[name] = np.mean(distances)
        first = path / "pairs" / "e00000_s00"
        spread[name + "_instance"] = (first / "instance.npz").read_bytes()
    assert spread["realism"] > spread["plain"] + 0.1
    assert spread["realism_instance"] == spread["plain_instance"]  # geometry untouched


def test_a_version_2_dataset_is_read_but_refused_under_a_latency_preset(v2x_pair, tmp_path):
    from dataset_forgery import as_older_version

    from cadsim.dataset import Dataset
    from eval.engine.splits import open_entry

    old = tmp_path / "old"
    shutil.copytree(v2x_pair["plain"], old)
    as_older_version(old, 2)  # as version 2 stored it: a forged number alone is refused
    assert len(Dataset(old, verify=True)) == 3
    open_entry(old, None, localisation="gnss-open-sky")  # no latency: read
    with pytest.raises(ValueError) as info:
        open_entry(old, None, localisation="gnss-urban")
    message = str(info.value)
    assert "\n" not in message and "100 ms" in message and "version 2" in message
    pair = Dataset(v2x_pair["plain"])[0]
    at_100 = pair.localise_preset("gnss-urban*0", seed=0).problem()
    at_0 = pair.localise_preset("gnss-urban*0+0ms", seed=0).problem()
    moved = np.linalg.norm(at_100.points2 - at_0.points2, axis=1)
    assert moved.max() > 0.2 and np.allclose(at_100.points1, at_0.points1)
