"""Thinning non-covisible detections: the regime sweep's one knob (``cadsim sweep-regime``).

At keep level k ∈ [0, 1] every covisible detection of a frame pair stays and every non-covisible
detection stays with probability k. The draw is seeded by the frame pair's identity — its
simulation seed (itself derived from the dataset's root seed and the episode), episode and
snapshot slot — and a draw index, never by bytes that carry floating-point results (a record
checksum would change with the last bit of a stored pose, ``../shared/DESIGN.md`` §10). The
evaluation uses the run's seed as the draw index, so each run of the regime sweep is an
independent thinning replicate, every matcher of a run sees the same thinned pair, and validation
and test pairs follow the same rule. The levels are nested: one uniform number u per detection,
kept when u < k, so what survives at k also survives at every k' > k (k = 1 keeps everything,
k = 0 leaves only covisible objects).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

_STREAM = 0x7468696E  # "thin": keeps these draws apart from every other seeded stream


class PairIdentity(NamedTuple):
    """What names a frame pair independently of its contents: simulation seed, episode, slot."""

    sim_seed: int
    episode: int
    slot: int

    @classmethod
    def of(cls, pair) -> PairIdentity:
        """The identity of ``pair`` (anything with ``sim_seed``, ``episode`` and ``slot``)."""
        return cls(int(pair.sim_seed), int(pair.episode), int(pair.slot))


def check_keep(keep: float) -> float:
    """`keep` as a float in [0, 1], else ValueError."""
    try:
        value = float(keep)
    except (TypeError, ValueError):
        raise ValueError(f"keep: expected a number in [0, 1], got {keep!r}") from None
    if not 0.0 <= value <= 1.0:
        raise ValueError(f"keep: expected a number in [0, 1], got {keep!r}")
    return value


def draws(identity: PairIdentity, n1: int, n2: int, draw: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The uniform numbers in [0, 1) of the n1 view-1 and n2 view-2 detections of the frame pair
    `identity` in thinning draw `draw` (≥ 0; the same every time)."""
    if int(draw) < 0:
        raise ValueError(f"draw: expected an integer >= 0, got {draw!r}")
    entropy = [_STREAM, *(int(v) for v in identity), int(draw)]
    if min(entropy) < 0:
        raise ValueError(f"identity: expected non-negative integers, got {tuple(identity)!r}")
    u = np.random.default_rng(np.random.SeedSequence(entropy)).random(n1 + n2)
    return u[:n1], u[n1:]


def kept_rows(
    identity: PairIdentity, n1: int, n2: int, gt_pairs: np.ndarray, keep: float, draw: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Row indices (ascending) of the detections kept at level `keep` in view 1 and view 2:
    every covisible one (a row of `gt_pairs`, (g, 2) int (i, j)) and each other one whose draw is
    below `keep` in draw `draw`."""
    keep = check_keep(keep)
    gt = np.asarray(gt_pairs, dtype=np.int64).reshape(-1, 2)
    u1, u2 = draws(identity, n1, n2, draw)
    covisible1 = np.zeros(n1, dtype=bool)
    covisible2 = np.zeros(n2, dtype=bool)
    covisible1[gt[:, 0]] = True
    covisible2[gt[:, 1]] = True
    return np.flatnonzero(covisible1 | (u1 < keep)), np.flatnonzero(covisible2 | (u2 < keep))


def thin_pair(pair, keep: float, draw: int = 0):
    """`pair` (a ``cadsim.dataset.FramePair`` or anything with ``view1``, ``view2``,
    ``gt_pairs``, ``sim_seed``, ``episode``, ``slot`` and ``select(rows1, rows2)``) with its
    non-covisible detections thinned to level `keep` in draw `draw`; keep = 1 returns `pair`
    itself."""
    if check_keep(keep) == 1.0:
        return pair
    identity = PairIdentity.of(pair)
    rows1, rows2 = kept_rows(identity, len(pair.view1), len(pair.view2), pair.gt_pairs, keep, draw)
    return pair.select(rows1, rows2)


def noncovisible_share(n1, n2, n_gt) -> float:
    """Non-covisible objects over all objects of both views, pooled over frame pairs (arrays of
    per-pair counts); NaN when there are no objects."""
    n1, n2, n_gt = (np.asarray(a, dtype=float) for a in (n1, n2, n_gt))
    total = float(np.sum(n1 + n2))
    return float(np.sum(n1 + n2 - 2 * n_gt) / total) if total > 0 else float("nan")
