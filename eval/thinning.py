"""Thinning non-covisible detections: the regime sweep's one knob (``cadsim sweep-regime``).

At keep level k ∈ [0, 1] every covisible detection of a frame pair stays and every non-covisible
detection stays with probability k. The draw is seeded by the frame pair's identity alone (its
record checksum), not by the run seed or the split, so validation and test pairs follow the same
rule, every matcher and run sees the same thinned pair, and the levels are nested: one uniform
number u per detection, kept when u < k, so what survives at k also survives at every k' > k
(k = 1 keeps everything, k = 0 leaves only covisible objects).
"""

from __future__ import annotations

import hashlib

import numpy as np

_SALT = b"cadsim thinning v1\0"


def check_keep(keep: float) -> float:
    """`keep` as a float in [0, 1], else ValueError."""
    try:
        value = float(keep)
    except (TypeError, ValueError):
        raise ValueError(f"keep: expected a number in [0, 1], got {keep!r}") from None
    if not 0.0 <= value <= 1.0:
        raise ValueError(f"keep: expected a number in [0, 1], got {keep!r}")
    return value


def draws(checksum: str, n1: int, n2: int) -> tuple[np.ndarray, np.ndarray]:
    """The uniform numbers in [0, 1) of the n1 view-1 and n2 view-2 detections of the frame pair
    with record checksum `checksum` (the same every time)."""
    digest = hashlib.sha256(_SALT + str(checksum).encode()).digest()
    rng = np.random.default_rng(int.from_bytes(digest[:16], "little"))
    u = rng.random(n1 + n2)
    return u[:n1], u[n1:]


def kept_rows(
    checksum: str, n1: int, n2: int, gt_pairs: np.ndarray, keep: float
) -> tuple[np.ndarray, np.ndarray]:
    """Row indices (ascending) of the detections kept at level `keep` in view 1 and view 2:
    every covisible one (a row of `gt_pairs`, (g, 2) int (i, j)) and each other one whose draw is
    below `keep`."""
    keep = check_keep(keep)
    gt = np.asarray(gt_pairs, dtype=np.int64).reshape(-1, 2)
    u1, u2 = draws(checksum, n1, n2)
    covisible1 = np.zeros(n1, dtype=bool)
    covisible2 = np.zeros(n2, dtype=bool)
    covisible1[gt[:, 0]] = True
    covisible2[gt[:, 1]] = True
    return np.flatnonzero(covisible1 | (u1 < keep)), np.flatnonzero(covisible2 | (u2 < keep))


def thin_pair(pair, keep: float):
    """`pair` (a ``cadsim.dataset.FramePair`` or anything with ``view1``, ``view2``,
    ``gt_pairs``, ``checksum`` and ``select(rows1, rows2)``) with its non-covisible detections
    thinned to level `keep`; keep = 1 returns `pair` itself."""
    if check_keep(keep) == 1.0:
        return pair
    rows1, rows2 = kept_rows(pair.checksum, len(pair.view1), len(pair.view2), pair.gt_pairs, keep)
    return pair.select(rows1, rows2)


def noncovisible_share(n1, n2, n_gt) -> float:
    """Non-covisible objects over all objects of both views, pooled over frame pairs (arrays of
    per-pair counts); NaN when there are no objects."""
    n1, n2, n_gt = (np.asarray(a, dtype=float) for a in (n1, n2, n_gt))
    total = float(np.sum(n1 + n2))
    return float(np.sum(n1 + n2 - 2 * n_gt) / total) if total > 0 else float("nan")
