"""``windowed:<name>``: any two-view matcher lifted to a window of frames along the agents' own
tracks.

The base matcher runs once per frame (its soft scores S_s, (n_s, m_s)). For frame t and window
W (frames s = t - W + 1 .. t, those that exist), the score of a track pair (a, b) — a one of
agent 1's own tracks, b one of agent 2's — is accumulated over the frames of the window in
which both tracks have a detection:

    reduce="mean":  A_ab = mean_s S_s[i_s(a), j_s(b)]   (over those frames)
    reduce="sum":   A_ab = sum_s S_s[i_s(a), j_s(b)] / W (a pair seen together more often
                    scores higher; still in [0, 1])

and frame t's matching is the shared discretisation (Hungarian, then ``threshold``) of
S~_t[i, j] = A_{track1_t(i), track2_t(j)}; with ``margin`` > 0 (issue 61) a track pair keeps its
partner unless another assignment scores more than ``margin`` above it
(:mod:`matchers.temporal.partner_hold`; W >= 2 only: W = 1 stays one frame's evidence).
Causal: frame t never looks past t. W = 1 is the base matcher itself, bit for bit, whatever
``margin`` (tested). Vectorised: one scatter-add per frame of the window.
``windowed(base).over_windows(seq, windows, …)`` gives the matchings at several W from one run
of the base matcher per frame (a table over W need not run it once per W).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from matchers.core.matching import Matching
from matchers.core.options import check_count, rng_from_seed
from matchers.core.sequence_problem import SequenceProblem
from matchers.temporal.partner_hold import NO_LINKS, check_margin, hold_partners

REDUCTIONS = ("mean", "sum")


def check_sequence(seq: object) -> SequenceProblem:
    if not isinstance(seq, SequenceProblem):
        raise TypeError(f"seq: expected a matchers SequenceProblem, got {type(seq).__name__}")
    return seq


def accumulate(
    seq: SequenceProblem, scores: Sequence[np.ndarray], t: int, window: int, reduce: str = "mean"
) -> np.ndarray:
    """(n_t, m_t) frame-t scores accumulated along the own tracks over the window ending at t
    (module docstring); ``scores[s]`` is frame s's (n_s, m_s) score matrix."""
    if reduce not in REDUCTIONS:
        raise ValueError(f"reduce: expected one of {REDUCTIONS}, got {reduce!r}")
    ids1, ids2 = seq.tracks1[t], seq.tracks2[t]
    if window == 1 or not (len(ids1) and len(ids2)):
        return np.asarray(scores[t], dtype=float).reshape(len(ids1), len(ids2))
    total = np.zeros((len(ids1), len(ids2)))
    count = np.zeros((len(ids1), len(ids2)))
    for s in range(max(0, t - window + 1), t + 1):
        a, b = seq.tracks1[s], seq.tracks2[s]
        # rows of frame s whose track is alive at t, and where it sits at t
        rows_t, rows_s = _positions(ids1, a)
        cols_t, cols_s = _positions(ids2, b)
        if not (len(rows_t) and len(cols_t)):
            continue
        block = np.asarray(scores[s], dtype=float)[np.ix_(rows_s, cols_s)]
        total[np.ix_(rows_t, cols_t)] += block
        count[np.ix_(rows_t, cols_t)] += 1.0
    if reduce == "sum":
        return np.clip(total / min(window, t + 1), 0.0, 1.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, total / np.maximum(count, 1.0), 0.0)


def _positions(at_t: np.ndarray, at_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Indices (into frame t, into frame s) of the track ids the two frames share."""
    _, where_t, where_s = np.intersect1d(at_t, at_s, assume_unique=True, return_indices=True)
    return where_t, where_s


def windowed(base: str):
    """The temporal matcher ``windowed:<base>`` (module docstring). ValueError naming an
    unknown base."""
    from matchers.core.registry import get  # the two-view registry

    matcher = get(base)
    name = f"windowed:{base}"

    def over_windows(
        seq: SequenceProblem,
        windows: Sequence[int],
        seed: int | None = 0,
        threshold: float | None = None,
        *,
        reduce: str = "mean",
        margin: float = 0.0,
        **options,
    ) -> dict[int, list[Matching]]:
        """{W: ``lifted(seq, seed, threshold, window=W, reduce=reduce, margin=margin,
        **options)``} for every W of ``windows``, the base matcher run once per frame for all
        of them (the same matchings as one call per W: the base does not depend on W)."""
        check_sequence(seq)
        rng_from_seed(seed)
        windows = [check_count("window", w) for w in windows]
        if reduce not in REDUCTIONS:
            raise ValueError(f"reduce: expected one of {REDUCTIONS}, got {reduce!r}")
        margin = check_margin(margin)
        per_frame = [
            matcher(frame, seed=seed, threshold=threshold, **options) for frame in seq.frames
        ]
        return {w: _lift(per_frame, seq, w, reduce, threshold, margin) for w in windows}

    def _lift(per_frame, seq, window, reduce, threshold, margin) -> list[Matching]:
        if window == 1:  # one frame: the base matcher itself, no hysteresis (no memory)
            return per_frame
        out, held = [], NO_LINKS
        for t in range(seq.num_frames):
            start = time.perf_counter()
            scores = accumulate(seq, [m.scores for m in per_frame], t, window, reduce)
            info = {"window": window, "reduce": reduce, "base": per_frame[t].info}
            done, held = hold_partners(
                name, scores, threshold, start, seq.tracks1[t], seq.tracks2[t], held, margin,
                per_frame[t].iterations, info,
            )  # fmt: skip
            done.time_s += per_frame[t].time_s
            out.append(done)
        return out

    def lifted(
        seq: SequenceProblem,
        seed: int | None = 0,
        threshold: float | None = None,
        *,
        window: int = 5,
        reduce: str = "mean",
        margin: float = 0.0,
        **options,
    ) -> list[Matching]:
        window = check_count("window", window)
        return over_windows(
            seq, [window], seed, threshold, reduce=reduce, margin=margin, **options
        )[window]

    lifted.__name__ = lifted.__qualname__ = name
    lifted.requires = frozenset(getattr(matcher, "requires", ()))
    lifted.deterministic = bool(getattr(matcher, "deterministic", False))
    lifted.temporal = True
    lifted.over_windows = over_windows
    return lifted
