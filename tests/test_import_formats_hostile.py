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
    # 527 bytes expanding to 10⁹ numbers in a numeric field: the error path once formatted the
    # expanded value (16 s and 640 MB at 7 levels, still running at 120 s at 9)
    "alias bomb in a number": (
        "a0: &a0 [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\n"
        + "".join(f"a{k}: &a{k} [" + ", ".join([f"*a{k - 1}"] * 10) + "]\n" for k in range(1, 9))
        + "lidar_pose: *a8\n",
        "more than 1,000,000 values with its aliases expanded",
    ),
    "larger than the YAML cap": ("x: " + "1" * (4 * 2**20) + "\n", "larger than 4 MiB"),
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


def test_anchors_and_aliases_stay_legal(tmp_path):
    """Real V2V4Real files use anchors: a file whose boxes share an aliased extent and whose
    pose is an alias imports as the same file written out in full."""
    plain = write_opv2v(tmp_path / "plain", agents=(7, 3))
    aliased = write_opv2v(tmp_path / "aliased", agents=(7, 3))
    path = aliased / "2021_08_22_21_41_24" / "7" / "000070.yaml"
    data = yaml.safe_load(path.read_text())
    data["true_ego_pos"] = data["lidar_pose"]  # dumped as an anchor and an alias
    (plain / path.relative_to(aliased)).write_text(
        yaml.safe_dump(data).replace("&id001 ", "").replace("*id001", str(data["lidar_pose"]))
    )
    path.write_text(yaml.safe_dump(data))
    assert "*id001" in path.read_text()
    one = main(["import", "opv2v", str(plain), "--out", str(tmp_path / "one")])
    two = main(["import", "opv2v", str(aliased), "--out", str(tmp_path / "two")])
    assert one == two == 0
    records = [sorted((tmp_path / o / "pairs").rglob("record.json")) for o in ("one", "two")]
    assert [p.read_bytes() for p in records[0]] == [p.read_bytes() for p in records[1]]


@pytest.mark.parametrize("target", ["outside yaml", "/etc/passwd"])
def test_data_protocol_yaml_is_confined_like_every_file(tmp_path, capsys, target):
    """The one file once opened without the confinement check: a link out of SRC was followed
    (another folder's protocol renumbered the episodes; /etc/passwd was parsed silently)."""
    src = write_opv2v(tmp_path / "split")
    outside = tmp_path / "evil.yaml"
    outside.write_text(yaml.safe_dump({"cadsim": {"episode": 77, "slot": 5, "sim_seed": 9}}))
    link = src / "2021_08_22_21_41_24" / "data_protocol.yaml"
    os.symlink(outside if target == "outside yaml" else target, link)
    _refused(tmp_path, capsys, ["opv2v", str(src)], "data_protocol.yaml", "leads outside")


def test_protocol_ids_cannot_forge_ground_truth(tmp_path, capsys):
    """``cadsim.ids`` renaming actor 103 to ``105`` made two different objects (agent 7's 103,
    agent 3's 105) one true pair, silently."""
    src = write_opv2v(tmp_path / "split", agents=(7, 3))
    protocol = {"cadsim": {"episode": 0, "slot": 0, "sim_seed": 0, "ids": {103: "105"}}}
    (src / "2021_08_22_21_41_24" / "data_protocol.yaml").write_text(yaml.safe_dump(protocol))
    _refused(
        tmp_path, capsys, ["opv2v", str(src)], "data_protocol.yaml", "cadsim.ids: actors", "105"
    )


