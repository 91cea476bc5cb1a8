"""LiDAR scenarios end to end: the ``sensor`` key and ``[lidar]`` table, records that carry the
points (bounded) and the boxes, box-only matching problems, ``cadsim show`` from above."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from cadsim.cli import main
from cadsim.dataset import Dataset, layout
from cadsim.dataset.lidar_points import MAX_POINTS_PER_VIEW, bounded, check_lidar_arrays
from cadsim.dataset.manifest import DatasetError
from cadsim.scenario import ScenarioError, load_scenario
from cadsim.sensing.box_features import BOX_CUES, BOX_FEATURE_DIM
from cadsim.sensing.lidar.beam_pattern import PRESETS
from cadsim.sensing.lidar.raycast import LidarScan

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
LIDAR = SCENARIOS / "cad-v2x-lidar.toml"
RECORD_BYTES_CAP = 1_500_000  # a two-view LiDAR record: two 64-channel sweeps + boxes


def _scenario(tmp_path: Path, text: str, name: str = "s.toml") -> Path:
    shutil.copy(SCENARIOS / "cad-vtypes.add.xml", tmp_path / "cad-vtypes.add.xml")
    path = tmp_path / name
    path.write_text(text)
    return path


def test_the_lidar_scenario_loads_with_its_sensor_and_table():
    s = load_scenario(LIDAR)
    assert s.sensor == "lidar" and s.lidar["preset"] == "hdl-64e"
    assert load_scenario(SCENARIOS / "cad-v2x.toml").sensor == "camera"


@pytest.mark.parametrize(("edit", "message"), [
    (('sensor = "lidar"', 'sensor = "radar"'), r"sensor.*radar.*camera.*lidar.*both"),
    (('sensor = "lidar"', 'sensor = "camera"'), r'lidar: is given but sensor is "camera"'),
    (('preset = "hdl-64e"', 'preset = "hdl-16"'), r"lidar.preset.*must be one of hdl-32e, hdl-64e, pandar128"),
    (('dropout = 0.05 ', 'dropuot = 0.05 '), r"lidar.dropuot"),
    (('dropout = 0.05 ', 'dropout = 1.5 '), r"lidar.dropout.*<= 1"),
])  # fmt: skip
def test_bad_sensor_settings_are_one_line_errors_naming_file_and_key(tmp_path, edit, message):
    text = LIDAR.read_text()
    assert edit[0] in text
    path = _scenario(tmp_path, text.replace(edit[0], edit[1], 1))
    with pytest.raises(ScenarioError, match=message) as err:
        load_scenario(path)
    assert str(path) in str(err.value) and "\n" not in str(err.value)


def test_a_sweep_beyond_the_cap_keeps_every_kth_return():
    n = MAX_POINTS_PER_VIEW * 2 + 5
    pattern = PRESETS["pandar128"]
    scan = LidarScan(
        pattern, np.arange(n), np.full(n, 100, np.uint16), np.full(n, -1, np.int32), ()
    )
    kept = bounded(scan)
    assert len(kept) <= MAX_POINTS_PER_VIEW and np.array_equal(kept.ray_index, np.arange(0, n, 3))


@pytest.fixture(scope="module")
def lidar_dataset(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("lidar") / "ds"
    args = ["generate", str(LIDAR), "--out", str(out), "--pairs", "2", "--workers", "1"]
    assert main([*args, "--no-progress"]) == 0
    return out


def test_lidar_records_carry_boxes_and_bounded_points(lidar_dataset):
    ds = Dataset(lidar_dataset, verify=True)
    assert ds.manifest["record_files"] == [
        layout.DETECTIONS_NPZ,
        layout.RECORD_JSON,
        layout.LIDAR_NPZ,
    ]
    for pair in ds:
        size = sum(f.stat().st_size for f in pair.path.iterdir())
        assert size < RECORD_BYTES_CAP
        assert pair.cues == BOX_CUES and not pair.has_images
        problem = pair.problem()
        assert problem.pixels1 is None and problem.features1.shape[1] == BOX_FEATURE_DIM
        assert pair.view1.headings is not None and pair.view1.reported_classes
        assert len(pair.gt_pairs) >= 3
        objects = pair.objects
        for view, sweep, observer in zip((pair.view1, pair.view2), pair.lidar, pair.observer_ids, strict=True):  # fmt: skip
            assert 10_000 < len(sweep.points) <= MAX_POINTS_PER_VIEW
            hit = {objects[i].id for i in np.unique(sweep.object_index) if i >= 0}
            assert observer not in hit  # the carrier is not drawn
            # every box that is an object was hit by that object's points
            assert {i for i in view.object_ids if not i.startswith("clutter:")} <= hit
            # the sensor pose is on the carrier's roof
            carrier = next(o for o in objects if o.id == observer)
            assert np.allclose(sweep.pose[:2, 3], carrier.center[:2])
            assert sweep.pose[2, 3] == pytest.approx(carrier.center[2] + carrier.size[2] / 2 + 0.25)


def test_a_damaged_points_file_is_a_one_line_error(lidar_dataset):
    from cadsim.dataset.encoding import load_npz

    pair = Dataset(lidar_dataset)[0]
    objects = len(pair.objects)
    arrays = load_npz(str(pair.path / layout.LIDAR_NPZ), "x")
    check_lidar_arrays(arrays, 2, objects, "x")
    arrays["view1_range"] = arrays["view1_range"].astype(np.int32)
    with pytest.raises(ValueError, match=r"^x: view1_range: expected \(\d+,\) uint16$"):
        check_lidar_arrays(arrays, 2, objects, "x")
    arrays = load_npz(str(pair.path / layout.LIDAR_NPZ), "x")
    arrays["view2_object"][:1] = objects
    with pytest.raises(ValueError, match=rf"^x: view2_object: index outside -1\.\.{objects - 1}$"):
        check_lidar_arrays(arrays, 2, objects, "x")
    arrays = load_npz(str(pair.path / layout.LIDAR_NPZ), "x")
    arrays["view1_stray"] = np.zeros(3)
    with pytest.raises(ValueError, match=r"^x: view1_stray: not an array of a 2-view lidar.npz$"):
        check_lidar_arrays(arrays, 2, objects, "x")
    # through the dataset: the record's verification names the file
    damaged = pair.path / layout.LIDAR_NPZ
    from cadsim.dataset.encoding import npz_bytes

    original = damaged.read_bytes()
    try:
        arrays = load_npz(original, "x")
        arrays["view1_hits"] = arrays["view1_hits"][:-1]
        damaged.write_bytes(npz_bytes(arrays))
        with pytest.raises(DatasetError):
            Dataset(lidar_dataset).verify_record(0)
    finally:
        damaged.write_bytes(original)


def test_show_draws_the_points_from_above(lidar_dataset, tmp_path, capsys):
    out = tmp_path / "fig.png"
    assert main(["show", str(lidar_dataset), "--pair", "0", "--out", str(out)]) == 0
    assert out.stat().st_size > 20_000


@pytest.mark.render
def test_both_sensors_keep_camera_detections_and_add_the_points(tmp_path):
    text = LIDAR.read_text().replace('sensor = "lidar"', 'sensor = "both"', 1)
    path = _scenario(tmp_path, text)
    out = tmp_path / "both"
    assert main(["generate", str(path), "--out", str(out), "--pairs", "1", "--workers", "1", "--no-progress"]) == 0  # fmt: skip
    ds = Dataset(out, verify=True)
    pair = ds[0]
    assert pair.has_images and pair.cues != BOX_CUES
    assert layout.LIDAR_NPZ in ds.manifest["record_files"]
    boxes = pair.lidar[0].boxes
    assert boxes is not None and len(boxes["ids"]) == len(boxes["classes"]) > 0
    assert main(["show", str(out), "--pair", "0", "--lidar", "--out", str(tmp_path / "f.png")]) == 0


def test_the_opv2v_export_writes_each_sweep_as_a_pcd_in_carla_axes(lidar_dataset, tmp_path):
    from cadsim.exporters.pcd import read_pcd

    out = tmp_path / "opv2v"
    assert main(["export", "opv2v", str(lidar_dataset), "--out", str(out)]) == 0
    pair = Dataset(lidar_dataset)[0]
    clouds = sorted((out / pair.name).glob("*/000000.pcd"))
    assert len(clouds) == 2
    counts = sorted(len(read_pcd(c.read_bytes())[0]) for c in clouds)
    assert counts == sorted(len(s.points) for s in pair.lidar)
    for cloud in clouds:
        pts, _ = read_pcd(cloud.read_bytes())
        sweep = next(s for s in pair.lidar if len(s.points) == len(pts))
        assert np.allclose(pts, sweep.points * [1.0, -1.0, 1.0], atol=1e-4)
    # the export still imports (the point clouds are extra files of the layout)
    assert main(["import", "opv2v", str(out), "--out", str(tmp_path / "back")]) == 0


def test_the_regime_card_reports_recall_by_range_and_centre_error(lidar_dataset):
    from cadsim.dataset.lidar_regime import RANGE_BANDS_M, card_lines, lidar_detector_card

    card = lidar_detector_card(Dataset(lidar_dataset))
    assert [e["band_m"] for e in card["recall"]] == [list(b) for b in RANGE_BANDS_M]
    near = card["recall"][0]
    assert near["objects"] > 0 and 0.0 <= near["recall"] <= 1.0
    for everything, hit in zip(card["recall"], card["recall_hit"], strict=True):
        assert hit["objects"] <= everything["objects"]
    err = card["centre_error_m"]
    assert err["boxes"] > 0 and err["median"] < 0.5  # completed boxes: centres within half a metre
    assert 0.0 <= card["false_positive_share"] < 1.0
    # every false positive is attributed to a source; the shares add up to the whole
    sources = card["false_positive_sources"]
    assert sum(sources.values()) == pytest.approx(card["false_positive_share"])
    assert "other" not in sources and list(sources.values()) == sorted(
        sources.values(), reverse=True
    )
    assert len(card_lines(card)) == 4
    # camera datasets have no card
    assert lidar_detector_card([]) is None


def _record_bytes(folder: Path) -> dict[str, bytes]:
    root = folder / "pairs"
    return {
        str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()
    }


def test_both_sensors_sweep_only_accepted_pairs_and_write_the_same_records(tmp_path, monkeypatch):
    """With both sensors a pair is accepted by its camera detections, so the LiDAR sweeps only
    the accepted pairs' views (two per record), and the records are byte for byte those of
    sweeping every candidate at capture time (each view's LiDAR draws on its own seed)."""
    from cadsim.generation import pipeline

    path = _scenario(tmp_path, (SCENARIOS / "cad-v2x-both.toml").read_text())
    sweeps = []
    observe = pipeline._lidar_observation
    monkeypatch.setattr(
        pipeline, "_lidar_observation", lambda *a: sweeps.append(a[-1]) or observe(*a)
    )

    def generate(out: Path) -> int:
        sweeps.clear()
        args = ["generate", str(path), "--out", str(out), "--pairs", "3", "--workers", "1"]
        assert main([*args, "--no-progress"]) == 0
        return len(sweeps)

    deferred = generate(tmp_path / "deferred")
    summaries = [
        json.loads(p.read_text())
        for p in (tmp_path / "deferred" / layout.EPISODES_DIR).glob("*.json")
    ]
    assert deferred == 2 * 3 == 2 * sum(s["accepted"] for s in summaries)
    capture = pipeline._capture
    monkeypatch.setattr(pipeline, "_capture", lambda *a, **k: capture(*a, **{**k, "lidar_now": True}))  # fmt: skip
    monkeypatch.setattr(pipeline, "_with_lidar", lambda task, snapshot, views, slot, result: views)
    at_capture = generate(tmp_path / "at-capture")
    assert at_capture > deferred
    assert sum(s["candidates"] for s in summaries) > 3  # a candidate was refused: a sweep saved
    assert _record_bytes(tmp_path / "deferred") == _record_bytes(tmp_path / "at-capture")


def test_a_two_sensor_split_takes_its_frames_from_the_camera_split_of_the_same_frames(tmp_path):
    """``--frames-from``: the episodes a camera-only dataset of the same settings and seed holds
    take their camera captures from it (no simulation, no rendering: two sweeps per record),
    the others are simulated; the records and checksum are those of a full generation. A camera
    dataset generated otherwise (another seed) is not used."""
    both = _scenario(tmp_path, (SCENARIOS / "cad-v2x-both.toml").read_text())
    camera = _scenario(tmp_path, (SCENARIOS / "cad-v2x.toml").read_text(), "camera.toml")

    def generate(path: Path, out: str, pairs: int, *extra: str) -> Path:
        args = ["generate", str(path), "--out", str(tmp_path / out), "--pairs", str(pairs)]
        assert main([*args, "--workers", "1", "--no-progress", *extra]) == 0
        return tmp_path / out

    full = generate(both, "full", 3)
    frames = generate(camera, "frames", 2)
    derived = generate(both, "derived", 3, "--frames-from", str(frames))
    assert _record_bytes(derived) == _record_bytes(full)
    assert Dataset(derived, verify=True).checksum == Dataset(full, verify=True).checksum
    summaries = sorted(
        (json.loads(p.read_text()) for p in (derived / layout.EPISODES_DIR).glob("*.json")),
        key=lambda s: s["episode"],
    )
    taken = [s for s in summaries if s["candidates"] == 0]  # no candidate tried: from the frames
    assert [s["episode"] for s in taken] == [0, 1] and all(s["views"] == 2 for s in taken)
    assert summaries[-1]["candidates"] >= 1  # the episode the frames lack was simulated

    other = generate(camera, "other-seed", 1, "--seed", "5")
    elsewhere = generate(both, "elsewhere", 1, "--frames-from", str(other))
    summary = json.loads((elsewhere / layout.EPISODES_DIR / "e00000.json").read_text())
    assert summary["candidates"] >= 1 and _record_bytes(elsewhere) == {
        k: v for k, v in _record_bytes(full).items() if k.startswith("e00000_")
    }


def test_a_tampered_frames_dataset_is_a_one_line_error_before_anything_is_written(tmp_path, capsys):
    """``--frames-from`` copies the frames' records, so the command verifies them first: a
    record changed after generation stops it with one line, and the output is not created."""
    both = _scenario(tmp_path, (SCENARIOS / "cad-v2x-both.toml").read_text())
    camera = _scenario(tmp_path, (SCENARIOS / "cad-v2x.toml").read_text(), "camera.toml")
    frames = tmp_path / "frames"
    args = ["--pairs", "1", "--workers", "1", "--no-progress"]
    assert main(["generate", str(camera), "--out", str(frames), *args]) == 0
    record = next((frames / layout.PAIRS_DIR).iterdir()) / layout.RECORD_JSON
    record.write_text(record.read_text().replace('"time"', '"time" ', 1))
    capsys.readouterr()
    out = tmp_path / "derived"
    code = main(["generate", str(both), "--out", str(out), "--frames-from", str(frames), *args])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "cadsim generate: error:" in err
    assert not out.exists()
