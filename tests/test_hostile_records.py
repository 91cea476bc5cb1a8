"""Issue 52, hostile findings 9-15: what a forged record, a forged import source, an impossible
scenario or a Ctrl-C used to get through (a traceback, a silent merge, a run that could never
end). Each is now one line naming the file and the key, exit status 2, and nothing written."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from dataset_forgery import edit_json, record_dirs, reseal
from format_fixtures import write_opv2v, write_v2x_seq

from cadsim.cli import main
from cadsim.dataset.lidar_points import check_lidar_arrays

ROOT = Path(__file__).resolve().parents[1]


def _tree(root: Path) -> dict[str, int]:
    return {str(p.relative_to(root)): p.stat().st_size for p in sorted(root.rglob("*"))}


def _refused(capsys, root: Path, args: list[str], *expected: str) -> str:
    """``cadsim ARGS`` exits 2 with one line holding ``expected``; nothing under ``root``
    changes (``--out`` included)."""
    before = _tree(root)
    assert main(args) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"cadsim {args[0]}: error:"), lines
    for part in expected:
        assert part in lines[0], (part, lines[0])
    assert _tree(root) == before
    return lines[0]


# --- import sources (findings 9, 11, 13) -------------------------------------------------------


def _coop(src: Path, edit) -> None:
    path = src / "cooperative" / "data_info.json"
    path.write_text(json.dumps(edit(json.loads(path.read_text()))))


def _side(src: Path, edit) -> None:
    path = src / "vehicle-side" / "data_info.json"
    path.write_text(json.dumps(edit(json.loads(path.read_text()))))


def _same_time(d: list) -> list:
    d[1]["pointcloud_timestamp"] = d[0]["pointcloud_timestamp"]
    return d


SPD_CASES = {
    "offset as a list": (
        lambda s: _coop(s, lambda d: [d[0] | {"system_error_offset": [1, 2]}, *d[1:]]),
        "data_info.json: [0].system_error_offset: expected {delta_x, delta_y}",
    ),
    "offset as a string": (
        lambda s: _coop(s, lambda d: [d[0] | {"system_error_offset": "1"}, *d[1:]]),
        "[0].system_error_offset: expected {delta_x, delta_y}",
    ),
    "cooperative frame twice": (
        lambda s: _coop(s, lambda d: [d[0], d[0], *d[1:]]),
        "[1].vehicle_frame: '000010' already listed at [0]",
    ),
    "frame_id twice": (
        lambda s: _side(s, lambda d: [*d, dict(d[0])]),
        "vehicle-side/data_info.json: [3].frame_id: '000010' already at [0]",
    ),
    "same timestamp": (
        lambda s: _side(s, _same_time),
        "frames '000010' and '000011' of sequence '0010': same pointcloud_timestamp",
    ),
}


@pytest.mark.parametrize("case", sorted(SPD_CASES))
def test_v2x_seq_sources_that_were_merged_or_crashed(tmp_path, capsys, case):
    src = write_v2x_seq(tmp_path / "spd")
    edit, expected = SPD_CASES[case]
    edit(src)
    _refused(capsys, tmp_path, ["import", "v2x-seq", str(src), "--out", str(tmp_path / "o")], expected)  # fmt: skip


def test_a_sequence_named_with_a_superscript_digit_is_a_name(tmp_path, capsys):
    src = write_v2x_seq(tmp_path / "spd")
    _coop(src, lambda d: [c | {"vehicle_sequence": "²"} for c in d])
    assert main(["import", "v2x-seq", str(src), "--out", str(tmp_path / "o")]) == 0


def _agent_yaml(scenario: Path, edit) -> None:
    path = scenario / "7" / "000070.yaml"
    path.write_text(yaml.safe_dump(edit(yaml.safe_load(path.read_text()))))


def _actor_twice(spelled):
    def edit(d: dict) -> dict:
        key = next(iter(d["vehicles"]))
        d["vehicles"][spelled(key)] = d["vehicles"][key]
        return d

    return edit


OPV2V_CASES = {
    "yaml key twice": (
        lambda sc: (sc / "7" / "000070.yaml").write_text(
            (sc / "7" / "000070.yaml").read_text() + "lidar_pose: [1, 2, 3, 0, 0, 0]\n"
        ),
        "7/000070.yaml: not safe YAML (key 'lidar_pose' given twice",
    ),
    "agent 3 and 03": (
        lambda sc: shutil.copytree(sc / "3", sc / "03"),
        "agent 3 is also the folder 03/",
    ),
    "agent 0 and -0": (
        lambda sc: (shutil.copytree(sc / "3", sc / "0"), shutil.copytree(sc / "3", sc / "-0")),
        "agent 0 is also the folder -0/",
    ),
    "frame 70 and 000070": (
        lambda sc: shutil.copy(sc / "7" / "000070.yaml", sc / "7" / "70.yaml"),
        "7/70.yaml: frame 70 is also named 000070.yaml",
    ),
    "actor 101 and '101'": (
        lambda sc: _agent_yaml(sc, _actor_twice(str)),
        "7/000070.yaml: vehicles.'101': actor 101 given twice (101 and '101')",
    ),
    "actor in Arabic-Indic digits": (
        lambda sc: _agent_yaml(sc, _actor_twice(lambda k: "١٠١")),
        "vehicles.'١٠١': expected an integer actor id (ASCII digits)",
    ),
    "actor with a newline": (
        lambda sc: _agent_yaml(sc, _actor_twice(lambda k: f"{k}\n")),
        "expected an integer actor id (ASCII digits)",
    ),
    "pose with last row 5 5 5 5": (
        lambda sc: _agent_yaml(
            sc, lambda d: d | {"lidar_pose": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [5] * 4]}
        ),
        "lidar_pose[3]: expected the row [0, 0, 0, 1]",
    ),
}


@pytest.mark.parametrize("case", sorted(OPV2V_CASES))
def test_opv2v_sources_that_were_merged_silently(tmp_path, capsys, case):
    src = write_opv2v(tmp_path / "split", agents=(7, 3))
    edit, expected = OPV2V_CASES[case]
    edit(src / "2021_08_22_21_41_24")
    _refused(capsys, tmp_path, ["import", "opv2v", str(src), "--out", str(tmp_path / "o")], expected)  # fmt: skip


def test_a_prior_sigma_beyond_10_km_is_refused(tmp_path, capsys):
    src = write_opv2v(tmp_path / "split", agents=(7, 3))
    args = ["import", "opv2v", str(src), "--out", str(tmp_path / "o"), "--prior-sigma", "1e308"]
    _refused(capsys, tmp_path, args, "--prior-sigma: expected a finite number in (0, 1e4] metres")


# --- resealed records (findings 9, 10, 12) -----------------------------------------------------


@pytest.fixture(scope="module")
def generated(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("hostile") / "arena"
    args = ["generate", str(ROOT / "scenarios" / "mrc-arena.toml"), "--out", str(out)]
    assert main([*args, "--pairs", "2", "--workers", "1", "--no-progress"]) == 0
    return out


@pytest.fixture(scope="module")
def sequence(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("hostile-seq")
    src = write_v2x_seq(root / "spd")
    assert main(["import", "v2x-seq", str(src), "--out", str(root / "ds")]) == 0
    return root / "ds"


def _observer(key: str, value):
    return lambda r: r["observers"][0]["camera"].__setitem__(key, value)


RECORD_CASES = {
    "hfov 0": (
        _observer("hfov_deg", 0),
        "observers[0].camera.hfov_deg: expected degrees in (0, 180)",
    ),  # fmt: skip
    "hfov 720": (
        _observer("hfov_deg", 720),
        "observers[0].camera.hfov_deg: expected degrees in (0, 180), got 720",
    ),  # fmt: skip
    "camera at 1e300": (
        _observer("position", [1e300, 0, 0]),
        "observers[0].camera: expected position",
    ),  # fmt: skip
    "negative size": (
        lambda r: r["objects"][0].__setitem__("size", [-1.0, 1.0, 1.0]),
        "objects[0].size: expected [length, width, height] in (0, 100000] m",
    ),
    "zero size": (
        lambda r: r["objects"][0].__setitem__("size", [0, 1.0, 1.0]),
        "objects[0].size",
    ),  # fmt: skip
    "centre at 1e300": (
        lambda r: r["objects"][0].__setitem__("center", [1e300, 0.0, 0.0]),
        "objects[0].center: expected [x, y, z] within ±1e+07 m",
    ),
    "prior sigma 1e300": (
        lambda r: r["prior"].__setitem__("position_sigma_m", 1e300),
        "prior: [localisation] position_sigma_m must be <= 10000",
    ),
}


@pytest.mark.parametrize("command", ["info", "export", "evaluate"])
@pytest.mark.parametrize("case", sorted(RECORD_CASES))
def test_resealed_records_outside_physics_are_refused(generated, tmp_path, capsys, case, command):
    ds = tmp_path / "ds"
    shutil.copytree(generated, ds)
    edit, expected = RECORD_CASES[case]
    edit_json(record_dirs(ds)[0], edit)
    reseal(ds)
    out = str(tmp_path / "out")
    args = {
        "info": ["info", str(ds)],
        "export": ["export", "opv2v", str(ds), "--out", out],
        "evaluate": ["evaluate", str(ds), "--no-calibration", "--matchers", "sm", "--runs", "1",
                     "--workers", "1", "--no-progress", "--out", out, "--cache", out + "-cache"],
    }[command]  # fmt: skip
    _refused(capsys, tmp_path, args, "record.json: " + expected)


def test_a_stored_prior_sigma_beyond_10_km_is_refused(sequence, tmp_path, capsys):
    ds = tmp_path / "ds"
    shutil.copytree(sequence, ds)
    edit_json(record_dirs(ds)[0], lambda r: r.__setitem__("prior", {"kind": "stored", "world_sigma_m": 1e308}))  # fmt: skip
    reseal(ds)
    _refused(capsys, tmp_path, ["info", str(ds)], "prior.world_sigma_m: expected metres in [0, 10000]")  # fmt: skip


def _time(k: int, value):
    return {k: lambda r: r.__setitem__("time", value)}


def _frames_times(ds: Path) -> list[float]:
    return [json.loads((d / "record.json").read_text())["time"] for d in record_dirs(ds)]


SEQUENCE_CASES = {
    "times swapped": ("swap", "e00010_s02/record.json: time: ", "not after the previous frame's"),
    "time repeated": ("repeat", "e00010_s02/record.json: time: ", "not after the previous frame's"),
    "interval_s mixed": (
        {1: lambda r: r["sequence"].__setitem__("interval_s", 0.5)},
        "e00010_s01/record.json: sequence.interval_s: 0.5, but frame 0",
    ),
    "start_time mixed": (
        {2: lambda r: r["sequence"].__setitem__("start_time", 5.0)},
        "e00010_s02/record.json: sequence.start_time: 5.0, but frame 0",
    ),
    "observers swapped": (
        {1: lambda r: r.__setitem__("observers", r["observers"][::-1])},
        "e00010_s01/record.json: observers: not frame 0's observers",
    ),
    "frames 500": (
        {k: (lambda r: r["sequence"].__setitem__("frames", 500)) for k in range(3)},
        "sequence.frames: 500, but the manifest lists 3 frames",
    ),
    "odometry 1e300": (
        {1: lambda r: r["observers"][0]["odometry"].__setitem__("position", [1e300, 0.0])},
        "e00010_s01/record.json: observers[0].odometry: expected position",
    ),
}


@pytest.mark.parametrize("case", sorted(SEQUENCE_CASES))
def test_a_sequence_is_checked_as_a_whole(sequence, tmp_path, capsys, case):
    ds = tmp_path / "ds"
    shutil.copytree(sequence, ds)
    edits, *expected = SEQUENCE_CASES[case]
    times = _frames_times(ds)
    if edits == "swap":
        edits = _time(1, times[2]) | _time(2, times[1])
    elif edits == "repeat":
        edits = _time(2, times[1])
    for k, edit in edits.items():
        edit_json(record_dirs(ds)[k], edit)
    reseal(ds)
    _refused(capsys, tmp_path, ["info", str(ds)], *expected)


def _lidar_arrays(boxes: bool = True) -> dict[str, np.ndarray]:
    """A one-view lidar.npz with two channels, eight azimuths, no returns and two boxes."""
    arrays = {
        "view1_elevations_deg": np.array([-10.0, 5.0]),
        "view1_azimuth_steps": np.array([8], dtype=np.int64),
        "view1_pose": np.eye(4),
        "view1_hits": np.zeros(2, dtype=np.uint8),
        "view1_range": np.zeros(0, dtype=np.uint16),
        "view1_object": np.zeros(0, dtype=np.int16),
    }
    if boxes:
        arrays |= {
            "view1_box_centres": np.array([[5.0, 0.0, 0.5], [9.0, 2.0, 0.5]]),
            "view1_box_sizes": np.array([[4.5, 1.8, 1.5], [4.0, 1.7, 1.4]]),
            "view1_box_yaws": np.array([0.0, 0.3]),
            "view1_box_classes": np.array(["car", "car"]),
            "view1_box_ids": np.array(["a", "b"]),
        }
    return arrays


def _set_array(key: str, value):
    return lambda a: a.__setitem__(key, value)


def _scaled_pose(a: dict) -> None:
    a["view1_pose"] = np.eye(4)
    a["view1_pose"][:3, :3] *= 1e6


LIDAR_CASES = {
    "box centres (b, 2)": (
        _set_array("view1_box_centres", np.zeros((2, 2))),
        "view1_box_centres: expected (2, 3) finite float64",
    ),  # fmt: skip
    "box ids as integers": (
        _set_array("view1_box_ids", np.arange(2)),
        "view1_box_ids: expected (2,) strings",
    ),  # fmt: skip
    "box yaws NaN": (
        _set_array("view1_box_yaws", np.array([0.0, np.nan])),
        "view1_box_yaws: expected (2,) finite float64",
    ),  # fmt: skip
    "negative box size": (
        _set_array("view1_box_sizes", -np.ones((2, 3))),
        "view1_box_sizes: expected sizes in (0, 100000]",
    ),  # fmt: skip
    "elevation NaN": (
        _set_array("view1_elevations_deg", np.array([np.nan, 5.0])),
        "view1_elevations_deg: expected ascending angles in [-90, 90]",
    ),  # fmt: skip
    "elevations unsorted": (
        _set_array("view1_elevations_deg", np.array([5.0, -10.0])),
        "view1_elevations_deg: expected ascending",
    ),  # fmt: skip
    "elevation 250°": (
        _set_array("view1_elevations_deg", np.array([-10.0, 250.0])),
        "view1_elevations_deg: expected ascending",
    ),  # fmt: skip
    "pose scaled 1e6": (_scaled_pose, "view1_pose: expected a rigid (4, 4) float64 transform"),
    "pose last row": (
        lambda a: a["view1_pose"].__setitem__(3, 5.0),
        "view1_pose: expected a rigid",
    ),  # fmt: skip
}


def test_a_well_formed_lidar_npz_passes():
    check_lidar_arrays(_lidar_arrays(), 1, 0, "lidar.npz")
    check_lidar_arrays(_lidar_arrays(boxes=False), 1, 0, "lidar.npz")


@pytest.mark.parametrize("case", sorted(LIDAR_CASES))
def test_lidar_npz_boxes_elevations_and_poses_are_checked(case):
    arrays = _lidar_arrays()
    edit, expected = LIDAR_CASES[case]
    edit(arrays)
    with pytest.raises(ValueError) as info:
        check_lidar_arrays(arrays, 1, 0, "pairs/e00000_s00/lidar.npz")
    message = str(info.value)
    assert message.startswith("pairs/e00000_s00/lidar.npz: ") and "\n" not in message
    assert expected in message, message


# --- scenarios that can never finish (finding 14, newcomer's impossible scenario) --------------


@pytest.mark.parametrize(
    "scenario, old, new, expected",
    [
        ("cad-v2x-lidar.toml", "dropout = 0.05", "dropout = 1.0",
         "lidar.dropout: invalid value: [lidar] dropout must be below 1"),
        ("cad-intersection.toml", "min_shared_area_m2 = 900.0", "min_shared_area_m2 = 100000",
         "observers.min_shared_area_m2: is 100000 m², more than one camera's footprint"),
    ],
)  # fmt: skip
def test_a_scenario_that_can_never_yield_a_pair_fails_at_once(tmp_path, capsys, scenario, old, new, expected):  # fmt: skip
    text = (ROOT / "scenarios" / scenario).read_text()
    assert old in text
    path = tmp_path / scenario
    path.write_text(text.replace(old, new, 1))
    shutil.copy(ROOT / "scenarios" / "cad-vtypes.add.xml", tmp_path)
    out = tmp_path / "out"
    _refused(capsys, tmp_path, ["generate", str(path), "--out", str(out), "--pairs", "2"], f"{path}: {expected}")  # fmt: skip
    assert not out.exists()


# --- Ctrl-C during import (finding 15) ---------------------------------------------------------

_SLOW_IMPORT = """
import sys, time
import cadsim.importers.box_dataset as box_dataset
write = box_dataset.write_record
def slow(*args, **kwargs):
    write(*args, **kwargs)
    print("wrote", flush=True)
    time.sleep(60)
