"""The ray-cast LiDAR: analytic ranges, beam pattern sizes, ground-truth object tags, seeded
noise and dropout, empty scenes."""

from __future__ import annotations

import math

import numpy as np
import pytest
from lidar_scenes import box, car, flat_pattern, sensor_pose, snapshot

from cadsim.sensing.lidar.beam_pattern import PRESETS, LidarConfig
from cadsim.sensing.lidar.raycast import RANGE_STEP_M, scan


def _scan(snap, pattern, seed=0, **kw):
    return scan(snap, sensor_pose(), pattern, np.random.default_rng(seed), **kw)


def test_a_level_ray_hits_a_planted_box_at_the_analytic_range():
    # box faces at x = 9 (front) spanning y in [-1, 1], z in [0, 2]; sensor at height 1.8 sees it
    s = _scan(snapshot(box("b", 10.0, 0.0)), flat_pattern(3600, elevations=(-1.0, 0.0)))
    az = s.ray_index % 3600
    level = s.channel == 1
    ahead = level & (az == 0)
    assert s.range_m[ahead].tolist() == [9.0]
    assert s.point_object_ids()[int(np.flatnonzero(ahead)[0])] == "b"
    # off-axis rays on the front face: r = 9 / cos(azimuth), to the 4 mm grid
    side = level & (az > 0) & (az < 30)
    expect = 9.0 / np.cos(np.radians(az[side] * 0.1))
    assert np.abs(s.range_m[side] - expect).max() <= RANGE_STEP_M / 2 + 1e-12
    # the face stops at y = ±1: atan(1 / 9) = 6.34°, so azimuth 63 hits and 64 misses the front
    assert 63 in az[level] and 64 not in az[level & (s.range_m < 9.2)]
    # the tilted channel reaches the ground behind nothing: r = 1.83 / sin(1°) ≈ 104.9 m at the back
    back = (s.channel == 0) & (az == 1800)
    assert abs(s.range_m[back][0] - (1.8 + 0.03) / math.sin(math.radians(1.0))) < 0.01


def test_the_points_are_range_times_direction_in_the_sensor_frame():
    s = _scan(snapshot(box("b", 0.0, 12.0)), flat_pattern(360))
    hit = np.asarray(s.point_object_ids()) == "b"
    pts = s.points[hit]
    # the box lies to the left (+y) of the sensor: its near face at y = 11
    assert np.allclose(pts[:, 1].min(), 11.0, atol=RANGE_STEP_M)
    assert np.allclose(pts[:, 2], 0.0)
    assert np.allclose(np.linalg.norm(pts, axis=1), s.range_m[hit])


@pytest.mark.parametrize(("name", "channels", "lo", "hi", "mount"), [
    ("hdl-32e", 32, -30.67, 10.67, "roof"),
    ("hdl-64e", 64, -24.8, 2.0, "roof"),
    ("pandar128", 128, -25.0, 15.0, "roadside"),
])  # fmt: skip
def test_presets_have_their_data_sheets_channels_and_fields_of_view(name, channels, lo, hi, mount):
    p = PRESETS[name]
    assert p.channels == channels and p.mount == mount
    assert p.elevations_deg[0] == pytest.approx(lo) and p.elevations_deg[-1] == pytest.approx(hi)
    assert len(set(p.elevations_deg)) == channels
    d = p.directions()
    assert d.shape == (channels * p.azimuth_steps, 3)
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0)
    assert np.allclose(np.degrees(np.arcsin(d[:: p.azimuth_steps, 2])), p.elevations_deg)


def test_a_sweep_fires_channels_times_azimuths_rays():
    # a closed room: every ray returns, so the count is exactly the pattern's
    cfg = LidarConfig(channels=16, vertical_fov_deg=[-15.0, 15.0], horizontal_resolution_deg=1.0,
                      dropout=0.0, range_noise_m=0.0, max_range_m=50.0)  # fmt: skip
    p = cfg.pattern()
    assert (p.channels, p.azimuth_steps, p.ray_count) == (16, 360, 5760)
    walls = [box(f"w{i}", 20.0 * c, 20.0 * s, (2.0, 60.0, 40.0), yaw=math.atan2(s, c))
             for i, (c, s) in enumerate([(1, 0), (0, 1), (-1, 0), (0, -1)])]  # fmt: skip
    s = _scan(snapshot(*walls), p)
    assert len(s) == p.ray_count
    assert np.array_equal(s.ray_index, np.arange(p.ray_count))


