"""Hostile input to ``cadsim import v2x-seq`` and ``cadsim import opv2v``: code-running YAML
tags, deep nesting, huge numbers, path traversal, missing keys, NaN boxes. Each is refused with
one line naming the file and the key, exit status 2, and nothing is written anywhere — not
outside ``--out``, and no dataset inside it."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
import yaml
from format_fixtures import write_opv2v, write_v2x_seq

from cadsim.cli import main


def _tree(root: Path) -> dict[str, int]:
    return {
        str(p.relative_to(root)): p.stat().st_size
        for p in sorted(root.rglob("*"))
        if p.is_file() or p.is_symlink()
    }


def _refused(tmp_path: Path, capsys, args: list[str], *expected: str) -> None:
    before = _tree(tmp_path)
    out = tmp_path / "out"
    assert main(["import", *args, "--out", str(out)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("cadsim import: error:"), lines
    for part in expected:
        assert part in lines[0], (part, lines[0])
    assert _tree(tmp_path) == before  # nothing written, in --out or beside it
    assert not out.exists()


def _edit_json(path: Path, edit) -> None:
    data = json.loads(path.read_text())
    path.write_text(edit(data) if callable(edit) else edit)


SPD_CASES = {
    "deep nesting": ("cooperative/data_info.json", "[" * 200 + "]" * 200, "nested deeper"),
    "huge number": (
        "vehicle-side/label/lidar/000010.json",
        lambda d: json.dumps([d[0] | {"3d_location": {"x": 1e300, "y": 0, "z": 0}}]),
        "[0].3d_location.x: expected a finite number",
    ),
    "huge integer": (
        "vehicle-side/label/lidar/000010.json",
        '[{"x": ' + "9" * 5000 + "}]",
        "not valid JSON",
    ),
    "NaN box": (
        "infrastructure-side/label/virtuallidar/000020.json",
        lambda d: json.dumps(d).replace('"l": 4.5', '"l": NaN'),
        "non-finite number NaN",
    ),
    "missing key": (
        "vehicle-side/label/lidar/000011.json",
        lambda d: json.dumps([{k: v for k, v in d[0].items() if k != "3d_dimensions"}]),
        "[0].3d_dimensions: missing",
    ),
    "path traversal": (
        "vehicle-side/data_info.json",
        lambda d: json.dumps([d[0] | {"label_lidar_std_path": "../../../etc/passwd"}, *d[1:]]),
        "[0].label_lidar_std_path: path '../../../etc/passwd' leaves",
    ),
    "absolute path": (
        "infrastructure-side/data_info.json",
        lambda d: json.dumps([d[0] | {"calib_virtuallidar_to_world_path": "/etc/passwd"}, *d[1:]]),
        "calib_virtuallidar_to_world_path: path '/etc/passwd' leaves",
    ),
    "not a rotation": (
        "vehicle-side/calib/novatel_to_world/000010.json",
        json.dumps({"rotation": [[2, 0, 0], [0, 1, 0], [0, 0, 1]], "translation": [0, 0, 0]}),
        "rotation: not a rotation matrix",
    ),
}


@pytest.mark.parametrize("case", sorted(SPD_CASES))
def test_v2x_seq_hostile_input_is_one_line(tmp_path, capsys, case):
    src = write_v2x_seq(tmp_path / "spd")
    rel, edit, expected = SPD_CASES[case]
    _edit_json(src / rel, edit)
    _refused(tmp_path, capsys, ["v2x-seq", str(src)], rel.split("/")[-1], expected)


def _yaml_edit(path: Path, edit) -> None:
    if callable(edit):
        path.write_text(yaml.safe_dump(edit(yaml.safe_load(path.read_text()))))
    else:
        path.write_text(edit)


OPV2V_CASES = {
    "python object tag": (
        "!!python/object/apply:os.system ['touch {pwned}']\n",
        "not safe YAML",
    ),
    "deep nesting": ("a: " + "[" * 200 + "]" * 200 + "\n", "nested deeper"),
    "huge number": (
        lambda d: d | {"lidar_pose": [1e400, 0, 0, 0, 0, 0]},
        "lidar_pose[0]: expected a finite number",
    ),
    "NaN box": (
        lambda d: (
            d
            | {
                "vehicles": {
                    101: next(iter(d["vehicles"].values())) | {"location": [float("nan"), 0, 0]}
                }
            }
        ),
        "vehicles.101.location[0]: expected a finite number",
    ),
    "missing key": (
        lambda d: {k: v for k, v in d.items() if k != "lidar_pose"},
        "lidar_pose: missing",
    ),
    "bad actor id": (
        lambda d: d | {"vehicles": {"../../x": next(iter(d["vehicles"].values()))}},
        "expected an integer actor id",
    ),
    "alias bomb": (
        "a: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(f"b{k}: *a\n" for k in range(1100)),
        "more than 1000 aliases",
    ),
}


@pytest.mark.parametrize("case", sorted(OPV2V_CASES))
def test_opv2v_hostile_input_is_one_line(tmp_path, capsys, case):
    src = write_opv2v(tmp_path / "split")
    path = src / "2021_08_22_21_41_24" / "7" / "000070.yaml"
    edit, expected = OPV2V_CASES[case]
    if isinstance(edit, str):
        edit = edit.replace("{pwned}", str(tmp_path / "PWNED"))
    _yaml_edit(path, edit)
    _refused(tmp_path, capsys, ["opv2v", str(src)], "7/000070.yaml", expected)
    assert not (tmp_path / "PWNED").exists()


# data_protocol.yaml's prior keys (written by cadsim export opv2v): key -> hostile values
PRIOR_CASES = [
    (key, value)
    for key in ("prior_sigma_m", "prior_latency_s", "prior_position_sigma_m", "prior_yaw_sigma_deg")
    for value in (-1.0, float("nan"), 1e300, 10**400, "3.2", [3.2], True)
] + [("prior_sigma_m", 0), ("prior_sigma_m", float("inf")), ("prior_latency_s", 60.0)]
PRESET_CASES = ["gnss-nowhere", 3, ["gnss-urban"], "gnss-urban*" + "9" * 100]


@pytest.mark.parametrize(("key", "value"), PRIOR_CASES, ids=[f"{k}={str(v)[:12]}" for k, v in PRIOR_CASES])  # fmt: skip
def test_opv2v_hostile_prior_keys_are_one_line(tmp_path, capsys, key, value):
    src = write_opv2v(tmp_path / "split")
    block = {"episode": 0, "slot": 0, "sim_seed": 5, "prior_sigma_m": 3.2, key: value}
    path = src / "2021_08_22_21_41_24" / "data_protocol.yaml"
    path.write_text(yaml.safe_dump({"cadsim": block}))
    expected = f"cadsim.{key}: expected a number "
    _refused(tmp_path, capsys, ["opv2v", str(src)], "data_protocol.yaml", expected)


@pytest.mark.parametrize("value", PRESET_CASES, ids=[str(v)[:14] for v in PRESET_CASES])
def test_opv2v_hostile_prior_preset_is_one_line(tmp_path, capsys, value):
    src = write_opv2v(tmp_path / "split")
    block = {"episode": 0, "slot": 0, "sim_seed": 5, "prior_preset": value}
    path = src / "2021_08_22_21_41_24" / "data_protocol.yaml"
    path.write_text(yaml.safe_dump({"cadsim": block}))
    expected = "cadsim.prior_preset: expected a localisation preset"
    _refused(tmp_path, capsys, ["opv2v", str(src)], "data_protocol.yaml", expected)


def test_links_out_of_the_folder_are_not_followed(tmp_path, capsys):
    src = write_opv2v(tmp_path / "split", agents=(7, 3))
    outside = write_opv2v(tmp_path / "elsewhere", agents=(-1,))
    scenario = src / "2021_08_22_21_41_24"
    os.symlink(outside / "2021_08_22_21_41_24" / "-1", scenario / "-1")
    assert main(["import", "opv2v", str(src), "--out", str(tmp_path / "out"), "--agents", "3"]) == 2
    assert "no frame with 3 agents" in capsys.readouterr().err


def test_refusal_of_a_used_output_folder_writes_nothing(tmp_path, capsys):
    src = write_v2x_seq(tmp_path / "spd")
    assert main(["import", "v2x-seq", str(src), "--out", str(src)]) == 2
    assert "not an empty folder" in capsys.readouterr().err