@pytest.mark.parametrize("fmt", ["v2x-seq", "opv2v", "dmgm"])
def test_an_empty_out_never_means_the_current_folder(tmp_path, capsys, monkeypatch, fmt):
    """``Path("")`` is ``.``: the importers checked the output folder after that conversion, so
    ``--out ""`` in an empty folder wrote a dataset into it."""
    src = write_v2x_seq(tmp_path / "spd") if fmt == "v2x-seq" else write_opv2v(tmp_path / "s")
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    assert main(["import", fmt, str(src), "--out", ""]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "--out: expected a folder path, got an empty one" in lines[0]
    assert list(cwd.iterdir()) == []


def test_the_v2x_seq_digest_reads_only_the_files_imported(tmp_path):
    """The source digest once read every ``*.json`` under SRC, whole (a 64 GiB sparse file:
    MemoryError; a 1,200-deep tree: RecursionError). Stray files — one above the size limit,
    one at the bottom of a 1,200-deep tree — leave the import and its digest unchanged."""
    src = write_v2x_seq(tmp_path / "spd")
    assert main(["import", "v2x-seq", str(src), "--out", str(tmp_path / "clean")]) == 0
    with open(src / "stray.json", "wb") as big:
        big.truncate(65 * 2**20)  # sparse: no disk used, and never read
    deep = src / "deep"
    os.mkdir(deep)
    for _ in range(1200):
        deep = deep / "d"
        os.mkdir(deep)
    (deep / "x.json").write_text("[]")
    try:
        assert main(["import", "v2x-seq", str(src), "--out", str(tmp_path / "strays")]) == 0
        digests = [
            json.loads((tmp_path / o / "manifest.json").read_text())["source"]["sha256"]
            for o in ("clean", "strays")
        ]
        assert digests[0] == digests[1]
    finally:  # pytest's own clean-up recurses once per level
        (deep / "x.json").unlink()
        while deep != src:
            deep.rmdir()
            deep = deep.parent


# --- the numpy-tag reader (V2V4Real) and the DAIR-V2X-C importer ---

_DTYPE = "!!python/object/apply:numpy.dtype {args: [f8, false, true]}"
NUMPY_TAG_CASES = {
    "other python tag": ("!!python/object/apply:subprocess.Popen [[touch, pwned]]", "refused tag !!python/object/apply:subprocess.Popen"),
    "python name": ("!!python/name:os.system ''", "refused tag !!python/name:os.system"),
    "object dtype": ("!!python/object/apply:numpy.dtype {args: [O8, false, true]}", "numpy.dtype: expected one of"),
    "scalar payload too short": (f"!!python/object/apply:numpy.core.multiarray.scalar [{_DTYPE}, !!binary AAAA]", "3 bytes for a 8-byte item"),
    "array payload lies": (
        "!!python/object/apply:numpy.core.multiarray._reconstruct {args: [!!python/name:numpy.ndarray '', "
        f"!!python/tuple [0], !!binary Yg==], state: !!python/tuple [1, !!python/tuple [4, 4], {_DTYPE}, false, !!binary AAAA]}}",
        "3 bytes for 16 items",
    ),
    "array too large": (
        "!!python/object/apply:numpy.core.multiarray._reconstruct {args: [!!python/name:numpy.ndarray '', "
        f"!!python/tuple [0], !!binary Yg==], state: !!python/tuple [1, !!python/tuple [60000, 60000], {_DTYPE}, false, !!binary AAAA]}}",
        "more than 65536",
    ),
    "reconstruct of another class": (
        "!!python/object/apply:numpy.core.multiarray._reconstruct {args: [!!python/name:numpy.matrix '', "
        "!!python/tuple [0], !!binary Yg==]}",
        "refused tag !!python/name:numpy.matrix",
    ),
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(NUMPY_TAG_CASES))
def test_v2v4real_hostile_numpy_tags_are_one_line(tmp_path, capsys, case):
    from format_fixtures import write_v2v4real

    src = write_v2v4real(tmp_path / "src")
    path = next(src.rglob("000001.yaml"))
    value, expected = NUMPY_TAG_CASES[case]
    path.write_text(path.read_text() + f"extra: {value}\n")
    _refused(tmp_path, capsys, ["v2v4real", str(src)], "000001.yaml", expected)
    assert not (tmp_path / "pwned").exists() and not Path("pwned").exists()


def test_numpy_tag_alias_bomb_is_refused(tmp_path, capsys):
    from format_fixtures import write_v2v4real

    src = write_v2v4real(tmp_path / "src")
    path = next(src.rglob("000002.yaml"))
    bomb = "a0: &a0 [" + ", ".join(["*id001"] * 9) + "]\n"
    for k in range(1, 9):
        bomb += f"a{k}: &a{k} [" + ", ".join([f"*a{k - 1}"] * 9) + "]\n"
    path.write_text(path.read_text() + bomb)
    _refused(
        tmp_path, capsys, ["v2v4real", str(src)], "000002.yaml", "values with its aliases expanded"
    )


def _dair_edit(path: Path, edit) -> None:
    path.write_text(json.dumps(edit(json.loads(path.read_text()))))


DAIR_CASES = {
    "cooperative label path traversal": (
        "cooperative/data_info.json",
        lambda d: [d[0] | {"cooperative_label_path": "../../../etc/passwd"}, *d[1:]],
        "[0].cooperative_label_path: path '../../../etc/passwd' leaves",
    ),
    "not a frame file name": (
        "cooperative/data_info.json",
        lambda d: [d[0] | {"vehicle_pointcloud_path": "vehicle-side/velodyne/../x.pcd"}, *d[1:]],
        "[0].vehicle_pointcloud_path: expected a digit file name",
    ),
    "NaN corner": (
        "cooperative/label_world/000010.json",
        lambda d: [d[0] | {"world_8_points": [[float("nan"), 0, 0]] * 8}],
        "non-finite number NaN",
    ),
    "seven corners": (
        "cooperative/label_world/000010.json",
        lambda d: [d[0] | {"world_8_points": d[0]["world_8_points"][:7]}],
        "[0].world_8_points: expected a list of 24 numbers",
    ),
    "huge offset": (
        "cooperative/data_info.json",
        lambda d: [d[0] | {"system_error_offset": {"delta_x": 1e9, "delta_y": 0}}, *d[1:]],
        "[0].system_error_offset.delta_x: expected a finite number",
    ),
    "a reflection as the roadside rotation": (
        "infrastructure-side/calib/virtuallidar_to_world/000020.json",
        lambda d: d | {"rotation": [[1, 0, 0], [0, 1, 0], [0, 0, -1]]},
        "rotation: not a rotation matrix",
    ),
    "missing label": (
        "vehicle-side/label/lidar/000011.json",
        None,
        "missing file",
    ),
}


@pytest.mark.parametrize("case", sorted(DAIR_CASES))
def test_dair_v2x_hostile_input_is_one_line(tmp_path, capsys, case):
    from format_fixtures import write_dair_v2x

    src = write_dair_v2x(tmp_path / "dair")
    rel, edit, expected = DAIR_CASES[case]
    if edit is None:
        (src / rel).unlink()
    else:
        _dair_edit(src / rel, edit)
    _refused(tmp_path, capsys, ["dair-v2x", str(src)], rel.split("/")[-1], expected)


def test_dair_v2x_without_any_calibration_is_one_line(tmp_path, capsys):
    from format_fixtures import write_dair_v2x

    src = write_dair_v2x(tmp_path / "dair", world=False)
    _refused(tmp_path, capsys, ["dair-v2x", str(src)], "lidar_i2v/000010.json", "missing file")
