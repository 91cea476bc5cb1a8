"""Hostile import sources and scenarios past the earlier limits: an empty array axis (a size
product of 0) that hid billions of empty lists, DAIR-V2X label files with no box limit and a
frame listed twice, ``clutter_spacing`` without a minimum, and V2V4Real's local keys, dtype
byte orders, duplicated links and recording names. Each is one line naming the file (and the
key) with exit status 2, or a correct result; the costly ones run in a child process whose
address space is capped at what it maps after start-up + 1 GiB (the old code asked for 2.3 and
3.6 GB), with a generous timeout and no timing assertion."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from format_fixtures import write_dair_v2x, write_v2v4real, write_v2x_seq

from cadsim.cli import main
from cadsim.dataset.encoding import load_npz
from cadsim.importers.dair_side import MAX_BOXES, MAX_LABEL_BYTES
from cadsim.importers.episode_names import episode_numbers
from cadsim.importers.numpy_yaml import MAX_ARRAY_ITEMS, MAX_FILE_ARRAY_ITEMS
from cadsim.sources.sumo.schema import MAX_CLUTTER_OBJECTS, MIN_CLUTTER_SPACING_M

ROOT = Path(__file__).resolve().parents[1]
_CAPPED = """
import resource, sys
from pathlib import Path
from cadsim.cli import main
status = Path("/proc/self/status").read_text().splitlines()
mapped = next(int(line.split()[1]) * 1024 for line in status if line.startswith("VmSize:"))
soft, hard = resource.getrlimit(resource.RLIMIT_AS)
limit = mapped + 2**30
resource.setrlimit(resource.RLIMIT_AS, (limit if hard < 0 else min(limit, hard), hard))
sys.exit(main(sys.argv[1:]))
"""


def _capped(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    """``cadsim ARGS`` in a child whose address space is capped (module docstring)."""
    env = os.environ | {"PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1"}
    return subprocess.run(
        [sys.executable, "-c", _CAPPED, *args],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )


def _one_line(stderr: str, command: str, *parts: str) -> str:
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"cadsim {command}: error:"), lines[-5:]
    for part in parts:
        assert part in lines[0], (part, lines[0])
    return lines[0]


def _refused(capsys, args: list[str], *parts: str) -> str:
    assert main(args) == 2
    return _one_line(capsys.readouterr().err, args[0], *parts)


def _json_edit(path: Path, edit) -> None:
    path.write_text(json.dumps(edit(json.loads(path.read_text()))))


# --- an empty axis: the size product is 0, the lists built are not ------------------------

_DTYPE = "!!python/object/apply:numpy.dtype {args: [f8, false, true]}"


def _array(shape: tuple[int, ...], payload: str = "''") -> str:
    sizes = ", ".join(map(str, shape))
    return (
        "!!python/object/apply:numpy.core.multiarray._reconstruct {args: [!!python/name:numpy.ndarray "
        f"'', !!python/tuple [0], !!binary Yg==], state: !!python/tuple [1, !!python/tuple [{sizes}], "
        f"{_DTYPE}, false, !!binary {payload}]}}"
    )  # fmt: skip


def test_a_v2v4real_import_runs_under_the_cap(tmp_path):
    """The control: the cap leaves a legitimate import room."""
    src = write_v2v4real(tmp_path / "src")
    done = _capped(["import", "v2v4real", str(src), "--out", str(tmp_path / "out")], tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]


@pytest.mark.parametrize(
    "shape",
    [
        (65536, 65536, 0),
        (0, 65536, 65536),
        (65536, 2, 0),
        (300, 300, 0, 1),
        (65536, 65536, 65536, 65536),  # 2⁶⁴: an int64 product wrapped to 0 ("cannot reshape")
    ],
)
def test_an_empty_axis_cannot_build_billions_of_lists(tmp_path, shape):
    src = write_v2v4real(tmp_path / "src")
    path = next(src.rglob("0/000001.yaml"))
    path.write_text(path.read_text().replace("lidar_pose: &id002", f"extra: {_array(shape)}\nlidar_pose: &id002"))  # fmt: skip
    done = _capped(["import", "v2v4real", str(src), "--out", str(tmp_path / "out")], tmp_path)
    assert done.returncode == 2, done.stderr[-2000:]
    _one_line(done.stderr, "import", "0/000001.yaml", f"is more than {MAX_ARRAY_ITEMS} items")
    assert not (tmp_path / "out").exists()


def test_many_empty_arrays_cannot_add_up_to_billions_of_lists(tmp_path):
    """1,000 arrays of (256, 256, 0), each within the limit: 66 million lists together."""
    src = write_v2v4real(tmp_path / "src")
    path = next(src.rglob("0/000001.yaml"))
    extra = "".join(f"extra{k}: {_array((256, 256, 0))}\n" for k in range(1000))
    path.write_text(path.read_text() + extra)
    done = _capped(["import", "v2v4real", str(src), "--out", str(tmp_path / "out")], tmp_path)
    assert done.returncode == 2, done.stderr[-2000:]
    _one_line(
        done.stderr,
        "import",
        "0/000001.yaml",
        f"more than {MAX_FILE_ARRAY_ITEMS} items in one file",
    )


def test_an_empty_array_within_the_limit_is_read(tmp_path):
    src = write_v2v4real(tmp_path / "src")
    path = next(src.rglob("0/000001.yaml"))
    path.write_text(path.read_text() + f"extra: {_array((4, 0))}\n")
    assert main(["import", "v2v4real", str(src), "--out", str(tmp_path / "out")]) == 0


def test_an_npz_header_with_an_empty_axis_is_refused():
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        header, {"descr": "<f8", "fortran_order": False, "shape": (2**40, 0)}
    )
    blob = io.BytesIO()
    with zipfile.ZipFile(blob, "w") as zf:
        zf.writestr("view1_positions.npy", header.getvalue())
    with pytest.raises(ValueError, match=r"^pairs/x/detections.npz: view1_positions: its header"):
        load_npz(blob.getvalue(), "pairs/x/detections.npz")
    ok = load_npz(_npz({"a": np.zeros((3, 0))}), "ok.npz")["a"]
    assert ok.shape == (3, 0)


def _npz(arrays: dict) -> bytes:
    blob = io.BytesIO()
    np.savez(blob, **arrays)
    return blob.getvalue()


# --- DAIR-V2X: a box limit per side file, one side entry per frame, batch names ------------


def _boxes(n: int):
    return lambda d: [d[0]] * n


@pytest.mark.parametrize(
    "rel, boxes",
    [
        ("vehicle-side/label/lidar/000010.json", 12_000),
        ("infrastructure-side/label/virtuallidar/000021.json", 12_000),
        ("cooperative/label_world/000010.json", 5_000),  # 450 bytes a box: within 4 MiB
    ],
)
def test_dair_v2x_label_files_have_a_box_limit(tmp_path, rel, boxes):
    """12,000 boxes on one side (1.7 MB) once asked for 2.3 GB."""
    src = write_dair_v2x(tmp_path / "dair")
    _json_edit(src / rel, _boxes(boxes))
    done = _capped(["import", "dair-v2x", str(src), "--out", str(tmp_path / "out")], tmp_path)
    assert done.returncode == 2, done.stderr[-2000:]
    _one_line(done.stderr, "import", rel, f"{boxes} boxes, more than {MAX_BOXES}")


def test_dair_v2x_label_files_have_a_size_limit(tmp_path, capsys):
    """A 64 MiB label would be parsed whole before its boxes are counted."""
    src = write_dair_v2x(tmp_path / "dair")
    rel = "infrastructure-side/label/virtuallidar/000020.json"
    with open(src / rel, "r+b") as label:
        label.truncate(64 * 2**20)  # sparse: no disk used
    _refused(
        capsys,
        ["import", "dair-v2x", str(src), "--out", str(tmp_path / "out")],
        f"{rel}: larger than {MAX_LABEL_BYTES / 2**20:g} MiB",
    )


def test_dair_v2x_boxes_up_to_the_limit_are_imported(tmp_path):
    src = write_dair_v2x(tmp_path / "dair")
    _json_edit(src / "vehicle-side/label/lidar/000010.json", _boxes(MAX_BOXES))
    assert main(["import", "dair-v2x", str(src), "--out", str(tmp_path / "out")]) == 0


@pytest.mark.parametrize("side", ["vehicle-side", "infrastructure-side"])
def test_a_frame_twice_in_a_side_data_info_is_refused(tmp_path, capsys, side):
    src = write_dair_v2x(tmp_path / "dair")
    info = src / side / "data_info.json"
    _json_edit(info, lambda d: [*d, d[0] | {"pointcloud_timestamp": "1"}])
    frame = json.loads(info.read_text())[0]["pointcloud_path"].split("/")[-1][:-4]
    _refused(
        capsys,
        ["import", "dair-v2x", str(src), "--out", str(tmp_path / "out")],
        f"{side}/data_info.json: [3].pointcloud_path: frame '{frame}' already at [0]",
    )


def _episodes(out: Path) -> dict[int, int]:
    records = json.loads((out / "manifest.json").read_text())["records"]
    counts: dict[int, int] = {}
    for r in records:
        counts[r["episode"]] = counts.get(r["episode"], 0) + 1
    return counts


@pytest.mark.parametrize(
    "batches, episodes",
    [
        (["3", "3", "4"], {3: 2, 4: 1}),  # the fixture as written
        (["3", "3", "abc"], {3: 2, 4: 1}),  # once silently episode 0
        (["abc", "x", "abc"], {1: 2, 2: 1}),  # once all episode 0, two batches merged
        (["1", "abc", 7], {1: 1, 7: 1, 8: 1}),  # an integer batch_id is its number
        (["abc", "abc", None], {0: 1, 1: 2}),  # a frame not listed: 0, never a named batch's
    ],
)
def test_dair_v2x_batch_ids_are_distinct_episodes(tmp_path, batches, episodes):
    src = write_dair_v2x(tmp_path / "dair")
    _json_edit(
        src / "vehicle-side/data_info.json",
        lambda d: [e | {"batch_id": b} for e, b in zip(d, batches, strict=True) if b is not None],
    )
    assert main(["import", "dair-v2x", str(src), "--out", str(tmp_path / "out")]) == 0
    assert _episodes(tmp_path / "out") == episodes


@pytest.mark.parametrize(
    "batch, expected",
    [
        (["a"], "[0].batch_id: expected a recording name (string or integer), got ['a']"),
        (True, "[0].batch_id: expected a recording name"),
    ],
)
def test_a_batch_id_that_is_no_name_is_refused(tmp_path, capsys, batch, expected):
    src = write_dair_v2x(tmp_path / "dair")
    _json_edit(src / "vehicle-side/data_info.json", lambda d: [d[0] | {"batch_id": batch}, *d[1:]])
    args = ["import", "dair-v2x", str(src), "--out", str(tmp_path / "out")]
    _refused(capsys, args, "vehicle-side/data_info.json: " + expected)


def test_two_spellings_of_one_batch_number_are_refused(tmp_path, capsys):
    src = write_dair_v2x(tmp_path / "dair")
    _json_edit(src / "vehicle-side/data_info.json", lambda d: [d[0] | {"batch_id": "03"}, *d[1:]])
    args = ["import", "dair-v2x", str(src), "--out", str(tmp_path / "out")]
    _refused(capsys, args, "vehicle-side/data_info.json: batch_id: '03' and '3' are both episode 3")


def test_episode_numbers_never_collide():
    assert episode_numbers(["1", "abc"]) == {"1": 1, "abc": 2}
    assert episode_numbers(["abc", "0010", "²", "1234567890"]) == {
        "0010": 10, "1234567890": 11, "abc": 12, "²": 13,
    }  # fmt: skip
    assert episode_numbers(["b", "a"]) == {"a": 0, "b": 1}


def test_v2x_seq_sequences_1_and_abc_are_two_episodes(tmp_path):
    """Once refused as "episode 1 twice" (abc took its index, 1)."""
    src = write_v2x_seq(tmp_path / "spd")
    _json_edit(
        src / "cooperative/data_info.json",
        lambda d: [d[0] | {"vehicle_sequence": "abc"}, *(c | {"vehicle_sequence": "1"} for c in d[1:])],
    )  # fmt: skip
    assert main(["import", "v2x-seq", str(src), "--out", str(tmp_path / "out")]) == 0
    assert _episodes(tmp_path / "out") == {1: 2, 2: 1}
    source = json.loads((tmp_path / "out" / "manifest.json").read_text())["source"]
    assert source["sequences"] == {"1": 2, "abc": 1}


# --- clutter_spacing: a minimum, and the object count it implies -------------------------


def _scenario(tmp_path: Path, old: str, new: str) -> Path:
    text = (ROOT / "scenarios" / "cad-v2x.toml").read_text()
    assert old in text
    path = tmp_path / "cad-v2x.toml"
    path.write_text(text.replace(old, new, 1))
    (tmp_path / "cad-vtypes.add.xml").write_bytes((ROOT / "scenarios" / "cad-vtypes.add.xml").read_bytes())  # fmt: skip
    return path


@pytest.mark.parametrize("spacing", ["1e-9", "0.001", "0.01", "9.99", "-1", "1e308"])
def test_clutter_spacing_below_its_minimum_is_refused(tmp_path, spacing):
    """1e-9 once asked for 2 TiB, 0.001 for 2 GB and 120 s, 0.01 gave 73,202 overlapping
    objects."""
    path = _scenario(tmp_path, "clutter_spacing = 25.0", f"clutter_spacing = {spacing}")
    out = tmp_path / "out"
    done = _capped(["generate", str(path), "--out", str(out), "--pairs", "1"], tmp_path)
    assert done.returncode == 2, done.stderr[-2000:]
    _one_line(
        done.stderr,
        "generate",
        f"{path}: traffic.scene.clutter_spacing: is ",
        f"expected 0 (none) or metres in [{MIN_CLUTTER_SPACING_M:g}, 10000]",
    )
    assert not out.exists()


def test_clutter_on_a_large_network_is_bounded(tmp_path, capsys):
    path = _scenario(
        tmp_path, "junctions = 1 ", "block_length = 5000.0\njunctions = 20 "
    )  # 7,600 km of road sides at 25 m: about 305,000 objects
    out = tmp_path / "out"
    line = _refused(
        capsys,
        ["generate", str(path), "--out", str(out), "--pairs", "1"],
        f"{path}: traffic.scene.clutter_spacing: is 25: about ",
        f"expected at most {MAX_CLUTTER_OBJECTS:,} objects",
    )
    assert "km of road sides" in line and not out.exists()


# --- V2V4Real: local keys, exact byte orders, one box per object, names shown inert -------


def test_boxes_without_ass_id_are_never_linked_across_vehicles(tmp_path):
    """ "c" sits under local key 5 in both vehicles: with ``ass_id`` −1 or without one it is two
    objects; the datasets are the same."""
    with_link = write_v2v4real(tmp_path / "with")
    without = write_v2v4real(tmp_path / "without")
    for path in without.rglob("*.yaml"):
        text = path.read_text()
        path.write_text(text.replace("    ass_id: -1\n", ""))
    assert "ass_id: -1" not in "".join(p.read_text() for p in without.rglob("*.yaml"))
    for src, out in ((with_link, "a"), (without, "b")):
        assert main(["import", "v2v4real", str(src), "--out", str(tmp_path / out)]) == 0
    checksums = [json.loads((tmp_path / o / "manifest.json").read_text())["checksum"] for o in "ab"]
    assert checksums[0] == checksums[1]


@pytest.mark.parametrize("order", ["<>", "'<>'", "5", "'><'", "[<]"])
def test_the_dtype_byte_order_is_exact(tmp_path, capsys, order):
    src = write_v2v4real(tmp_path / "src")
    path = next(src.rglob("0/000001.yaml"))
    text = path.read_text()
    assert text.count("\n    - <\n") == 1
    path.write_text(text.replace("\n    - <\n", f"\n    - {order}\n"))
    _refused(
        capsys,
        ["import", "v2v4real", str(src), "--out", str(tmp_path / "out")],
        "0/000001.yaml: not safe YAML (numpy.dtype: state is not a plain dtype's",
    )


def test_one_link_twice_in_one_vehicle_names_the_file(tmp_path, capsys):
    """Two boxes with ``ass_id`` 7 in one vehicle once failed naming no file."""
    src = write_v2v4real(tmp_path / "src")
    path = next(src.rglob("0/000001.yaml"))
    path.write_text(path.read_text().replace("ass_id: 8", "ass_id: 7"))
    _refused(
        capsys,
        ["import", "v2v4real", str(src), "--out", str(tmp_path / "out")],
        "0/000001.yaml: vehicles.",
        "object 'a7' is also vehicles.",
    )


def test_class_names_are_shown_inert_by_cadsim_info(tmp_path, capsys):
    src = write_dair_v2x(tmp_path / "dair")
    hostile = "Car\n<script>alert(1)</script>\x1b[2J"
    _json_edit(
        src / "vehicle-side/label/lidar/000010.json", lambda d: [d[0] | {"type": hostile}, *d[1:]]
    )
    assert main(["import", "dair-v2x", str(src), "--out", str(tmp_path / "out")]) == 0
    capsys.readouterr()
    assert main(["info", str(tmp_path / "out")]) == 0
    text = capsys.readouterr().out
    assert "<script>" not in text and "\x1b" not in text
    mix = [line for line in text.splitlines() if line.startswith("  class mix")]
    assert len(mix) == 1 and "car\\n\\x3cscript\\x3ealert(1)\\x3c/script\\x3e\\x1b" in mix[0]
    assert not any(line.startswith("<script>") for line in text.splitlines())