def test_the_lidar_table_names_its_errors():
    with pytest.raises(ValueError, match=r"x.toml \[lidar\]: unknown key\(s\) chanels .*channels"):
        LidarConfig.from_table({"chanels": 3}, "x.toml [lidar]")
    with pytest.raises(
        ValueError, match=r"\[lidar\] preset must be one of hdl-32e, hdl-64e, pandar128"
    ):
        LidarConfig.from_table({"preset": "vlp-16"}, "x.toml [lidar]")
    with pytest.raises(ValueError, match="channels and vertical_fov_deg go together"):
        LidarConfig.from_table({"channels": 8}, "x.toml [lidar]")
    with pytest.raises(ValueError, match="dropout must be <= 1"):
        LidarConfig.from_table({"dropout": 2.0}, "x.toml [lidar]")
    with pytest.raises(ValueError, match="min_range_m must be below max_range_m"):
        LidarConfig.from_table({"min_range_m": 50.0, "max_range_m": 10.0}, "x.toml [lidar]")


def test_each_point_carries_the_id_of_the_object_it_hit():
    # a car ahead, a box to the left; the carrier is excluded and never hit
    snap = snapshot(
        car("ego", 0.0, 0.0), car("c1", 15.0, 0.0), box("b2", 0.0, 10.0, (1.0, 3.0, 2.0))
    )
    s = _scan(snap, PRESETS["hdl-64e"], exclude_ids={"ego"})
    ids = np.asarray(s.point_object_ids())
    assert set(ids) == {"", "c1", "b2"}
    pts = s.points
    c1, b2 = pts[ids == "c1"], pts[ids == "b2"]
    assert len(c1) > 100 and len(b2) > 100
    tol = 0.1  # 5 σ of range noise
    assert (c1[:, 0] > 15.0 - 2.25 - tol).all() and (np.abs(c1[:, 1]) < 0.9 + tol).all()
    assert (b2[:, 1] > 10.0 - 1.5 - tol).all() and (np.abs(b2[:, 0]) < 0.5 + tol).all()
    ground = pts[ids == ""]
    assert np.allclose(ground[:, 2], -1.83, atol=tol)


def test_one_seed_one_sweep_and_another_seed_another():
    snap = snapshot(car("c1", 12.0, 3.0, 0.4), box("b", -8.0, -6.0))
    a, b = (_scan(snap, PRESETS["hdl-32e"], seed=7) for _ in range(2))
    c = _scan(snap, PRESETS["hdl-32e"], seed=8)
    for f in ("ray_index", "range_steps", "object_index"):
        assert getattr(a, f).tobytes() == getattr(b, f).tobytes()
    assert not np.array_equal(a.ray_index, c.ray_index)
    # dropout ≈ 5 % of the hits, noise ≈ 2 cm: seeds differ in draws, not in scale
    assert abs(len(a) - len(c)) < 0.02 * len(a)


def test_all_dropout_and_empty_scenes_give_empty_or_ground_only_sweeps():
    p = flat_pattern(720, elevations=(-10.0, 0.0), dropout=1.0)
    s = _scan(snapshot(car("c1", 10.0, 0.0)), p)
    assert len(s) == 0 and s.points.shape == (0, 3) and s.point_object_ids() == []
    empty = _scan(snapshot(), flat_pattern(720, elevations=(-10.0, 0.0)))
    assert set(empty.point_object_ids()) == {""} and (empty.channel == 0).all()
    assert len(empty) == 720
    sky = _scan(snapshot(), flat_pattern(720, elevations=(5.0,)))
    assert len(sky) == 0
