"""Where two matchers' curves in the regime sweep cross: the non-covisible share at which
maximin's advantage over a rival appears or vanishes.

For each dataset, rival (MOS, RRWHM) and metric (F1, balanced accuracy), d(share) = maximin − rival
is taken at the sweep's achieved shares (sorted ascending) and every sign change between two
neighbouring levels gives one row with the linearly interpolated share where d = 0 (a level where
d is exactly 0 is a crossing itself). No sign change: one row with an empty ``crossing_share``.
``direction`` says which way d changes as the share grows: ``a_gains`` (maximin ahead above the
crossing) or ``a_loses``.

Each crossing carries its uncertainty (:mod:`eval.protocol.episode_draw_bootstrap`: episodes and runs —
thinning draws — resampled together, the same resample at every level). In every resample the
curves are rebuilt, and the crossing of the same direction nearest to the point estimate is taken;
a resample without one contributes "no crossing" (+∞). ``share_ci_low``/``share_ci_high`` is the
95 % percentile interval of those shares (``share_ci_high`` empty when the interval reaches "no
crossing"), ``resamples_crossing`` the share of resamples with a crossing of that direction, and
``significant`` is true when the interval excludes "no crossing": ≥ 97.5 % of resamples cross in
that direction, *and* the curves are apart on both sides — at some level below the crossing and
some level above it the 95 % interval of d excludes 0 with the sign the direction implies (two
curves that are the same within their noise cross in almost every resample, yet never swap
order). A dataset with no crossing in its point estimate gets one row with ``significant`` false.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from eval.protocol import episode_draw_bootstrap as boot

COLUMNS = (
    "dataset",
    "matcher_a",
    "matcher_b",
    "metric",
    "crossing_share",
    "share_ci_low",
    "share_ci_high",
    "direction",
    "resamples_crossing",
    "significant",
)
PAIRS = (("maximin", "mos"), ("maximin", "rrwhm"))
METRICS = (("f1", "f1_mean"), ("balanced_accuracy", "balanced_accuracy_mean"))


def crossings(share: np.ndarray, diff: np.ndarray) -> list[tuple[float, str]]:
    """(share, direction) where the piecewise-linear d(share) crosses 0; `share` ascending."""
    share, diff = np.asarray(share, dtype=float), np.asarray(diff, dtype=float)
    out = []
    sign = np.sign(diff)
    for k in range(len(diff) - 1):
        a, b = diff[k], diff[k + 1]
        if sign[k] == 0 or sign[k] == sign[k + 1] or sign[k + 1] == 0:
            continue
        at = share[k] + (share[k + 1] - share[k]) * a / (a - b)
        out.append((float(at), "a_gains" if b > a else "a_loses"))
    for k in np.flatnonzero(sign == 0):
        if 0 < k < len(diff) - 1 and sign[k - 1] * sign[k + 1] < 0:
            out.append((float(share[k]), "a_gains" if diff[k + 1] > 0 else "a_loses"))
    return sorted(out)


def resampled_crossings(
    share: np.ndarray, diff: np.ndarray, at: float, direction: str
) -> np.ndarray:
    """Per resample (rows of `share` and `diff`, (R, K), shares ascending along K): the crossing
    of `direction` nearest to `at`, +inf where that resample has none."""
    a, b = diff[:, :-1], diff[:, 1:]
    s0, s1 = share[:, :-1], share[:, 1:]
    with np.errstate(divide="ignore", invalid="ignore"):
        where = s0 + (s1 - s0) * a / (a - b)
    found = (np.sign(a) * np.sign(b) < 0) & ((b > a) == (direction == "a_gains"))
    # an interior level where d is exactly 0 between opposite signs is a crossing itself
    mid, before, after = diff[:, 1:-1], diff[:, :-2], diff[:, 2:]
    zero = (mid == 0) & (before * after < 0) & ((after > 0) == (direction == "a_gains"))
    candidates = np.concatenate(
        [np.where(found, where, np.inf), np.where(zero, share[:, 1:-1], np.inf)], axis=1
    )
    distance = np.abs(candidates - at)
    nearest = np.argmin(distance, axis=1)
    return candidates[np.arange(len(candidates)), nearest]


def _apart_on_both_sides(
    share: np.ndarray, d_low: np.ndarray, d_high: np.ndarray, at: float, direction: str
) -> bool:
    """Some level below share `at` and some above it have a d-interval that excludes 0 with the
    signs `direction` implies (a_gains: negative below, positive above)."""
    below, above = share < at, share > at
    negative, positive = d_high < 0, d_low > 0
    if direction == "a_gains":
        return bool((below & negative).any() and (above & positive).any())
    return bool((below & positive).any() and (above & negative).any())


def find_crossovers(per_pair: pd.DataFrame, seed: int = boot.SEED) -> pd.DataFrame:
    """Rows of ``crossovers.csv`` from the regime sweep's per-(level, matcher, pair, run) metrics
    (``dataset``, ``keep``, ``matcher``, ``pair``, ``episode``, ``seed``, ``n1``, ``n2``,
    ``n_gt`` and the metrics of :data:`METRICS`)."""
    rows = []
    for dataset, group in per_pair.groupby("dataset", sort=False):
        objects = group.drop_duplicates(["keep", "pair", "seed"])
        objects = objects.assign(
            _all=(objects["n1"] + objects["n2"]).astype(float),
            _non=(objects["n1"] + objects["n2"] - 2 * objects["n_gt"]).astype(float),
        )
        axes, weights = boot.axes_of(group), boot.weights_for(group, seed)
        all_table = boot.table(objects, "_all", axes=axes)
        non = boot.table(objects, "_non", axes=axes).sums
        share = non.sum(axis=(1, 2)) / all_table.sums.sum(axis=(1, 2))  # keep ascending
        with np.errstate(invalid="ignore"):
            share_r = boot.pooled(non, weights) / boot.pooled(all_table.sums, weights)
        for a, b in PAIRS:
            if not {a, b} <= set(group["matcher"]):
                continue
            rows_a, rows_b = group[group["matcher"] == a], group[group["matcher"] == b]
            for metric, _ in METRICS:
                _, point_a, res_a = boot.means(rows_a, metric, weights, axes)
                _, point_b, res_b = boot.means(rows_b, metric, weights, axes)
                found = crossings(share, point_a - point_b)
                base = {"dataset": dataset, "matcher_a": a, "matcher_b": b, "metric": metric}
                if not found:
                    rows.append(base | {"direction": "", "significant": False})
                d_low, d_high = boot.interval(res_a - res_b)
                for at, direction in found:
                    shares = resampled_crossings(share_r, res_a - res_b, at, direction)
                    low, high = boot.interval(shares)
                    apart = _apart_on_both_sides(share, d_low, d_high, at, direction)
                    rows.append(
                        base
                        | {
                            "crossing_share": at,
                            "share_ci_low": low if np.isfinite(low) else np.nan,
                            "share_ci_high": high if np.isfinite(high) else np.nan,
                            "direction": direction,
                            "resamples_crossing": float(np.isfinite(shares).mean()),
                            "significant": bool(np.isfinite(high)) and apart,
                        }
                    )
    return pd.DataFrame(rows, columns=list(COLUMNS))
