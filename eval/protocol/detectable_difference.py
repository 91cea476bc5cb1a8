"""The minimum detectable difference (MDD) of a paired comparison whose unit is the cluster.

For per-item paired differences d (a − b per frame pair) grouped into G clusters (simulation
episodes, or snapshots that share no object), the MDD is the smallest true mean difference that
a two-sided test at level α = 1 − ``level`` rejects with probability ``power``:

    MDD = (t_{1 − α/2, G − 1} + t_{power, G − 1}) · SE,

t-based (Student's t quantiles with G − 1 degrees of freedom, the same as the interval of
:func:`eval.protocol.cluster_interval.t_interval`), SE the same cluster-robust (CR1) standard error
of the pair-weighted mean. With equal cluster sizes SE = sd(cluster means of d) / √G, so MDD =
(t_{0.975} + t_{0.8}) · sd / √G; for large G the quantiles tend to the normal ones, 1.960 +
0.842 = 2.802. It is the half-width of the 95 % interval times (1 + t_{0.8} / t_{0.975}) ≈ 1.43:
a difference smaller than it is one the data could easily miss, so an interval that contains 0
says "no difference larger than about this", not "no difference". Rates in, rates out (a
difference of fractions; printed as percentage points). NaN with fewer than two clusters.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import t as student_t

from eval.protocol.cluster_interval import cluster_standard_error

LEVEL = 0.95
POWER = 0.80


def mdd_factor(clusters: int, level: float = LEVEL, power: float = POWER) -> float:
    """t_{1 − α/2, G − 1} + t_{power, G − 1} for G = ``clusters`` (NaN below two clusters)."""
    if not 0 < level < 1 or not 0 < power < 1:
        raise ValueError(f"level, power: expected numbers in (0, 1), got {level}, {power}")
    if clusters < 2:
        return float("nan")
    df = clusters - 1
    return float(student_t.ppf(0.5 + level / 2, df) + student_t.ppf(power, df))


def minimum_detectable_difference(
    values: np.ndarray, clusters: np.ndarray, level: float = LEVEL, power: float = POWER
) -> tuple[float, int]:
    """(MDD, G) of the paired per-item differences ``values`` grouped by ``clusters``: the
    smallest true mean difference detected at ``level`` confidence with ``power`` (module
    docstring; same unit as ``values``)."""
    se, groups = cluster_standard_error(values, clusters)
    return mdd_factor(groups, level, power) * se, groups
