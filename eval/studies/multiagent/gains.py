"""The multi-agent study's own statistics: per (N, matcher, fusion, preset) the pooled-F1 gain of
a fusion over ``independent`` with its episode-bootstrap interval, two-sided p and Holm-adjusted
p over every gain of the table, the count error's interval and the time ratio to the smallest N
(:mod:`eval.protocol.pooled_bootstrap`, :mod:`eval.protocol.holm`); beside each gain its minimum
detectable difference (``gain_mdd``: 95 % two-sided, 80 % power) from the gain's cluster-robust
standard error over episodes, the pooled F1 linearised per snapshot and run (delta method,
:func:`linearised_f1`) and handed to the project's one MDD
(:func:`eval.protocol.detectable_difference.minimum_detectable_difference`). Imports
``eval/protocol/`` only."""

from __future__ import annotations

import numpy as np
import pandas as pd

from eval.protocol.detectable_difference import minimum_detectable_difference
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
    "gain_mdd",
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
        out["gain_mdd"] = gain_mdds(split, groups)
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


def linearised_f1(split: pd.DataFrame) -> np.ndarray:
    """Per row of ``split`` (one snapshot of one run), its linearised share of its group's
    (:data:`BY`) pooled F1 F = 2 ΣTP / (Σ declared + Σ true pairs): F + n · (2 tp − F · s) / Σ s
    with s = declared + true pairs and n the group's rows (delta method). Its mean over the group
    is F; its cluster-robust variance is F's delta-method variance. NaN in a group with no pair
    declared or true."""
    size = (split["declared"] + split["true_pairs"]).to_numpy(float)
    tp = split["true_positives"].to_numpy(float)
    keys = [split[c].to_numpy() for c in BY]  # by position: ``split`` may be any slice
    frame = pd.DataFrame({"tp": tp, "size": size})
    grouped = frame.groupby(keys, sort=False)
    total = grouped["size"].transform("sum").to_numpy()
    count = grouped["size"].transform("size").to_numpy(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        f1 = 2 * grouped["tp"].transform("sum").to_numpy() / total
        return np.where(total > 0, f1 + count * (2 * tp - f1 * size) / total, np.nan)


def gain_mdds(split: pd.DataFrame, groups: pd.DataFrame) -> np.ndarray:
    """Per row of ``groups`` (key columns :data:`BY`), the MDD of its pooled-F1 gain over
    ``independent``: :func:`minimum_detectable_difference` of the per-snapshot-and-run
    differences of :func:`linearised_f1` (fused − ``independent``, the same snapshot and run;
    their mean is the gain), clustered by episode. NaN for ``independent``'s rows, a row without
    its baseline, or fewer than two episodes."""
    item = ["n_agents", "matcher", "preset", "snapshot", "seed"]
    terms = split[[*BY, "snapshot", "seed", "episode"]].assign(_term=linearised_f1(split))
    base = terms.loc[terms["fusion"] == BASELINE, [*item, "_term"]]
    paired = terms[terms["fusion"] != BASELINE].merge(
        base, on=item, suffixes=("", "_base"), validate="many_to_one"
    )
    paired["_diff"] = paired["_term"] - paired["_term_base"]
    mdd = {}
    for key, rows in paired.groupby(BY, sort=False):
        mdd[key] = minimum_detectable_difference(
            rows["_diff"].to_numpy(), rows["episode"].to_numpy()
        )[0]
    return np.array([mdd.get(tuple(key), np.nan) for key in groups[BY].itertuples(index=False)])


def _smallest_n_rows(groups: pd.DataFrame) -> np.ndarray:
    """For each row of ``groups``, the row of the same matcher, fusion and preset at its
    smallest N."""
    smallest = groups.groupby(["matcher", "fusion", "preset"], sort=False)["n_agents"]
    return _rows_of(groups, n_agents=smallest.transform("min").to_numpy())


def _divide(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return num / den


__all__ = [
    "BASELINE",
    "BY",
    "INTERVAL_COLUMNS",
    "gain_intervals",
    "gain_mdds",
    "linearised_f1",
    "point_gains",
]
