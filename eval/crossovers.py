"""Where two matchers' curves in the regime sweep cross: the non-covisible share at which
maximin's advantage over a rival appears or vanishes.

For each dataset, rival (MOS, RRWHM) and metric (F1, balanced accuracy), d(share) = maximin − rival
is taken at the sweep's achieved shares (sorted ascending) and every sign change between two
neighbouring levels gives one row with the linearly interpolated share where d = 0 (a level where
d is exactly 0 is a crossing itself). No sign change: one row with an empty ``crossing_share``.
``direction`` says which way d changes as the share grows: ``a_gains`` (maximin ahead above the
crossing) or ``a_loses``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

COLUMNS = ("dataset", "matcher_a", "matcher_b", "metric", "crossing_share", "direction")
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


def find_crossovers(sweep: pd.DataFrame) -> pd.DataFrame:
    """Rows of ``crossovers.csv`` from the rows of ``regime_sweep.csv``."""
    rows = []
    for dataset, group in sweep.groupby("dataset", sort=False):
        for a, b in PAIRS:
            ca, cb = group[group["matcher"] == a], group[group["matcher"] == b]
            if ca.empty or cb.empty:
                continue
            joined = ca.merge(cb, on="keep", suffixes=("", "_b")).sort_values("share")
            for metric, column in METRICS:
                found = crossings(joined["share"], joined[column] - joined[f"{column}_b"])
                base = {"dataset": dataset, "matcher_a": a, "matcher_b": b, "metric": metric}
                if not found:
                    rows.append(base | {"crossing_share": np.nan, "direction": ""})
                rows += [base | {"crossing_share": s, "direction": d} for s, d in found]
    return pd.DataFrame(rows, columns=list(COLUMNS))


def write_crossovers(out_dir: str | Path) -> Path:
    """``crossovers.csv`` from ``regime_sweep.csv`` in `out_dir`."""
    out_dir = Path(out_dir)
    sweep = pd.read_csv(out_dir / "regime_sweep.csv", keep_default_na=False, na_values=[""])
    path = out_dir / "crossovers.csv"
    find_crossovers(sweep).round(4).to_csv(path, index=False)
    return path
