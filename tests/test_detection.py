"""Detection adapter: filters, positions from noisy depth, features. Rendered tiny scenes."""

import numpy as np
import pytest
from render_fixtures import cam

from cadsim.render import RenderedView
from cadsim.sensing.depth_noise import NoiseConfig, apply_depth_noise
from cadsim.sensing.detection import DetectionConfig, Detections, detect
from cadsim.sensing.features import FEATURE_DIM, FEATURE_LAYOUT
from cadsim.world import Snapshot, WorldObject

pytestmark = pytest.mark.render


def car(oid, x, y, color=(0.8, 0.1, 0.1), yaw=np.pi / 2):
    return WorldObject(oid, "car", "car", (x, y, 0.75), yaw, (4.5, 1.8, 1.5), color)


def building(oid, x, y, size=(4.0, 12.0, 8.0)):
    return WorldObject(
        oid, "building", "building", (x, y, size[2] / 2), 0.0, size, (0.6, 0.55, 0.5), target=False
    )


def clean_detect(renderer, objects, camera=None, config=None):
    camera = camera or cam()
    config = config or DetectionConfig()
    view = renderer.render(Snapshot(0.0, objects), camera)
    return view, detect(view, view.depth, objects, camera, config)


def test_object_behind_a_building_is_not_detected(renderer):
    hidden = car("hidden", 25.0, 0.0)
    _, alone = clean_detect(renderer, [hidden])
    assert alone.object_ids == ["hidden"]
    view, dets = clean_detect(renderer, [hidden, building("b", 15.0, 0.0)])
    assert dets.object_ids == [] and len(dets) == 0
    assert dets.features.shape == (0, FEATURE_DIM) and dets.positions.shape == (0, 3)
    assert 1 in np.unique(view.instance)  # the building is visible, but it is not a target


def test_mostly_occluded_object_is_filtered_by_visible_fraction(renderer):
    # The building hides all but a sliver (~9 % of the projected box) of the car.
    objects = [car("c", 14.0, 4.2, yaw=0.0), building("b", 8.0, -0.3, size=(2.0, 6.0, 8.0))]
    view, strict = clean_detect(renderer, objects)
    visible = int((view.instance == 0).sum())
    assert visible >= DetectionConfig().min_pixels
    assert strict.object_ids == []
    _, lenient = clean_detect(renderer, objects, config=DetectionConfig(min_visible_fraction=0.0))
    assert lenient.object_ids == ["c"] and lenient.pixels[0] == visible


def test_min_pixels_and_max_depth_filters(renderer):
    near, far = car("near", 12.0, 2.0), car("far", 75.0, -6.0)
    _, dets = clean_detect(
        renderer, [near, far], config=DetectionConfig(min_pixels=20, max_depth_m=200.0)
    )
    assert sorted(dets.object_ids) == ["far", "near"]
    far_px = dets.pixels[dets.object_ids.index("far")]
    _, dets = clean_detect(
        renderer, [near, far], config=DetectionConfig(min_pixels=int(far_px) + 1, max_depth_m=200.0)
    )
    assert dets.object_ids == ["near"]
    _, dets = clean_detect(
        renderer, [near, far], config=DetectionConfig(min_pixels=20, max_depth_m=40.0)
    )
    assert dets.object_ids == ["near"]


def test_truncation_at_the_image_border(renderer):
    c = cam()
    # Left edge of a 90° view at x = 10 m is y = 10 m; shift a car so that ~1/4 or ~3/4 is inside.
    mostly_out = car("out", 10.0, 11.6, yaw=np.pi / 2)
    mostly_in = car("in", 10.0, 8.0, yaw=np.pi / 2)
    for obj, kept in ((mostly_out, False), (mostly_in, True)):
        view, dets = clean_detect(renderer, [obj], c)
        assert (view.instance == 0).sum() > 200
        assert (obj.id in dets.object_ids) == kept, obj.id
    _, dets = clean_detect(renderer, [mostly_out], c, DetectionConfig(max_truncation=1.0))
    assert dets.object_ids == ["out"]


def test_clean_positions_are_near_the_object_centres(renderer):
    objects = [car("a", 14.0, 3.0), car("b", 22.0, -2.0, yaw=0.3), car("c", 30.0, 1.0, yaw=0.0)]
    c = cam()
    _, dets = clean_detect(renderer, objects, c)
    truth = c.world_to_camera(np.array([o.center for o in objects]))
    order = [dets.object_ids.index(o.id) for o in objects]
    err = np.linalg.norm(dets.positions[order] - truth, axis=1)
    assert np.all(err < 0.45), err
    # Without moving the surface point to the centre, the error is about half the box depth.
    _, surf = clean_detect(renderer, objects, c, DetectionConfig(surface_to_center=False))
    err_surface = np.linalg.norm(surf.positions[order] - truth, axis=1)
    assert np.all(err_surface > err) and err_surface[2] > 1.5  # car "c" seen end-on (4.5 m long)
    # Boxes contain the projected centres; camera frame is OpenCV (z forward, y down).
    uv = c.project(truth)
    b = dets.boxes[order]
    assert np.all(
        (b[:, 0] <= uv[:, 0])
        & (uv[:, 0] <= b[:, 2])
        & (b[:, 1] <= uv[:, 1])
        & (uv[:, 1] <= b[:, 3])
    )


