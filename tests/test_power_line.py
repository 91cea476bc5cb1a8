"""The power line of a two-view table (eval/engine/power.py): interval half-widths against the
±5 / ±8 point goals, read off planted tables."""

from __future__ import annotations

import pandas as pd

from eval.engine.power import power_line


def _write(folder, rows, intervals):
    pd.DataFrame(rows, columns=["matcher", "preset", "f1_low", "f1_high"]).to_csv(folder / "table_t.csv", index=False)  # fmt: skip
    pd.DataFrame(intervals, columns=["preset", "ci_low", "ci_high"]).to_csv(folder / "table_t_intervals.csv", index=False)  # fmt: skip


def test_half_widths_and_the_presets_wider_than_the_goal(tmp_path):
    rows = [
        ("a", "exact", 0.80, 0.90),  # ±5
        ("b", "exact", 0.50, 0.70),  # ±10: the widest
        ("oracle", "exact", 0.0, 1.0),  # a reference row never counts
        ("a", "denied", 0.60, 0.72),  # ±6
    ]
    _write(tmp_path, rows, [("exact", -0.02, 0.04), ("denied", -0.10, 0.02)])
    line = power_line(tmp_path, "t")
    assert "`exact` 3.0, `denied` 6.0 points" in line
    assert "wider than ±5 in `denied`;" in line
    assert "widest row ±10.0 (`b`, `exact`), 1 of 3 rows wider than ±8" in line


def test_everything_within_and_missing_files(tmp_path):
    _write(tmp_path, [("a", "rtk", 0.9, 0.95)], [("rtk", 0.0, 0.02)])
    assert "— all within;" in power_line(tmp_path, "t")
    assert power_line(tmp_path, "absent") is None
