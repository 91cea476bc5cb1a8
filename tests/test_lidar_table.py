"""The LiDAR table's report part: nothing without the table; its camera-vs-LiDAR lines come from
the paired rows of ``table_v2x_sensors.csv`` (tests/test_v2x_sensors.py), never from the two
tables' marginal intervals."""

from __future__ import annotations

import pandas as pd

from eval.studies.v2x.lidar import NAME, readme_part
from eval.studies.v2x.sensors import sensor_lines


def test_marginal_tables_alone_state_no_sensor_verdict(tmp_path):
    columns = ["preset", "matcher", "f1_mean", "f1_low", "f1_high"]
    pd.DataFrame([("gnss-urban", "pose_refine", 0.90, 0.85, 0.95)], columns=columns).to_csv(
        tmp_path / f"table_{NAME}.csv", index=False
    )
    pd.DataFrame([("gnss-urban", "pose_refine", 0.60, 0.50, 0.70)], columns=columns).to_csv(
        tmp_path / "table_v2x.csv", index=False
    )
    assert sensor_lines(tmp_path) == []


def test_nothing_is_reported_without_the_table(tmp_path):
    assert readme_part(tmp_path, "results") == [] and sensor_lines(tmp_path) == []
