"""The multi-agent study's own statistics: per (N, matcher, fusion, preset) the pooled-F1 gain of
a fusion over ``independent`` with its episode-bootstrap interval, two-sided p and Holm-adjusted
p over every gain of the table, the count error's interval and the time ratio to the smallest N
(:mod:`eval.protocol.pooled_bootstrap`, :mod:`eval.protocol.holm`). Imports ``eval/protocol/``
only."""

from __future__ import annotations

import numpy as np
import pandas as pd

from eval.protocol.holm import holm
from eval.protocol.multiway_metrics import count_errors
from eval.protocol.pooled_bootstrap import (
    F1_COUNTS,
    f1_of,
    group_sums,
    interval,
    mean_of,
    resamplable,
    summarise,
    weights_for,
)

BASELINE = "independent"
"""The fusion every gain is measured against."""
BY = ["n_agents", "matcher", "fusion", "preset"]
INTERVAL_COLUMNS = (
    "f1_gain",
    "gain_ci_low",
    "gain_ci_high",
    "gain_p",
    "gain_p_holm",
    "gain_family",
    "count_error_ci_low",
    "count_error_ci_high",
    "time_ratio",
    "time_ratio_ci_low",
    "time_ratio_ci_high",
)


def _with_terms(split: pd.DataFrame) -> pd.DataFrame:
    """``split`` with the per-row terms the bootstrap sums: the count error (0 where no object
    is present) and whether it counts, and a 1 per row (a snapshot of a run)."""
    errors = count_errors(split["objects_estimated"], split["objects_present"])
    return split.assign(
        _error=np.nan_to_num(errors, nan=0.0), _counted=np.isfinite(errors).astype(float), _one=1.0
    )


def _rows_of(groups: pd.DataFrame, **change) -> np.ndarray:
    """For each row of ``groups`` (the key columns :data:`BY`), the row index of the same key
    with ``change`` applied (-1: none)."""
    where = {tuple(key): i for i, key in enumerate(groups[BY].itertuples(index=False))}
    changed = groups[BY].assign(**change)
    return np.array([where.get(tuple(key), -1) for key in changed.itertuples(index=False)])


def _gain_index(groups: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """(rows with a gain, their baseline's row): every fused row whose ``independent`` ran."""
    base = _rows_of(groups, fusion=BASELINE)
    has = (base >= 0) & (groups["fusion"].to_numpy() != BASELINE)
    return np.flatnonzero(has), base[has]


def point_gains(split: pd.DataFrame) -> pd.DataFrame:
    """Per (N, matcher, fusion, preset): the pooled F1 minus ``independent``'s (point only)."""
    sums = group_sums(split, BY, F1_COUNTS)
    rows, base = _gain_index(sums.groups)
    f1 = f1_of(sums)
    gain = np.full(len(sums.groups), np.nan)
    gain[rows] = f1[rows] - f1[base]
    return sums.groups.assign(f1_gain=gain)


def gain_intervals(split: pd.DataFrame, resamples: int, seed: int, level: float) -> pd.DataFrame:
    """Per (N, matcher, fusion, preset) of ``split``: the pooled-F1 gain over ``independent``
    with its interval, two-sided p and Holm-adjusted p over every gain of the table; the count
    error's interval; the time ratio to the smallest N with its interval — every interval from
    the same episode-and-run resamples (:mod:`eval.protocol.pooled_bootstrap`)."""
    values = [*F1_COUNTS, "_error", "_counted", "seconds", "_one"]
    sums = group_sums(_with_terms(split), BY, values)
    groups, k = sums.groups, len(sums.groups)
    weights = weights_for(sums, resamples, seed)
    out = {name: np.full(k, np.nan) for name in INTERVAL_COLUMNS}

    f1, f1_resampled = f1_of(sums), f1_of(sums, weights)
    rows, base = _gain_index(groups)
    if len(rows):
        gain = summarise(
            f1[rows] - f1[base],
            f1_resampled[:, rows] - f1_resampled[:, base],
            level,
            len(sums.episodes),
        )
        out["f1_gain"][rows], out["gain_p"][rows] = gain.point, gain.p
        out["gain_ci_low"][rows], out["gain_ci_high"][rows] = gain.low, gain.high
        out["gain_p_holm"][rows] = holm(gain.p)
        out["gain_family"][rows] = np.count_nonzero(np.isfinite(gain.p))
    low_rows = _smallest_n_rows(groups)
    seconds = mean_of(sums, "seconds", "_one")
    out["time_ratio"] = _divide(seconds, seconds[low_rows])
    if not resamplable(sums):  # one episode: the points, and no interval
        return groups.assign(**out)
    errors = mean_of(sums, "_error", "_counted", weights)
    out["count_error_ci_low"], out["count_error_ci_high"] = interval(errors, level)
    seconds = mean_of(sums, "seconds", "_one", weights)
    ratio = _divide(seconds, seconds[:, low_rows])
    out["time_ratio_ci_low"], out["time_ratio_ci_high"] = interval(ratio, level)
    return groups.assign(**out)


def _smallest_n_rows(groups: pd.DataFrame) -> np.ndarray:
    """For each row of ``groups``, the row of the same matcher, fusion and preset at its
    smallest N."""
    smallest = groups.groupby(["matcher", "fusion", "preset"], sort=False)["n_agents"]
    return _rows_of(groups, n_agents=smallest.transform("min").to_numpy())


def _divide(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return num / den


__all__ = ["BASELINE", "BY", "INTERVAL_COLUMNS", "gain_intervals", "point_gains"]
