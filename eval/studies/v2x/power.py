"""The V2X study's power analysis (:mod:`eval.engine.power_analysis`): per preset, the 95 %
half-width of the best-against-runner-up F1 difference of the camera, box-only and LiDAR tables
(the two named by ``table_<name>_intervals.csv``), measured on the per-pair metrics, one pair
per episode."""

from __future__ import annotations

from eval.engine.power_analysis import PowerCheck, best_vs_runner_up

TABLES = (
    ("camera", "v2x", "v2x/metrics_per_pair.csv"),
    ("box-only", "v2x_boxes", "v2x_boxes/metrics_per_pair.csv"),
    ("LiDAR", "v2x_lidar", "v2x_lidar/metrics_per_pair.csv"),
)
"""(comparison label, table name, per-pair file) of every table covered."""

CHECKS = tuple(
    PowerCheck(
        f"{label}: best − runner-up half-width",
        lambda results, label=label, table=table, per_pair=per_pair: best_vs_runner_up(
            results, "v2x", label, table, per_pair
        ),
    )
    for label, table, per_pair in TABLES
)
