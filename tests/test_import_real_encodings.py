"""The field's files as they are really encoded, on the project's own fixtures: V2V4Real's
numpy-tagged yaml and ``ass_id`` links, DAIR-V2X-C's path-only index and unlinked labels, OPV2V
agents listed by other agents, V2XSet's per-agent prior, V2X-Seq-SPD's tokens, untracked
objects and both ``system_error_offset`` conventions, non-orthonormal calibration rotations."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml
from format_fixtures import (
    INFRA_LIDAR,
    OFFSET,
    WORLD,
    vehicle_lidar,
    write_dair_v2x,
    write_opv2v,
    write_v2v4real,
    write_v2x_seq,
)

from cadsim.cli import main
from cadsim.dataset import Dataset
from cadsim.importers import ImportFormatError
from cadsim.importers.dair_v2x import import_dair_v2x, linked_pairs
from cadsim.importers.opv2v import import_opv2v
from cadsim.importers.safe_read import read_yaml, rigid
from cadsim.importers.v2x_seq import import_v2x_seq


def _gt_ids(pair) -> set[str]:
    return {pair.view1.object_ids[i] for i, _ in pair.gt_pairs}


def _aligned(pair) -> float:
    t = pair.true_relative_pose()
    gt = pair.gt_pairs
    moved = pair.view2.positions[gt[:, 1]] @ t[:3, :3].T + t[:3, 3]
    return float(np.abs(moved - pair.view1.positions[gt[:, 0]]).max())


# --- V2V4Real ---------------------------------------------------------------------------


@pytest.mark.parametrize("numpy_major", [1, 2])
def test_numpy_tags_are_rebuilt_as_plain_numbers(tmp_path, numpy_major):
    write_v2v4real(tmp_path / "src", numpy_major)
    path = next((tmp_path / "src").rglob("000000.yaml"))
    text = path.read_text()
    assert ("numpy.core.multiarray.scalar" in text) == (numpy_major == 1)
    assert "!!binary" in text and "&id001" in text  # payloads and a shared (aliased) dtype
    data = read_yaml(path, numpy_tags=True)
    assert data["gps"] == [39.9, -83.0, 228.5, 2.3, 0.1, 0.0]
    assert all(type(v) is float for v in data["gps"])
    assert np.array(data["lidar_pose"]).shape == (4, 4) and data["lidar_pose"][3] == [0, 0, 0, 1]


def test_v2v4real_links_by_ass_id_and_never_links_minus_one(tmp_path):
    src = write_v2v4real(tmp_path / "src")
    ds = Dataset(import_opv2v(src, tmp_path / "out", v2v4real=True).out, verify=True)
    assert len(ds) == 3
    for pair, boxes in zip(ds.sequence(0), WORLD, strict=True):
        # "a", "b": ass_id 7, 8 under different local keys; "c": key 5 on both, ass_id -1
        assert _gt_ids(pair) == {"a7", "a8"}
        assert "0:5" in pair.view1.object_ids and "1:5" in pair.view2.object_ids
        assert ("0:6" in pair.view1.object_ids) == ("d" in boxes)
        assert _aligned(pair) < 1e-6  # the right-handed poses as the file gives them


def test_v2v4real_poses_are_read_as_given(tmp_path):
    """The 4×4 ``lidar_pose`` is LiDAR → a right-handed world, used as is: a box's position in
    the view is the world box moved by the pose's inverse."""
    src = write_v2v4real(tmp_path / "src")
    pair = Dataset(import_opv2v(src, tmp_path / "out", v2v4real=True).out)[0]
    sensor = np.eye(4)
    sensor[:3, :3] = [[np.cos(0.1), -np.sin(0.1), 0], [np.sin(0.1), np.cos(0.1), 0], [0, 0, 1]]
    sensor[:3, 3] = (0.0, 0.0, 1.9)
    x, y, z = WORLD[0]["a"][:3]
    local = np.linalg.inv(sensor) @ [x, y, z, 1.0]  # LiDAR frame: x forward, y left, z up
    k = pair.view1.object_ids.index("a7")
    # camera convention of box views: x right (= −y), y down (= −z), z forward (= x)
    np.testing.assert_allclose(pair.view1.positions[k], [-local[1], -local[2], local[0]], atol=1e-9)


