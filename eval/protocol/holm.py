"""Holm's step-down adjustment of p-values (Holm, Scand. J. Statist. 1979): family-wise error
control for a table's many comparisons, uniformly more powerful than Bonferroni.

With m p-values sorted ascending, p_(1) ≤ … ≤ p_(m), the adjusted value of the i-th is
max_{j ≤ i} min(1, (m − j + 1) · p_(j)); rejecting where the adjusted p ≤ α keeps the chance of
any false rejection in the family at most α. NaN entries (no comparison) are left out of the
family and stay NaN.
"""

from __future__ import annotations

import numpy as np


def holm(p_values) -> np.ndarray:
    """Holm-adjusted p-values, in the input's order and shape (module docstring)."""
    p = np.asarray(p_values, dtype=float)
    out = np.full(p.shape, np.nan)
    flat, finite = p.reshape(-1), np.isfinite(p.reshape(-1))
    if ((flat[finite] < 0) | (flat[finite] > 1)).any():
        raise ValueError("p_values: expected values in [0, 1]")
    where = np.flatnonzero(finite)
    order = where[np.argsort(flat[where], kind="stable")]
    m = len(order)
    steps = (m - np.arange(m)) * flat[order]
    out.reshape(-1)[order] = np.minimum(1.0, np.maximum.accumulate(steps))
    return out


def holm_distinct(p_values, keys) -> np.ndarray:
    """Holm-adjusted p-values over the *distinct* comparisons: entries with equal ``keys`` (one
    hashable per p-value: the same comparison repeated, e.g. a matcher that reads no prior under
    several presets) count once in the family and share their adjusted value (that of the first
    of them); order and length as the input's."""
    p = np.asarray(p_values, dtype=float).reshape(-1)
    keys = list(keys)
    if len(keys) != len(p):
        raise ValueError(f"keys: expected {len(p)}, got {len(keys)}")
    first: dict = {}
    index = np.array([first.setdefault(k, i) for i, k in enumerate(keys)], dtype=int)
    distinct = np.unique(index)
    adjusted = np.full(len(p), np.nan)
    adjusted[distinct] = holm(p[distinct])
    return adjusted[index]
