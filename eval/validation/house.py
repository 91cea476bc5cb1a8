"""CMU House landmarks and the BCAGM/RRWHM House matching protocol.

Frames are 30 hand-labelled landmarks in image pixels (x right, y down); row r is the same
physical point in every frame (identity ground truth). Data: ``eval/data/cmu-house`` (see its
README for provenance).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

LABELS_DIR = Path(__file__).resolve().parents[1] / "data" / "cmu-house" / "labels"
N_FRAMES = 111
N_LANDMARKS = 30
BASELINES = tuple(range(10, 101, 10))


def load_house_landmarks(labels_dir: Path | str = LABELS_DIR) -> np.ndarray:
    """All frames as a (111, 30, 2) float array of pixel coordinates; index k is ``house{k+1}.txt``."""
    labels_dir = Path(labels_dir)
    frames = []
    for k in range(1, N_FRAMES + 1):
        path = labels_dir / f"house{k}.txt"
        if not path.is_file():
            raise FileNotFoundError(f"{path}: CMU House landmark file missing")
        pts = np.loadtxt(path, dtype=float, ndmin=2)
        if pts.shape != (N_LANDMARKS, 2):
            raise ValueError(f"{path}: expected {N_LANDMARKS} rows of 'x y', got shape {pts.shape}")
        frames.append(pts)
    return np.stack(frames)


@dataclass(frozen=True)
class HousePair:
    """One House matching problem: the first ``n1`` landmarks of frame ``u`` (0-based) against all
    30 of frame ``u + baseline``, view 2 shuffled by ``perm``: points2 = frame[u+b][perm], so the
    true partner of landmark i is ``truth[i]`` = position of i in ``perm``."""

    u: int
    baseline: int
    points1: np.ndarray
    points2: np.ndarray
    truth: np.ndarray


def house_pairs(
    frames: np.ndarray,
    n1: int,
    baseline: int,
    *,
    seed: int = 0,
    max_pairs: int | None = None,
) -> Iterator[HousePair]:
    """Frame pairs (u, u + baseline) for u = 0 .. 110 - baseline, as in ``test_house.m``.

    View 2 is randomly permuted (seeded) so that a matcher cannot score by favouring the identity;
    the published protocol does not permute, which is equivalent for a permutation-equivariant
    matcher. ``max_pairs`` keeps an evenly spaced subset of the frame pairs (for quick runs).
    """
    if not 3 <= n1 <= N_LANDMARKS:
        raise ValueError(f"n1: expected 3..{N_LANDMARKS} landmarks, got {n1}")
    n_frames = frames.shape[0]
    if not 1 <= baseline < n_frames:
        raise ValueError(f"baseline: expected 1..{n_frames - 1}, got {baseline}")
    starts = np.arange(n_frames - baseline)
    if max_pairs is not None and max_pairs < starts.size:
        starts = starts[np.linspace(0, starts.size - 1, max_pairs).round().astype(int)]
    for u in starts:
        rng = np.random.default_rng([seed, n1, baseline, int(u)])
        perm = rng.permutation(frames.shape[1])
        truth = np.argsort(perm)[:n1]
        yield HousePair(
            u=int(u),
            baseline=baseline,
            points1=frames[u, :n1].copy(),
            points2=frames[u + baseline][perm],
            truth=truth,
        )
