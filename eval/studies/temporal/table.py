"""The temporal table's layout and names: its dataset labels, scenario files, rows (the oracle's,
the windows W = 1 and W = 10 compared), columns, file names and which (method, preset) has no
number. Data only; imports nothing from the other temporal study modules."""

from __future__ import annotations

from eval.core.abstention import cannot_run

LABEL = "CAD-V2X-Seq"
SCENARIO = "scenarios/cad-v2x-seq.toml"
ORACLE_ROW = "oracle"
SUCCESS_BOUNDS = (1.0, 2.0)  # metres, degrees
LONG = 10
SHORT = 1
COLUMNS = (
    "method",
    "window",
    "preset",
    "tau",
    "val_f1",
    "params",
    "f1_pooled",
    "f1_pooled_low",
    "f1_pooled_high",
    "f1_mean",
    "f1_low",
    "f1_high",
    "success_1m_2deg",
    "success_low",
    "success_high",
    "share_of_oracle",
    "partner_changes_per_100",
    "partner_changes_low",
    "partner_changes_high",
    "idsw_per_100",
    "frames_to_first",
    "never_matched",
    "hota",
    "deta",
    "assa",
    "oracle_hota",
    "oracle_assa",
    "assa_share_of_oracle",
    "frames",
    "sequences",
    "episodes",
    "ms_per_frame",
)
GAIN_COLUMNS = (
    "preset",
    "method",
    "parameters",
    "f1_pooled_w10",
    "f1_pooled_w1",
    "pooled_diff",
    "pooled_low",
    "pooled_high",
    "pooled_mdd",
    "f1_w10",
    "f1_w1",
    "diff",
    "ci_low",
    "ci_high",
    "mdd",
    "episodes",
    "clusters",
)
COUNT_COLUMNS = ("never_matched", "frames", "sequences", "episodes")  # integers, or no number
TABLE, GAIN = "table_temporal", "table_temporal_gain"
TUNING_FILE = "temporal/tuning.csv"
CONTINUITY_FILE = "temporal/continuity.csv"
LIDAR_TABLE, LIDAR_LABEL = "table_temporal_lidar", "CAD-V2X-Seq-LiDAR"
LIDAR_SCENARIO = "scenarios/cad-v2x-seq-lidar.toml"


def folder_of(name: str) -> str:
    """The folder of table ``name``'s side files: ``temporal`` for the camera table,
    ``temporal_lidar`` for ``table_temporal_lidar``."""
    return "temporal" if name == TABLE else name.removeprefix("table_")


CONTINUITY_COLUMNS = (
    "preset", "band", "low_m_s", "high_m_s", "kept", "links", "continuity",
    "continuity_low", "continuity_high",
)  # fmt: skip
TUNING_COLUMNS = ("preset", "window", "matcher", "config", "params", "val_f1", "tau", "chosen")

TUNED, FIXED = "tuned per W", "fixed: W = 10's"


def abstains(method: str, preset: str) -> bool:
    """Whether temporal method ``method`` cannot run under ``preset`` (it requires the prior and
    the preset gives none, :func:`eval.core.abstention.cannot_run`)."""
    return cannot_run(method, preset, temporal=True)