def test_cli_imports_v2v4real_and_refuses_any_other_python_tag(tmp_path, capsys):
    src = write_v2v4real(tmp_path / "src")
    assert main(["import", "v2v4real", str(src), "--out", str(tmp_path / "out")]) == 0
    assert "3 frame pairs" in capsys.readouterr().out
    path = next(src.rglob("000001.yaml"))
    path.write_text(path.read_text() + "plan: !!python/object/apply:os.system ['touch pwned']\n")
    assert main(["import", "v2v4real", str(src), "--out", str(tmp_path / "out2")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "refused tag !!python/object/apply:os.system" in lines[0]
    assert str(path) in lines[0] and not (tmp_path / "out2").exists()
    assert not (tmp_path / "pwned").exists()


# --- OPV2V / V2XSet ---------------------------------------------------------------------


def _edit_yaml(path, edit) -> None:
    data = yaml.safe_load(path.read_text())
    edit(data)
    path.write_text(yaml.safe_dump(data))


def test_a_connected_vehicle_listed_by_another_keeps_its_class_and_size(tmp_path):
    """Agent 3 lists agent 7 in its ``vehicles`` (as 4288 lists 4279 in OpenCDA's
    dummy_v2xset): 7 is an ordinary object there, with the box 3 gives it, never the 0.1 m
    agent marker; and ``center`` is added to ``location`` in world axes, as OpenCOOD does."""
    src = write_opv2v(tmp_path / "split", agents=(7, 3))
    for path in sorted((src / "2021_08_22_21_41_24" / "3").glob("*.yaml")):
        _edit_yaml(path, lambda d: d["vehicles"].update({7: {
            "angle": [0.0, 90.0, 0.0], "center": [0.5, 0.0, 0.7], "extent": [2.4, 1.0, 0.75],
            "location": [0.0, 0.0, 0.0], "speed": 0.0, "obj_type": "Truck"}}))  # fmt: skip
    ds = Dataset(import_opv2v(src, tmp_path / "out", prior=False).out, verify=True)
    pair = ds[0]
    objects = {o["id"]: o for o in pair.record["objects"]}
    assert objects["7"]["cls"] == "truck" and objects["7"]["target"]
    assert objects["7"]["size"] == pytest.approx([4.8, 2.0, 1.5])
    # centre: location + center in CARLA axes (y negated into ours), not rotated by the yaw
    assert objects["7"]["center"] == pytest.approx([0.5, 0.0, 0.7])
    assert objects["3"]["cls"] == "agent"  # the other agent, listed by nobody, stays a marker


def test_v2xset_prior_is_per_agent(tmp_path, capsys):
    src = write_opv2v(tmp_path / "split")
    for path in (src / "2021_08_22_21_41_24" / "-1").glob("*.yaml"):
        _edit_yaml(path, lambda d: d.pop("predicted_ego_pos"))
    result = import_opv2v(src, tmp_path / "out")
    ds = Dataset(result.out, verify=True)
    snap = ds.snapshot(0)
    assert snap.pair(1, 2).prior() is not None  # the two vehicles keep theirs
    assert snap.pair(1, 3).prior() is None and snap.pair(2, 3).prior() is None
    assert ds.manifest["source"]["agents_without_prior"] == ["2021_08_22_21_41_24/-1"]
    assert main(["info", str(result.out)]) == 0
    assert "no stored prior for     2021_08_22_21_41_24/-1" in capsys.readouterr().out


# --- V2X-Seq-SPD ------------------------------------------------------------------------


def test_v2x_seq_links_by_token_and_refuses_a_track_mismatch(tmp_path, capsys):
    src = write_v2x_seq(tmp_path / "spd")
    path = src / "cooperative/label/000010.json"
    labels = json.loads(path.read_text())
    for label in labels:  # the track ids alone would link nothing now: tokens must
        label["veh_track_id"] = label["inf_track_id"] = "-1" if label["veh_token"] else "-1"
    path.write_text(json.dumps(labels))
    pair = Dataset(import_v2x_seq(src, tmp_path / "out").out)[0]
    assert len(pair.gt_pairs) == 3  # a, b, c by token
    labels[0]["veh_track_id"] = "000999"  # a token whose track id disagrees with the side label
    path.write_text(json.dumps(labels))
    assert main(["import", "v2x-seq", str(src), "--out", str(tmp_path / "out2")]) == 2
    line = capsys.readouterr().err.strip()
    assert "000010.json" in line and "frame '000010'" in line and "'000999'" in line


def test_objects_without_track_ids_are_kept_and_counted(tmp_path):
    src = write_v2x_seq(tmp_path / "spd")
    path = src / "vehicle-side/label/lidar/000011.json"
    labels = json.loads(path.read_text())
    cones = [dict(labels[0], type="TrafficCone", token=f"cone{k}") for k in range(2)]
    for k, cone in enumerate(cones):
        cone.pop("track_id")
        cone["3d_location"] = {"x": 5.0 + k, "y": 2.0, "z": -1.5}
    path.write_text(json.dumps(labels + cones))
    result = import_v2x_seq(src, tmp_path / "out")
    ds = Dataset(result.out, verify=True)
    pair = ds.sequence(0)[1]
    assert sum(i.startswith("vuntracked:") for i in pair.view1.object_ids) == 2
    assert pair.record["meta"]["untracked_objects"] == 2
    assert ds.manifest["source"]["untracked_objects"] == 2


@pytest.mark.parametrize("convention", ["roadside", "vehicle"])
def test_both_offset_conventions_give_the_documented_pose(tmp_path, convention):
    """roadside: T_world←inf = published + δ (world axes); vehicle: T_veh←inf = published
    relative pose + δ in the vehicle LiDAR's axes."""
    src = write_v2x_seq(tmp_path / "spd")
    ds = Dataset(import_v2x_seq(src, tmp_path / "out", offset_convention=convention).out)
    published = INFRA_LIDAR[:3, 3] - [*OFFSET, 0.0]
    delta = np.array([*OFFSET, 0.0])
    for k, pair in enumerate(ds.sequence(0)):
        rotation = vehicle_lidar(k)[:3, :3]
        expected = published + (delta if convention == "roadside" else rotation @ delta)
        np.testing.assert_allclose(pair.cameras[1].position, expected, atol=1e-9)
    assert ds.manifest["source"]["offset_convention"] == convention


# --- DAIR-V2X-C -------------------------------------------------------------------------


def test_dair_v2x_links_follow_the_cooperative_boxes(tmp_path):
    src = write_dair_v2x(tmp_path / "dair")
    ds = Dataset(import_dair_v2x(src, tmp_path / "out").out, verify=True)
    assert len(ds) == 3 and sorted(ds.manifest["seeds"]["episodes"]) == ["3", "4"]
    for pair in ds:
        # "a": one fused box; "b": within the gate, but the fused label does not join them;
        # "c": a pedestrian, a class the cooperative label lacks, linked side to side
        classes = sorted(pair.view1.true_classes[i] for i, _ in pair.gt_pairs)
        assert classes == ["car", "pedestrian"]
        assert _aligned(pair) < 1e-6
        assert pair.observer_kinds == ("vehicle", "roadside") and pair.prior() is None
        assert pair.record["meta"]["time_offset_s"] == pytest.approx(0.03)


def test_dair_v2x_without_cooperative_boxes_links_the_sides_directly(tmp_path):
    src = write_dair_v2x(tmp_path / "dair", cooperative=False)
    ds = Dataset(import_dair_v2x(src, tmp_path / "out").out)
    for pair in ds:
        assert len(pair.gt_pairs) == 3  # a, b (0.6 m apart), c
    narrow = Dataset(import_dair_v2x(src, tmp_path / "narrow", link_gate_m=0.5).out)
    assert all(len(p.gt_pairs) == 2 for p in narrow)  # b is beyond a 0.5 m gate


def test_dair_v2x_lidar_i2v_alone_places_the_roadside_and_is_polar_decomposed(tmp_path):
    src = write_dair_v2x(tmp_path / "dair", cooperative=False, world=False, i2v=True, skew=2e-3)
    ds = Dataset(import_dair_v2x(src, tmp_path / "out").out, verify=True)
    for k, pair in enumerate(ds):  # the world is the vehicle LiDAR's frame
        t, gt = pair.true_relative_pose(), pair.gt_pairs
        moved = pair.view2.positions[gt[:, 1]] @ t[:3, :3].T + t[:3, 3]
        gaps = np.sort(np.linalg.norm(moved - pair.view1.positions[gt[:, 0]], axis=1))
        # "a", "c" exact (a 1.002-scaled rotation would move them by centimetres); "b" 0.6 m off
        np.testing.assert_allclose(gaps, [0.0, 0.0, 0.6], atol=1e-6)
        expected = (np.linalg.inv(vehicle_lidar(k)) @ INFRA_LIDAR)[:3, 3]
        np.testing.assert_allclose(pair.cameras[0].position, [0.0, 0.0, 0.0], atol=1e-12)
        np.testing.assert_allclose(pair.cameras[1].position, expected, atol=1e-9)


def test_linked_pairs_is_one_to_one_same_class_and_gated():
    a = np.array([[0.0, 0.0], [1.2, 0.0], [5.0, 5.0]])
    b = np.array([[0.2, 0.0], [1.0, 0.0], [5.0, 5.5]])
    assert linked_pairs(a, ["cone", "cone", "car"], b, ["cone", "cone", "bus"], 1.0) == [
        (0, 0),
        (1, 1),
    ]
    assert linked_pairs(a, ["car"] * 3, b[:1], ["car"], 1.0) == [(0, 0)]


# --- calibration rotations --------------------------------------------------------------


def test_near_orthonormal_rotations_are_polar_decomposed_and_far_ones_refused(tmp_path):
    r = np.array([[np.cos(0.3), -np.sin(0.3), 0.0], [np.sin(0.3), np.cos(0.3), 0.0], [0, 0, 1]])
    skewed = r + 4e-3 * np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    out = rigid(skewed.tolist(), [1.0, 2.0, 3.0], tmp_path / "c.json", "")
    np.testing.assert_allclose(out[:3, :3] @ out[:3, :3].T, np.eye(3), atol=1e-12)
    assert np.abs(out[:3, :3] - r).max() < 4e-3
    with pytest.raises(ImportFormatError, match="not a rotation matrix"):
        rigid((2.0 * r).tolist(), [0.0, 0.0, 0.0], tmp_path / "c.json", "")


# --- the temporal table on imported data ------------------------------------------------


def test_temporal_methods_run_on_an_imported_v2x_seq_split(tmp_path):
    """An imported V2X-Seq split loads as the temporal table loads its splits, and every
    temporal method of the table runs on it and assigns the covisible objects."""
    from eval.studies.temporal.evaluation import METHODS, load_split, run_method

    out = import_v2x_seq(write_v2x_seq(tmp_path / "spd"), tmp_path / "out").out
    [(seed, item)] = load_split(out, "gnss-urban", (0,))
    assert len(item.seq.frames) == 3
    for method, windows in METHODS:
        frames, _ = run_method(method, windows[-1], item, seed, "gnss-urban")
        assert len(frames) == 3 and all(len(assigned) >= 1 for assigned, _ in frames), method
