"""Is the oracle a ceiling? Each matcher's pose success against the oracle's on the same frames,
as a paired difference with an episode-level interval.

The oracle is the same robust planar fit of every true pair (:mod:`eval.core.pose_metrics`). On
one frame a matcher can still beat it: a wrong pair that happens to lie consistently with the
right ones lengthens the lever arm, a physical object the ground truth does not pair (a parked
trailer both LiDARs see is non-target clutter) adds a point, and an exact two-match fit can land
nearer the truth than the fit of all (noisy) true pairs. No fit rules that out on a finite
sample, so the ceiling is stated as what a sample can show: per matcher, the mean over pairs of
(matcher's success − oracle's success) at success@(1 m, 2°), each pair's success averaged over
the matcher's runs, with the cluster-robust t-interval over episodes
(:func:`eval.protocol.cluster_interval.t_interval`). A matcher is ``above`` the oracle only when
the whole interval lies above 0.
"""

from __future__ import annotations

import pandas as pd

from eval.protocol.cluster_interval import t_interval

RTE_BOUND_M, RRE_BOUND_DEG = 1.0, 2.0
"""success@(1 m, 2°): RTE ≤ 1 m and RRE ≤ 2°; a failed fit (NaN) is unsuccessful."""
COLUMNS = (
    "matcher",
    "success",
    "oracle_success",
    "difference",
    "ci_low",
    "ci_high",
    "clusters",
    "verdict",
)


def _success(rte: pd.Series, rre: pd.Series) -> pd.Series:
    return ((rte <= RTE_BOUND_M) & (rre <= RRE_BOUND_DEG)).astype(float)


def oracle_ceiling(per_pair: pd.DataFrame, split: str = "test") -> pd.DataFrame:
    """One row per matcher of ``per_pair`` (a study's ``metrics_per_pair.csv``: ``matcher``,
    ``split``, ``pair``, ``episode``, ``rte_m``, ``rre_deg``, ``oracle_rte_m``,
    ``oracle_rre_deg``) on ``split``: success rates, their paired difference with its 95 %
    episode interval, the number of episodes, and ``verdict`` — ``above`` (interval above 0),
    ``at or below`` (point value ≤ 0) or ``above, within noise`` (point value > 0, interval
    reaching 0)."""
    rows = per_pair[per_pair["split"] == split] if "split" in per_pair else per_pair
    rows = rows.assign(
        s=_success(rows["rte_m"], rows["rre_deg"]),
        o=_success(rows["oracle_rte_m"], rows["oracle_rre_deg"]),
    )
    out = []
    for matcher, group in rows.groupby("matcher", sort=True):
        frames = group.groupby("pair", sort=True).agg(s=("s", "mean"), o=("o", "mean"), e=("episode", "first"))  # fmt: skip
        diff = frames["s"].to_numpy() - frames["o"].to_numpy()
        mean, low, high, clusters = t_interval(diff, frames["e"].to_numpy(), bounds=(-1.0, 1.0))
        verdict = "above" if low > 0 else "at or below" if mean <= 0 else "above, within noise"
        out.append((matcher, frames["s"].mean(), frames["o"].mean(), mean, low, high, clusters, verdict))  # fmt: skip
    return pd.DataFrame(out, columns=list(COLUMNS))


__all__ = ["COLUMNS", "oracle_ceiling"]
