"""The LiDAR table's report lines: which sensor favours which matcher family, stated only where
the two intervals do not overlap; nothing without the table."""

from __future__ import annotations

import pandas as pd

from eval.studies.v2x_lidar import NAME, readme_part, sensor_lines


def _table(rows):
    return pd.DataFrame(rows, columns=["preset", "matcher", "f1_mean", "f1_low", "f1_high"])


def test_a_sensor_favours_a_family_only_with_disjoint_intervals(tmp_path):
    _table([
        ("gnss-urban", "pose_refine", 0.90, 0.85, 0.95),  # reads the prior
        ("gnss-urban", "consistency", 0.50, 0.30, 0.70),
        ("gnss-urban", "oracle", None, None, None),
    ]).to_csv(tmp_path / f"table_{NAME}.csv", index=False)  # fmt: skip
    _table([
        ("gnss-urban", "pose_refine", 0.60, 0.50, 0.70),
        ("gnss-urban", "consistency", 0.55, 0.40, 0.75),
    ]).to_csv(tmp_path / "table_v2x.csv", index=False)  # fmt: skip
    lines = sensor_lines(tmp_path)
    assert len(lines) == 2
    prior, no_prior = lines
    assert "with the prior" in prior and prior.endswith("LiDAR boxes favour it")
    assert "without a prior" in no_prior and no_prior.endswith("no sensor is shown to favour it")


def test_nothing_is_reported_without_the_table(tmp_path):
    assert readme_part(tmp_path, "results") == [] and sensor_lines(tmp_path) == []
