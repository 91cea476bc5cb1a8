"""What accumulation buys in the temporal study: per preset the method with the best validation
F1 at W = 10 (:func:`best_long`), its test F1 at W = 10 minus at W = 1, pooled (paired
episode-level bootstrap) and per frame (paired per frame, episode-level t-interval), with W = 1
tuned on its own (:data:`TUNED`) or run at W = 10's parameters and τ (:data:`FIXED`).

Beside each interval the minimum detectable difference at 95 % confidence and 80 % power:
``mdd`` of the per-frame difference from its episode-level standard error
(:func:`eval.protocol.detectable_difference.minimum_detectable_difference`), ``pooled_mdd`` of the
pooled difference from its bootstrap interval under the normal approximation,
(z_0.975 + z_0.80) · (high − low) / (2 z_0.975); ``clusters``: the episodes both rest on."""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.stats import norm

from eval.protocol import pooled_bootstrap
from eval.protocol.cluster_interval import t_interval
from eval.protocol.detectable_difference import LEVEL, POWER, minimum_detectable_difference
from eval.studies.temporal.scores import pooled_sums
from eval.studies.temporal.table import FIXED, LONG, ORACLE_ROW, SHORT, TUNED, abstains


def best_long(table: pd.DataFrame, preset: str) -> str | None:
    """The method with the best validation F1 at W = 10 under ``preset`` among those that can run
    there (None: none)."""
    rows = table[(table["preset"] == preset) & (table["window"] == LONG)]
    rows = rows[rows["method"] != ORACLE_ROW]
    rows = rows[[not abstains(m, preset) for m in rows["method"]]]
    if not len(rows):
        return None
    return str(rows.sort_values(["val_f1", "method"], ascending=[False, True]).iloc[0]["method"])


def gain_rows(preset: str, rows: list[dict], frames_by: dict) -> list[dict]:
    """The preset's gain rows for the best method at W = 10: W = 10 against W = 1 each with
    its own tuned parameters and τ (``parameters`` = :data:`TUNED`), and against W = 1 run with
    W = 10's parameters and τ (:data:`FIXED`: the window's effect alone)."""
    table = pd.DataFrame([r for r in rows if r["preset"] == preset])
    method = best_long(table, preset)
    if method is None or (method, SHORT) not in frames_by:
        return []
    out = [_gain(preset, method, TUNED, frames_by[(method, LONG)], frames_by[(method, SHORT)])]
    if (method, "fixed") in frames_by:
        fixed = frames_by[(method, "fixed")]
        out.append(_gain(preset, method, FIXED, frames_by[(method, LONG)], fixed))
    return out


def bootstrap_mdd(low: float, high: float, level: float = LEVEL, power: float = POWER) -> float:
    """The MDD of a difference whose bootstrap interval at ``level`` is [low, high], under the
    normal approximation: its standard error (high − low) / (2 z_{(1+level)/2}) times
    z_{(1+level)/2} + z_power (NaN without an interval)."""
    if not (np.isfinite(low) and np.isfinite(high)):
        return float("nan")
    z = norm.ppf(0.5 + level / 2)
    return float((z + norm.ppf(power)) * (high - low) / (2 * z))


def _gain(preset: str, method: str, parameters: str, long, short) -> dict:
    diff = long["f1"].to_numpy(float) - short["f1"].to_numpy(float)
    mean, low, high, episodes = t_interval(diff, long["episode"].to_numpy(), bounds=(-1.0, 1.0))
    mdd, _ = minimum_detectable_difference(diff, long["episode"].to_numpy())
    pooled = pooled_bootstrap.f1_difference(pooled_sums(long), pooled_sums(short))
    return {
        "preset": preset,
        "method": method,
        "parameters": parameters,
        "f1_pooled_w10": float(pooled_bootstrap.f1_of(pooled_sums(long))[0]),
        "f1_pooled_w1": float(pooled_bootstrap.f1_of(pooled_sums(short))[0]),
        "pooled_diff": float(pooled.point[0]),
        "pooled_low": float(pooled.low[0]),
        "pooled_high": float(pooled.high[0]),
        "pooled_mdd": bootstrap_mdd(float(pooled.low[0]), float(pooled.high[0])),
        "f1_w10": float(long["f1"].mean()),
        "f1_w1": float(short["f1"].mean()),
        "diff": mean,
        "ci_low": low,
        "ci_high": high,
        "mdd": mdd,
        "episodes": episodes,
        "clusters": episodes,
    }
