"""Hysteresis on the cross-agent links of a temporal matcher: a track pair keeps its
partner unless the evidence for a change exceeds the evidence for the current partner by a
margin.

State: the held links, pairs (a, b) of own track ids (agent 1's, agent 2's). At frame t, with
the frame's scores S (n_t, m_t) (already in [0, 1], e.g. accumulated along the own tracks over
the window) and the frame's own track ids:

    boosted[i, j] = S[i, j] + margin · [(track1_t(i), track2_t(j)) is held]

and the assignment is the Hungarian one on ``boosted``: a held link is given up only when the
other assignment gains more than ``margin`` of score (one held link against one new one:
S[i, j'] > S[i, j] + margin). A held link is helped even with no evidence now (S = 0), so a
partner survives a frame in which its object is briefly unscored. The reported scores stay S
and ``threshold`` reads S (a held pair below it is dropped from the frame's pairs, not kept).

Update after frame t: the assigned pairs with S > 0, and the held links assigned again, are
held; a held link is forgotten when either of its tracks takes another partner, or when both of
its tracks are seen at t and it was not assigned; a link whose track is unseen at t is kept (the
object may come back on that track).
The held links do not depend on ``threshold`` (a run with ``threshold=None`` whose pairs are cut
at τ afterwards, as the evaluation does, declares what a run at τ declares).

``margin = 0`` is the plain discretisation (:func:`matchers.core.result.finish`), bit for bit.
Vectorised: one membership test and one Hungarian per frame.
"""

from __future__ import annotations

import time

import numpy as np

from matchers.core.discretise import canonical_scores, hungarian
from matchers.core.matching import Matching
from matchers.core.options import check_range
from matchers.core.result import finish

NO_LINKS = np.zeros((0, 2), dtype=np.int64)


def check_margin(margin: object) -> float:
    """``margin`` as a float in [0, 1] (score units), or ValueError naming it."""
    return check_range("margin", margin, 0.0, 1.0)


def held_mask(ids1: np.ndarray, ids2: np.ndarray, held: np.ndarray) -> np.ndarray:
    """(n, m) bool: whether (ids1[i], ids2[j]) is one of the ``held`` (k, 2) track-id links."""
    ids1 = np.asarray(ids1, dtype=np.int64).reshape(-1)
    ids2 = np.asarray(ids2, dtype=np.int64).reshape(-1)
    if not len(held):
        return np.zeros((len(ids1), len(ids2)), dtype=bool)
    order = np.argsort(held[:, 0], kind="stable")
    keys, partners = held[order, 0], held[order, 1]
    at = np.clip(np.searchsorted(keys, ids1), 0, len(keys) - 1)
    has = keys[at] == ids1
    partner = np.where(has, partners[at], np.iinfo(np.int64).min)
    return has[:, None] & (partner[:, None] == ids2[None, :])


def update_links(
    held: np.ndarray, ids1: np.ndarray, ids2: np.ndarray, assigned: np.ndarray
) -> np.ndarray:
    """The held links after a frame (module docstring): ``assigned`` (k, 2) track-id pairs of
    the frame (with positive score), ``ids1``/``ids2`` the frame's own track ids."""
    if len(held):
        taken = np.isin(held[:, 0], assigned[:, 0]) | np.isin(held[:, 1], assigned[:, 1])
        both_seen = np.isin(held[:, 0], ids1) & np.isin(held[:, 1], ids2)
        held = held[~(taken | both_seen)]
    return np.concatenate([held, assigned]).astype(np.int64)


def hold_partners(
    name: str,
    scores: np.ndarray,
    threshold: float | None,
    started: float,
    ids1: np.ndarray,
    ids2: np.ndarray,
    held: np.ndarray,
    margin: float,
    iterations: int = 0,
    info: dict | None = None,
) -> tuple[Matching, np.ndarray]:
    """(frame t's :class:`Matching`, the held links after it) from its scores (n, m) in [0, 1]
    and the held links before it (module docstring). ``margin = 0``: :func:`finish`'s matching
    and no links kept."""
    if margin == 0:
        return finish(name, scores, threshold, started, iterations, info), NO_LINKS
    ids1 = np.asarray(ids1, dtype=np.int64).reshape(-1)
    ids2 = np.asarray(ids2, dtype=np.int64).reshape(-1)
    canon = np.nan_to_num(canonical_scores(scores), nan=0.0, posinf=0.0, neginf=0.0)
    kept = held_mask(ids1, ids2, held)
    if canon.size:
        rows, cols = hungarian(canon + margin * kept)
    else:
        rows = cols = np.zeros(0, dtype=np.int64)
    positive = (canon[rows, cols] > 0) | kept[rows, cols]
    assigned = np.stack([ids1[rows[positive]], ids2[cols[positive]]], 1).astype(np.int64)
    held_now = int(kept[rows, cols].sum())
    if threshold is not None:
        keep = canon[rows, cols] >= threshold
        rows, cols = rows[keep], cols[keep]
    pairs = np.stack([rows, cols], axis=1).astype(np.int64).reshape(-1, 2)
    done = Matching(
        pairs=pairs,
        scores=canonical_scores(scores),
        name=name,
        iterations=int(iterations),
        time_s=time.perf_counter() - started,
        info=dict(info or {}) | {"margin": margin, "held_links": held_now},
    )
    return done, update_links(held, ids1, ids2, assigned)