def _position_errors(renderer, distance, rates, seeds):
    """RMS over seeds of |noisy position - clean position| of a 2 m box straight ahead."""
    obj = WorldObject(
        "box", "box", "box", (distance + 1.0, 0.0, 1.6), 0.0, (2.0, 2.0, 2.0), (0.2, 0.6, 0.9)
    )
    c = cam()
    view = renderer.render(Snapshot(0.0, [obj]), c)
    clean = detect(view, view.depth, [obj], c, DetectionConfig(min_pixels=10)).positions[0]
    out = []
    for rate in rates:
        cfg = NoiseConfig(noise_rate=rate, correlation_length_px=60.0, correlated_fraction=0.8)
        errs = []
        for s in seeds:
            noisy = apply_depth_noise(view.depth, cfg, np.random.default_rng(s))
            dets = detect(view, noisy, [obj], c, DetectionConfig(min_pixels=10))
            errs.append(np.linalg.norm(dets.positions[0] - clean))
        out.append(np.sqrt(np.mean(np.square(errs))))
    return np.array(out)


def test_position_error_grows_with_depth_squared_and_with_noise_rate(renderer):
    seeds = range(30)
    rates = [0.0005, 0.001, 0.002]
    errs = {d: _position_errors(renderer, d, rates, seeds) for d in (8.0, 16.0, 32.0)}
    for d in errs:
        # Linear in noise_rate: the median of the mask is scale-equivariant.
        np.testing.assert_allclose(errs[d][1:] / errs[d][:-1], 2.0, rtol=0.05)
    for rate_k in range(len(rates)):
        e = np.array([errs[d][rate_k] for d in (8.0, 16.0, 32.0)])
        ratios = e[1:] / e[:-1]
        assert np.all((ratios > 3.0) & (ratios < 5.5)), ratios  # d doubles -> error x ~4
    # Absolute scale: the correlated part dominates the median, σ = rate·d².
    assert 0.3 * 0.001 * 16.0**2 < errs[16.0][1] < 1.2 * 0.001 * 16.0**2


def test_features_fixed_width_non_negative_and_look_alikes_match(renderer):
    objects = [
        car("red1", 14.0, 3.0, (0.8, 0.1, 0.1)),
        car("red2", 14.0, -3.0, (0.8, 0.1, 0.1)),
        car("blue", 20.0, 0.0, (0.1, 0.2, 0.8)),
        WorldObject(
            "p", "person", "person", (10.0, -1.5, 0.875), np.pi, (0.3, 0.5, 1.75), (0.8, 0.1, 0.1)
        ),
    ]
    _, dets = clean_detect(renderer, objects)
    assert sorted(dets.object_ids) == ["blue", "p", "red1", "red2"]
    f = dets.features
    assert f.shape == (4, FEATURE_DIM) and f.dtype == np.float32 and np.all(f >= 0)
    for block in FEATURE_LAYOUT.values():
        np.testing.assert_allclose(np.linalg.norm(f[:, block], axis=1), 1.0, rtol=1e-5)
    idx = {k: dets.object_ids.index(k) for k in dets.object_ids}
    col = f[:, FEATURE_LAYOUT["color"]]
    cos = col @ col.T
    assert cos[idx["red1"], idx["red2"]] > 0.9
    assert cos[idx["red1"], idx["blue"]] < 0.3
    attr = f[:, FEATURE_LAYOUT["attributes"]]
    assert attr[idx["red1"]] @ attr[idx["red2"]] == pytest.approx(1.0)
    assert attr[idx["red1"]] @ attr[idx["p"]] < 0.2  # different class and size
    assert dets.true_classes[idx["p"]] == "person"


def test_redetection_from_stored_arrays_needs_no_renderer(renderer):
    objects = [car("a", 14.0, 3.0), car("b", 20.0, -2.0, (0.1, 0.8, 0.2))]
    c = cam()
    view = renderer.render(Snapshot(0.0, objects), c)
    stored = RenderedView(view.color.copy(), view.depth.copy(), view.instance.copy())
    cfg = NoiseConfig(noise_rate=0.002)
    first = detect(
        view,
        apply_depth_noise(view.depth, cfg, np.random.default_rng(1)),
        objects,
        c,
        DetectionConfig(),
    )
    again = detect(
        stored,
        apply_depth_noise(stored.depth, cfg, np.random.default_rng(1)),
        objects,
        c,
        DetectionConfig(),
    )
    assert isinstance(again, Detections) and again.object_ids == first.object_ids
    np.testing.assert_array_equal(again.positions, first.positions)
    np.testing.assert_array_equal(again.features, first.features)
    other = detect(
        stored,
        apply_depth_noise(stored.depth, NoiseConfig(noise_rate=0.02), np.random.default_rng(1)),
        objects,
        c,
        DetectionConfig(),
    )
    assert other.object_ids == first.object_ids  # the noise changes positions, not the detections
    np.testing.assert_array_equal(other.features, first.features)
    assert not np.allclose(other.positions, first.positions)


def test_mismatched_inputs_are_rejected(renderer):
    objects = [car("a", 14.0, 3.0)]
    view = renderer.render(Snapshot(0.0, objects), cam())
    with pytest.raises(ValueError, match="noisy_depth"):
        detect(view, view.depth[:10], objects, cam(), DetectionConfig())
    with pytest.raises(ValueError, match="object index 0 but only 0 objects"):
        detect(view, view.depth, [], cam(), DetectionConfig())
    with pytest.raises(ValueError, match=r"x\.toml \[detection\]: unknown key\(s\) min_pixel\b"):
        DetectionConfig.from_table({"min_pixel": 3}, "x.toml [detection]")
    with pytest.raises(TypeError, match="min_pixels must be an integer"):
        DetectionConfig(min_pixels=2.5)
