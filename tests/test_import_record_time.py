"""Imported records' times (:mod:`cadsim.importers.record_time`): every importer counts a record's
time from its sequence's or scene's first frame, gives a timeless snapshot 0 and says so in the
manifest, so a localisation preset draws a prior of its own size on epoch-stamped and timeless
data alike; mixed units, non-finite or decreasing times and a span past a day are refused in one
line naming the file."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from format_fixtures import write_dair_v2x, write_opv2v, write_v2v4real, write_v2x_seq
from tumtraf_fixtures import write_tumtraf

from cadsim.cli import main
from cadsim.dataset import Dataset
from cadsim.importers import ImportFormatError
from cadsim.importers.box_sequence import ImportedFrame
from cadsim.importers.record_time import MAX_SPAN_S, relative_times
from cadsim.sensing.gnss_error import PRESETS, draw_error

EPOCH_S = 1_626_000_000.0
DRAWS = 200
DRAWN = [p for p, m in PRESETS.items() if m.given]  # every preset with a prior to draw


def _protocol(scenario: Path, start: float) -> None:
    """A ``cadsim`` block whose ``start_time`` is an epoch (a foreign clock, not cadsim's)."""
    block = {"episode": 0, "slot": 0, "sim_seed": 0, "start_time": start, "interval_s": 0.1}
    (scenario / "data_protocol.yaml").write_text(yaml.safe_dump({"cadsim": block}))


def _opv2v(root: Path, epoch: bool) -> list[str]:
    write_opv2v(root / "src", agents=(7, 3))
    if epoch:
        _protocol(root / "src" / "2021_08_22_21_41_24", EPOCH_S)
    return ["opv2v", str(root / "src"), "--no-prior"]


def _v2v4real(root: Path, epoch: bool) -> list[str]:
    write_v2v4real(root / "src")
    if epoch:
        _protocol(root / "src" / "testoutput_CAV_data_2022-03-15-09-54-40_1", EPOCH_S)
    return ["v2v4real", str(root / "src")]


def _dair(root: Path, epoch: bool) -> list[str]:
    src = write_dair_v2x(root / "src")
    if not epoch:  # the side data_info.json files are where DAIR-V2X keeps its times
        (src / "vehicle-side" / "data_info.json").unlink()
        (src / "infrastructure-side" / "data_info.json").unlink()
    return ["dair-v2x", str(src)]


def _v2x_seq(root: Path, epoch: bool) -> list[str]:
    assert epoch  # V2X-Seq orders a sequence's frames by their times: they are required
    return ["v2x-seq", str(write_v2x_seq(root / "src"))]


def _tumtraf(root: Path, epoch: bool) -> list[str]:
    return ["tumtraf-v2x", str(write_tumtraf(root / "src", timestamps=epoch))]


IMPORTS = {
    "opv2v": _opv2v,
    "v2v4real": _v2v4real,
    "dair-v2x": _dair,
    "v2x-seq": _v2x_seq,
    "tumtraf-v2x": _tumtraf,
}
CASES = [(name, epoch) for name in IMPORTS for epoch in (True, False) if epoch or name != "v2x-seq"]


def _imported(tmp_path: Path, name: str, epoch: bool) -> Path:
    out = tmp_path / "data"
    assert main(["import", *IMPORTS[name](tmp_path, epoch), "--out", str(out)]) == 0
    return out


def _median_error(pairs, preset: str) -> tuple[float, float]:
    """(median drawn position error of the first vehicle view over DRAWS runs, the median the
    preset's own model gives for the same elapsed times with independent seeds), metres."""
    model = PRESETS[preset]
    drawn, own = [], []
    for seed in range(DRAWS):
        pair = pairs[seed % len(pairs)]
        error = pair.localise_preset(preset, seed=seed).pose_errors()[0]
        drawn.append(math.hypot(error.dx, error.dy))
        ref = draw_error(model, 10_000 + seed, pair.observer_ids[0], pair.time, 20_000 + seed)
        own.append(math.hypot(ref.dx, ref.dy))
    return float(np.median(drawn)), float(np.median(own))


@pytest.mark.parametrize(("name", "epoch"), CASES)
def test_every_preset_draws_a_prior_of_its_own_size(tmp_path, name, epoch):
    data = _imported(tmp_path, name, epoch)
    pairs = list(Dataset(data, verify=True))
    assert all(p.observer_kinds[0] == "vehicle" for p in pairs)
    assert min(p.time for p in pairs) == 0.0 and max(p.time for p in pairs) < 1.0
    note = json.loads((data / "manifest.json").read_text())["source"]["time"]
    assert (note["relative"] if epoch else note["missing"]) == len(pairs)
    if epoch:
        assert min(p.record["meta"]["source_time_s"] for p in pairs) >= EPOCH_S
    for preset in DRAWN:
        drawn, own = _median_error(pairs, preset)
        if preset == "exact":
            assert drawn == own == 0.0
        else:
            assert drawn > 0 and own * 0.7 <= drawn <= own * 1.3, (preset, drawn, own)


@pytest.mark.parametrize(("name", "epoch"), CASES)
def test_imported_records_evaluate_under_gnss_urban_and_exact(tmp_path, name, epoch):
    data = _imported(tmp_path, name, epoch)
    for preset in ("gnss-urban", "exact"):
        args = ["evaluate", str(data), "--matchers", "pose", "--localisation", preset]
        args += ["--no-calibration", "--runs", "1", "--workers", "1", "--no-progress"]
        args += ["--cache", str(tmp_path / "cache"), "--out", str(tmp_path / preset)]
        assert main(args) == 0
        assert (tmp_path / preset / "table1.csv").exists()


def test_cadsim_own_clock_survives_the_round_trip(tmp_path):
    """``cadsim export opv2v``'s start_time is cadsim's simulation clock: kept as it is."""
    write_opv2v(tmp_path / "src", agents=(7, 3))
    _protocol(tmp_path / "src" / "2021_08_22_21_41_24", 12.5)
    out = tmp_path / "data"
    assert main(["import", "opv2v", str(tmp_path / "src"), "--no-prior", "--out", str(out)]) == 0
    times = [p.time for p in Dataset(out)]
    np.testing.assert_allclose(times, [12.5, 12.6, 12.7])


def _frames(*times) -> list[ImportedFrame]:
    return [ImportedFrame(t, ()) for t in times]


@pytest.mark.parametrize(
    ("times", "ordered", "message"),
    [
        ((EPOCH_S, EPOCH_S * 1e6), False, "mix units"),  # seconds beside microseconds
        ((EPOCH_S, 1.7e9), True, f"within {MAX_SPAN_S:.0f} s"),  # two years apart
        ((5.0, float("nan")), True, "not finite"),
        ((5.0, float("inf")), False, "not finite"),
        ((5.0, 6.0, 5.5), True, "not after frame 1's"),
        ((5.0, None), True, "1 of 2 frames have no time"),
    ],
)
def test_bad_times_are_refused_in_one_line_naming_the_file(times, ordered, message):
    with pytest.raises(ImportFormatError, match=message) as info:
        relative_times(_frames(*times), "side/data_info.json", "sequence '0010'", ordered=ordered)
    text = str(info.value)
    assert text.startswith("side/data_info.json: sequence '0010': ") and "\n" not in text


def test_a_v2x_seq_sequence_mixing_seconds_and_microseconds_is_refused(tmp_path, capsys):
    src = write_v2x_seq(tmp_path / "src")
    info = src / "vehicle-side" / "data_info.json"
    entries = json.loads(info.read_text())
    entries[1]["pointcloud_timestamp"] = str(int(EPOCH_S))  # seconds where µs are expected
    info.write_text(json.dumps(entries))
    assert main(["import", "v2x-seq", str(src), "--out", str(tmp_path / "d")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(info) in err[0] and "mix units" in err[0], err
    assert not (tmp_path / "d" / "manifest.json").exists()


def test_a_timeless_sequence_steps_by_its_interval():
    out = relative_times(_frames(None, None, None), "f", "s", ordered=True, interval_s=0.2)
    assert [f.time for f in out] == pytest.approx([0.0, 0.2, 0.4])
    assert [f.time for f in relative_times(_frames(None, None), "f", "s", ordered=False)] == [0, 0]


def test_v2x_seq_without_timestamps_is_refused_in_one_line(tmp_path, capsys):
    """V2X-Seq orders a sequence's frames by their point-cloud times: without them there is no
    order to keep, so the import refuses (every other importer gives such records 0)."""
    src = write_v2x_seq(tmp_path / "src")
    info = src / "vehicle-side" / "data_info.json"
    entries = json.loads(info.read_text())
    info.write_text(json.dumps([{k: v for k, v in e.items() if k != "pointcloud_timestamp"} for e in entries]))  # fmt: skip
    assert main(["import", "v2x-seq", str(src), "--out", str(tmp_path / "d")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(info) in err[0] and "pointcloud_timestamp: missing" in err[0], err


def test_a_record_imported_without_a_time_names_itself_under_a_walking_preset(tmp_path):
    """A dataset imported before every record had a time (``time: null``): presets without a
    walk draw as at 0 s; one with a walk refuses, naming the record and what to do."""
    data = _imported(tmp_path, "dair-v2x", False)
    record = Path(Dataset(data)[0].path) / "record.json"
    doc = json.loads(record.read_text())
    doc["time"] = None
    record.write_text(json.dumps(doc))
    pair = Dataset(data)[0]
    assert pair.localise_preset("exact", seed=0).prior() is not None
    assert pair.localise_preset("rtk", seed=0).prior() is not None
    with pytest.raises(
        ValueError, match=r"e00000_s00/record.json: time: null.*import the source again"
    ):
        pair.localise_preset("gnss-urban", seed=0).prior()
