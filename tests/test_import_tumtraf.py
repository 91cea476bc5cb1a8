"""``cadsim import tumtraf-v2x``: OpenLABEL files written from the published schema import as
box-only frame pairs whose links are the uids both sides share and whose true relative pose is
the files' transform; malformed files are refused in one line naming the file and key, and
nothing is written."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from format_fixtures import INFRA_SEES, VEHICLE_SEES, WORLD
from test_import_formats_hostile import _refused
from tumtraf_fixtures import write_tumtraf

from cadsim.cli import main
from cadsim.dataset import Dataset


def _imported(tmp_path: Path, **kwargs) -> Dataset:
    src = write_tumtraf(tmp_path / "src", **kwargs)
    assert main(["import", "tumtraf-v2x", str(src), "--out", str(tmp_path / "d")]) == 0
    return Dataset(tmp_path / "d", verify=True)


def _aligned(pair) -> None:
    """View 2's linked boxes, moved by the true relative pose, lie on view 1's."""
    pose = pair.true_relative_pose()
    gt = pair.gt_pairs
    moved = pair.view2.positions[gt[:, 1]] @ pose[:3, :3].T + pose[:3, 3]
    np.testing.assert_allclose(moved, pair.view1.positions[gt[:, 0]], atol=1e-6)


def test_frames_import_with_the_shared_uids_as_links(tmp_path):
    data = _imported(tmp_path)
    assert len(data) == 3 and data.n_views == 2
    for k, pair in enumerate(data):
        shared = VEHICLE_SEES & INFRA_SEES & set(WORLD[k])
        linked = {pair.view1.object_ids[i] for i, _ in pair.gt_pairs}
        assert linked == {f"uuid-{o}" for o in shared}
        assert len(pair.view1.object_ids) == len(VEHICLE_SEES & set(WORLD[k]))
        assert len(pair.view2.object_ids) == len(INFRA_SEES & set(WORLD[k]))
        assert pair.observer_kinds == ("vehicle", "roadside")
        _aligned(pair)
    assert [round(p.time, 6) for p in data] == [0.0, 0.1, 0.2]  # from the file's first frame
    source = json.loads((tmp_path / "d" / "manifest.json").read_text())["source"]
    assert source["time"]["relative"] == 3 and source["linked_objects"] == 3 + 3 + 3


def test_the_coordinate_systems_give_the_transform_when_frames_do_not(tmp_path):
    data = _imported(tmp_path, transforms="systems", timestamps=False)
    pair = data[0]
    _aligned(pair)
    assert pair.time == 0.0
    frame_given = _imported(tmp_path / "again")[0]
    np.testing.assert_allclose(pair.true_relative_pose(), frame_given.true_relative_pose(), atol=1e-9)  # fmt: skip


def _edit(path: Path, edit) -> None:
    doc = json.loads(path.read_text())
    edit(doc["openlabel"])
    path.write_text(json.dumps(doc))


def _frame0(ol) -> dict:
    return ol["frames"]["0"]


def _cuboid(ol, uid="uuid-a", k=0) -> dict:
    return _frame0(ol)["objects"][uid]["object_data"]["cuboid"][k]


CASES = {
    "no openlabel": (lambda d: d.pop("frames"), "openlabel.frames: missing"),
    "short val": (lambda d: _cuboid(d).__setitem__("val", [1, 2, 3]), "cuboid[0].val: expected a list of 10 numbers"),
    "NaN val": (lambda d: _cuboid(d)["val"].__setitem__(0, float("nan")), "non-finite number NaN"),
    "huge val": (lambda d: _cuboid(d)["val"].__setitem__(1, 1e300), "cuboid[0].val[1]: expected a finite number"),
    "not a unit quaternion": (lambda d: _cuboid(d)["val"].__setitem__(6, 3.0), "not a unit quaternion"),
    "zero size": (lambda d: _cuboid(d)["val"].__setitem__(7, 0.0), "sizes must be in (0, 1000]"),
    "no coordinate system": (lambda d: _cuboid(d).pop("coordinate_system"), "cuboid[0].coordinate_system: missing"),
    "two cuboids one side": (
        lambda d: _frame0(d)["objects"]["uuid-a"]["object_data"]["cuboid"].append(_cuboid(d)),
        "a second cuboid of 'uuid-a'",
    ),
    "no type": (lambda d: _frame0(d)["objects"]["uuid-a"]["object_data"].pop("type"), "object_data.type: expected a name"),
    "no transform": (lambda d: (_frame0(d)["frame_properties"].pop("transforms"), d.pop("coordinate_systems")), "no transform between"),
    "bad matrix": (
        lambda d: next(iter(_frame0(d)["frame_properties"]["transforms"].values()))["transform_src_to_dst"].__setitem__("matrix4x4", [1] * 16),
        "last row must be 0 0 0 1",
    ),
    "not a rotation": (
        lambda d: next(iter(_frame0(d)["frame_properties"]["transforms"].values()))["transform_src_to_dst"].__setitem__("matrix4x4", [2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]),
        "not a rotation matrix",
    ),
    "parent loop": (
        lambda d: (_frame0(d)["frame_properties"].pop("transforms"),
                   d["coordinate_systems"]["s110_base"].update(
                       parent="s110_lidar_ouster_south",
                       pose_wrt_parent={"matrix4x4": np.eye(4).reshape(-1).tolist()})),
        "parents form a loop",
    ),
    "objects not a mapping": (lambda d: _frame0(d).__setitem__("objects", [1, 2]), "objects: expected a mapping"),
    "timestamp string": (lambda d: _frame0(d)["frame_properties"].__setitem__("timestamp", "now"), "timestamp: expected a finite number"),
    "mixed times": (lambda d: _frame0(d)["frame_properties"].pop("timestamp"), "1 of 3 frames have no time"),
    "times a year apart": (lambda d: _frame0(d)["frame_properties"].__setitem__("timestamp", 1.6e9), "times span"),
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(CASES))
def test_tumtraf_hostile_input_is_one_line(tmp_path, capsys, case):
    src = write_tumtraf(tmp_path / "src")
    label = src / "labels" / "cooperative.json"
    edit, expected = CASES[case]
    _edit(label, edit)
    _refused(tmp_path, capsys, ["tumtraf-v2x", str(src)], str(label), expected)


@pytest.mark.parametrize(
    ("text", "expected"),
    [("[" * 200 + "]" * 200, "nested deeper"), ("{not json", "not valid JSON"), ("[1, 2]", "expected a mapping")],
)  # fmt: skip
def test_tumtraf_unreadable_files_are_one_line(tmp_path, capsys, text, expected):
    src = write_tumtraf(tmp_path / "src")
    (src / "labels" / "cooperative.json").write_text(text)
    _refused(tmp_path, capsys, ["tumtraf-v2x", str(src)], "cooperative.json", expected)


def test_a_folder_without_labels_and_links_out_are_refused(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    _refused(tmp_path, capsys, ["tumtraf-v2x", str(tmp_path / "empty")], "no OpenLABEL .json files")
    src = write_tumtraf(tmp_path / "src")
    outside = tmp_path / "outside.json"
    outside.write_text((src / "labels" / "cooperative.json").read_text())
    os.symlink(outside, src / "labels" / "linked.json")
    _refused(tmp_path, capsys, ["tumtraf-v2x", str(src)], "linked.json", "outside")


def test_import_help_names_it(capsys):
    with pytest.raises(SystemExit):
        main(["import", "--help"])
    assert "tumtraf-v2x" in capsys.readouterr().out