box_dataset.write_record = slow
from cadsim.cli import main
sys.exit(main(["import", "v2x-seq", sys.argv[1], "--out", sys.argv[2]]))
"""


def test_ctrl_c_during_import_is_one_line_and_leaves_no_records(tmp_path):
    src = write_v2x_seq(tmp_path / "spd")
    out = tmp_path / "out"
    env = os.environ | {"PYTHONPATH": str(ROOT)}
    # the child gets the default Ctrl-C disposition: a library earlier in the suite may leave
    # SIGINT ignored in this process, and an ignored signal stays ignored across exec
    proc = subprocess.Popen(
        [sys.executable, "-c", _SLOW_IMPORT, str(src), str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=ROOT,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )  # fmt: skip
    assert "wrote" in proc.stdout.readline()  # a record is on disk (writers print concurrently)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130
    assert err.strip().splitlines() == [
        f"cadsim import: interrupted; no dataset was written to {out} (its partial records are "
        "removed). Run the same command again."
    ]
    assert not any(p.is_file() for p in out.rglob("*"))
    assert main(["import", "v2x-seq", str(src), "--out", str(out)]) == 0


def test_an_import_killed_outright_is_cleared_by_the_next_one(tmp_path, capsys):
    src = write_v2x_seq(tmp_path / "spd")
    out = tmp_path / "out"
    assert main(["import", "v2x-seq", str(src), "--out", str(out)]) == 0
    (out / "manifest.json").unlink()  # what kill -9 before the manifest leaves
    assert main(["import", "v2x-seq", str(src), "--out", str(out)]) == 0
    # a user's file beside such records is still never touched
    (out / "manifest.json").unlink()
    (out / "pairs" / "e00010_s00" / "notes.txt").write_text("mine")
    assert main(["import", "v2x-seq", str(src), "--out", str(out)]) == 2
    assert (out / "pairs" / "e00010_s00" / "notes.txt").read_text() == "mine"


# --- the newcomer's first hour: generate's closing line adds up ------------------------------


def test_generates_closing_line_explains_surplus_records_and_refused_candidates(tmp_path):
    from types import SimpleNamespace

    from cadsim.commands.generate import _summary

    (tmp_path / "manifest.json").write_text('{"views": 2}')
    result = SimpleNamespace(out=tmp_path, pairs=3, new_records=4, views=14,
                             candidates=7, seconds=2.0, checksum="c")  # fmt: skip
    line = _summary(result)
    assert "3 frame pairs (3 new, 1 more written by parallel episodes and dropped; " in line
    assert "14 views rendered in 2.0 s for 7 candidates, those with too few shared objects" in line


def test_a_failing_plugin_prints_its_one_line_and_no_task_dump(generated, tmp_path, capsys):
    argv = ["evaluate", str(generated), "--no-calibration", "--matchers", "plugin_fakes:nan_scores",
            "--runs", "1", "--workers", "1", "--no-progress", "--out", str(tmp_path / "r"),
            "--cache", str(tmp_path / "c")]  # fmt: skip
    assert main(argv) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert not [line for line in lines if "RunTask" in line or line.startswith("ERROR")], lines
    assert lines[-1].startswith("cadsim evaluate: error: 1 of 1 tasks failed")
    assert "'plugin_fakes:nan_scores' returned scores with 1 NaN" in lines[-1]


def test_sweep_noise_prints_f1_by_rate_and_fig4_has_an_f1_panel(tmp_path):
    import pandas as pd

    from eval.commands.sweep_noise import f1_summary
    from eval.report.figures import PANELS, write_fig4

    rows = [
        {"dataset": "MRC", "matcher": m, "noise_rate": r, "seed": s, "accuracy": 0.5,
         "balanced_accuracy": 0.5, "precision": 0.5, "recall": 0.5, "f1": f}
        for m, f0 in (("sm", 0.4), ("maximin", 0.6))
        for r in (0.0, 0.01)
        for s, f in ((0, f0), (1, f0 + 0.02))
    ]  # fmt: skip
    table = f1_summary(pd.DataFrame(rows))
    assert table.splitlines()[1] == "| Method | 0 | 0.01 |"
    assert "| Maximin | 61.0 ± 1.4 | 61.0 ± 1.4 |" in table
    assert ("f1", "F1") in PANELS
    pd.DataFrame(rows).to_csv(tmp_path / "noise_runs.csv", index=False)
    assert [p.name for p in write_fig4(tmp_path)] == ["fig4.png", "fig4.pdf"]


def test_result_files_record_paths_inside_the_working_directory_relatively(tmp_path, monkeypatch):
    from eval.core.result_files import recorded_path

    monkeypatch.chdir(tmp_path)
    (tmp_path / "data" / "cad-val").mkdir(parents=True)
    assert recorded_path(tmp_path / "data" / "cad-val") == "data/cad-val"
    assert recorded_path(str(tmp_path / "data" / "cad-val")) == "data/cad-val"
    assert recorded_path("data/cad-val") == "data/cad-val"
    assert recorded_path("/elsewhere/cad-val") == "/elsewhere/cad-val"
    assert recorded_path(None) is None
