"""LiDAR sequences: the ``cad-v2x-seq-lidar`` scenario (``[sequence]`` with ``sensor = "lidar"``)
loads, ``sensor = "both"`` with a ``[sequence]`` is still refused in one line, and the temporal
study's LiDAR entry point writes its own files beside the camera table's; a sequence dataset's
regime card states the own tracker's continuity."""

from __future__ import annotations

import shutil
from pathlib import Path

import pandas as pd
import pytest
import test_sequences as seqs

from cadsim.scenario import ScenarioError, load_scenario
from eval.studies.temporal import evaluation as temporal

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "cad-v2x-seq-lidar.toml"


def test_the_lidar_sequence_scenario_loads():
    s = load_scenario(SCENARIO)
    camera = load_scenario(SCENARIO.parent / "cad-v2x-seq.toml")
    assert s.sensor == "lidar" and s.lidar["preset"] == "hdl-64e"
    assert s.sequence == camera.sequence
    assert s.seed == camera.seed  # the same test / validation seeds as the camera table


def test_both_sensors_with_a_sequence_is_a_one_line_error(tmp_path):
    shutil.copy(SCENARIO.parent / "cad-vtypes.add.xml", tmp_path / "cad-vtypes.add.xml")
    path = tmp_path / "both-seq.toml"
    path.write_text(SCENARIO.read_text().replace('sensor = "lidar"', 'sensor = "both"', 1))
    with pytest.raises(ScenarioError, match=r'sequence.*sensor = "both"') as err:
        load_scenario(path)
    assert "\n" not in str(err.value) and "both-seq.toml" in str(err.value)


def test_the_lidar_study_writes_its_own_files(tmp_path):
    scenario = seqs._scenario(frames=3)
    seqs._generate(tmp_path / "test", scenario, pairs=2)
    seqs._generate(tmp_path / "val", scenario, pairs=2, seed=99)
    out = tmp_path / "out"
    temporal.evaluate_temporal_lidar(
        tmp_path / "test", tmp_path / "val", out, (("trajectory_pose", (1, 10)),), ("denied",),
        tune=False,
    )  # fmt: skip
    assert (out / "table_temporal_lidar.csv").is_file()
    assert not (out / "table_temporal.csv").exists()  # the camera table is left alone
    md = (out / "table_temporal_lidar.md").read_text()
    assert md.startswith(f"**{temporal.LIDAR_LABEL}**")
    gain = pd.read_csv(out / "table_temporal_lidar_gain.csv")
    assert list(gain["parameters"]) == [temporal.TUNED, temporal.FIXED]
    for side in ("per_frame.csv", "continuity.csv", "tuning.csv"):
        assert (out / "temporal_lidar" / side).is_file(), side
    part = temporal.readme_part_lidar(out, "results")
    assert part[0] == "### The temporal table on LiDAR boxes"
    assert "results/table_temporal_lidar.md" in "\n".join(part)
    assert temporal.readme_part(out, "results") == []  # no camera table there


def test_the_regime_card_states_the_own_trackers_continuity_of_a_sequence_dataset(tmp_path):
    from eval.studies.table1.regime_cards import continuity_text, regime_of

    seqs._generate(tmp_path / "seq", seqs._scenario(frames=3), pairs=2)
    text = continuity_text(tmp_path / "seq")
    assert [part.split()[0] for part in text.split(", ")] == ["static", "slow", "fast"]
    assert regime_of(tmp_path / "seq")["continuity"] == text
