"""``trajectory_pose``: the two agents' planar relative pose from their own tracks alone (no GNSS
needed), then the association read from it, over a window of frames.

Each agent's detections are put into its own frame-0 ground plane through its mount and
odometry (:func:`~matchers.core.sequence_problem.ground_positions`), where its odometry keeps
them locally accurate. One planar rigid motion T = (R(θ), s) maps agent 2's frame-0 plane onto
agent 1's for the whole window, and it maps velocities too. For the window of frames
s = t - W + 1 .. t (dt seconds apart):

    tracks       per own track a: its observations (f, p_af) in the window, the least-squares
                 velocity v_a (m/s; tracks seen >= 3 times) and its position at frame t,
                 p_a(t) = mean_f p_af + v_a (t - mean_f f) dt; its class: the reported class of
                 its last detection.
    hypotheses   (1) every pair (a, b) of *moving* tracks (|v| >= min_speed in both, speeds
                 within speed_tol · max(|v_a|, |v_b|) + 1 m/s, same class) proposes its own
                 motion:  θ = ∠v_a - ∠v_b,  s = p_a(t) - R(θ) p_b(t);
                 (2) every pair of track pairs ((a1, b1), (a2, b2)) whose lengths agree
                 (| |p_a1 - p_a2| - |p_b1 - p_b2| | <= cutoff / 2, both >= 2 m) proposes the
                 motion aligning the two segments (static scenes, W = 1), among the 24 tracks
                 of each view seen most often; at most ``samples`` of them (a random subset
                 beyond);
                 (3) with a GNSS prior: the prior's mean motion.
                 A Hough vote over the motions of (2) (cells of 2° x cutoff / 2) keeps the
                 ``hypotheses`` most voted cells, each as the mean of its voters; every
                 hypothesis of (1) and (3) is kept.
    support      of T: sum over frames s and detections i of agent 1 of
                 max_j c_ij · biweight(|q1_si - T q2_sj|, cutoff)   (a vote: look-alikes and
                 clutter tracks propose motions the rest of the scene does not support);
                 c_ij = 1 for the same reported class, ``other_class`` otherwise; plus, with a
                 prior and ``prior_weight`` > 0, ``prior_weight`` · the mean prior likelihood of
                 the frame's GNSS anchors per frame (a soft term: one frame's prior weighs as
                 much as ``prior_weight`` detections; off by default).
    refinement   from the best, IRLS as ``temporal_pose``: track pairs chosen by Hungarian on
                 their mean aligned likelihood, a biweight-weighted Procrustes fit of their
                 observations (plus the GNSS anchors at ``prior_weight`` per frame, if any),
                 until the motion stops changing or ``max_iter`` rounds.
    association  per frame s: L_sij = c_ij · exp(-d² / (4 width²)) for d = |q1_si - T q2_sj|
                 <= cutoff, else 0; accumulated along the own tracks over the window (mean,
                 :func:`matchers.temporal.windowed.accumulate`), Hungarian, threshold.

Runs under every localisation preset: the prior, where there is one, is a hypothesis and a
soft term, never required. Deterministic for a given ``seed`` (the random pairs of step (2)
are drawn from ``seed`` and t). Vectorised over hypotheses, detections and observations; the
loops run over frames and refinement rounds.
"""

from __future__ import annotations

import time

import numpy as np

from matchers.blocks.rigid2d import biweight, rotation
from matchers.core.discretise import canonical_scores
from matchers.core.matching import Matching
from matchers.core.options import check_count, check_range, rng_from_seed
from matchers.core.sequence_problem import SequenceProblem, ground_positions
from matchers.temporal.partner_hold import NO_LINKS, check_margin, hold_partners
from matchers.temporal.temporal_pose import frame_prior
from matchers.temporal.track_motion import refine_motion
from matchers.temporal.windowed import accumulate, check_sequence

MIN_SEGMENT_M = 2.0
MIN_TRACK_FRAMES = 3
SEGMENT_TRACKS = 24


def _tracks(q, ids, classes, dt):
    """Per own track of one view over the window: (ids (K,), position at the last frame (K, 2),
    velocity (K, 2) m/s (0 below MIN_TRACK_FRAMES observations), class (K,) object array,
    observations (K,))."""
    frames = np.concatenate([np.full(len(x), f, dtype=float) for f, x in enumerate(q)])
    xy = np.concatenate(q).reshape(-1, 2)
    tid = np.concatenate(ids)
    cls = np.concatenate(
        [
            np.full(len(x), None, dtype=object) if c is None else np.asarray(c, dtype=object)
            for c, x in zip(classes, q, strict=True)
        ]
    )
    uniq, inv, count = np.unique(tid, return_inverse=True, return_counts=True)
    k = len(uniq)
    mean_f = np.bincount(inv, frames, k) / count
    mean_p = np.stack([np.bincount(inv, xy[:, d], k) for d in (0, 1)], 1) / count[:, None]
    df = frames - mean_f[inv]
    sff = np.bincount(inv, df * df, k)
    sfp = np.stack([np.bincount(inv, df * (xy[:, d] - mean_p[inv, d]), k) for d in (0, 1)], 1)
    ok = (count >= MIN_TRACK_FRAMES) & (sff > 0)
    vel = np.where(ok[:, None], sfp / np.where(sff > 0, sff, 1.0)[:, None] / dt, 0.0)
    last = len(q) - 1
    position = mean_p + vel * ((last - mean_f) * dt)[:, None]
    last_class = np.empty(k, dtype=object)
    last_class[inv] = cls  # later observations overwrite earlier ones: the last one stays
    return uniq, position, vel, last_class, count


def _class_weight(c1, c2, other_class):
    """(n, m) c_ij: 1 for the same reported class (or no classes), ``other_class`` else."""
    if c1 is None or c2 is None:
        return None
    same = np.asarray(c1, dtype=object)[:, None] == np.asarray(c2, dtype=object)[None, :]
    return np.where(same, 1.0, other_class)


def _apply(yaw, shift, xy):
    """(H, K, 2): motions (yaw (H,), shift (H, 2)) applied to (K, 2) points."""
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    return np.stack([c * xy[:, 0] - s * xy[:, 1], s * xy[:, 0] + c * xy[:, 1]], -1) + shift[:, None]


def _turn(yaw, xy):
    """(H, 2): each of the (H, 2) points ``xy`` turned by its own ``yaw`` (H,)."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.stack([c * xy[:, 0] - s * xy[:, 1], s * xy[:, 0] + c * xy[:, 1]], 1)


def _moving_hypotheses(tr1, tr2, min_speed, speed_tol, other_class):
    _, p1, v1, c1, _ = tr1
    _, p2, v2, c2, _ = tr2
    s1, s2 = np.linalg.norm(v1, axis=1), np.linalg.norm(v2, axis=1)
    a, b = np.flatnonzero(s1 >= min_speed), np.flatnonzero(s2 >= min_speed)
    if not (len(a) and len(b)):
        return np.zeros(0), np.zeros((0, 2))
    sa, sb = s1[a][:, None], s2[b][None, :]
    ok = np.abs(sa - sb) <= speed_tol * np.maximum(sa, sb) + 1.0
    if other_class == 0.0:
        ok &= c1[a][:, None] == c2[b][None, :]
    ia, ib = np.nonzero(ok)
    a, b = a[ia], b[ib]
    yaw = np.arctan2(v1[a, 1], v1[a, 0]) - np.arctan2(v2[b, 1], v2[b, 0])
    return yaw, p1[a] - _turn(yaw, p2[b])


def _longest(count: np.ndarray, keep: int) -> np.ndarray:
    """Indices of the ``keep`` tracks seen most often (ties: the earlier track), in order."""
    return np.sort(np.argsort(-count, kind="stable")[:keep])


def _segment_hypotheses(tr1, tr2, samples, cutoff, rng):
    """Every pair of track pairs ((a1, b1), (a2, b2)) whose segments agree in length (module
    docstring), among the SEGMENT_TRACKS tracks of each view seen most often (a clutter box is
    seen once); beyond ``samples`` of them, a random subset of that many (drawn from ``rng``)."""
    p1 = tr1[1][_longest(tr1[4], SEGMENT_TRACKS)]
    p2 = tr2[1][_longest(tr2[4], SEGMENT_TRACKS)]
    if len(p1) < 2 or len(p2) < 2 or samples == 0:
        return np.zeros(0), np.zeros((0, 2))
    i = np.stack(np.triu_indices(len(p1), 1), 1)  # unordered in view 1
    j = np.stack(np.nonzero(~np.eye(len(p2), dtype=bool)), 1)  # ordered in view 2
    l1 = np.linalg.norm(p1[i[:, 1]] - p1[i[:, 0]], axis=1)
    l2 = np.linalg.norm(p2[j[:, 1]] - p2[j[:, 0]], axis=1)
    ia, jb = np.nonzero(
        (np.abs(l1[:, None] - l2[None, :]) <= cutoff / 2)
        & (np.minimum(l1[:, None], l2[None, :]) >= MIN_SEGMENT_M)
    )
    if len(ia) > samples:
        keep = np.sort(rng.choice(len(ia), samples, replace=False))
        ia, jb = ia[keep], jb[keep]
    i, j = i[ia], j[jb]
    d1, d2 = p1[i[:, 1]] - p1[i[:, 0]], p2[j[:, 1]] - p2[j[:, 0]]
    yaw = np.arctan2(d1[:, 1], d1[:, 0]) - np.arctan2(d2[:, 1], d2[:, 0])
    mid1 = (p1[i[:, 0]] + p1[i[:, 1]]) / 2
    mid2 = (p2[j[:, 0]] + p2[j[:, 1]]) / 2
    return yaw, mid1 - _turn(yaw, mid2)


def _shortlist(yaw, shift, keep, yaw_bin, shift_bin):
    """(yaw (k,), shift (k, 2)) of the ``keep`` most voted cells of a Hough grid over motions
    (``yaw_bin`` radians x ``shift_bin`` metres): each hypothesis votes once for its cell, a
    cell's motion is the mean of its voters (yaw as a circular mean). Ties in the count go to
    the smaller cell key."""
    if len(yaw) <= keep:
        return yaw, shift
    wrapped = np.mod(yaw + np.pi, 2 * np.pi) - np.pi
    span = 1 << 20  # cells per axis: shifts within ±2^19 cells (cutoff / 2 each)
    cells = (
        (np.floor(wrapped / yaw_bin).astype(np.int64) + span // 2) * span
        + np.clip(np.floor(shift[:, 0] / shift_bin).astype(np.int64) + span // 2, 0, span - 1)
    ) * span + np.clip(np.floor(shift[:, 1] / shift_bin).astype(np.int64) + span // 2, 0, span - 1)
    unique, cell, count = np.unique(cells, return_inverse=True, return_counts=True)
    top = np.argsort(-count, kind="stable")[:keep]
    k = len(unique)
    c = np.bincount(cell, np.cos(wrapped), k)[top]
    s = np.bincount(cell, np.sin(wrapped), k)[top]
    mean_shift = np.stack([np.bincount(cell, shift[:, d], k) for d in (0, 1)], 1)
    return np.arctan2(s, c), (mean_shift / count[:, None])[top]


def estimate(
    q1, q2, ids1, ids2, classes1, classes2, priors, sigma, options, rng, previous=None
) -> tuple[tuple[np.ndarray, np.ndarray], dict] | None:
    """The window's motion (R, t) of agent 2's frame-0 plane into agent 1's and its info
    (module docstring); None when no hypothesis can be formed. ``previous`` (yaw, shift): the
    motion held from the frame before (issue 61), a hypothesis whose support gets ``margin`` per
    detection of agent 1 in the window."""
    o = options
    cutoff, width, other_class = o["cutoff"], o["width"], o["other_class"]
    tr1 = _tracks(q1, ids1, classes1, o["interval_s"])
    tr2 = _tracks(q2, ids2, classes2, o["interval_s"])
    if not (len(tr1[0]) and len(tr2[0])):
        return None
    moving = _moving_hypotheses(tr1, tr2, o["min_speed"], o["speed_tol"], other_class)
    segments = _segment_hypotheses(tr1, tr2, o["samples"], cutoff, rng)
    voted = _shortlist(*segments, o["hypotheses"], np.radians(2.0), cutoff / 2)
    yaw, shift = np.r_[moving[0], voted[0]], np.r_[moving[1], voted[1]]
    used = [p for p in priors if p is not None] if o["prior_weight"] > 0 else []
    priors = [p if used else None for p in priors]
    if used:
        yaw0 = float(np.arctan2(*np.sum([[r[1, 0], r[0, 0]] for _, (r, _) in used], axis=0)))
        shift0 = np.mean([m for _, (_, m) in used], axis=0)
        yaw, shift = np.r_[yaw0, yaw], np.r_[[shift0], shift]
    held = previous is not None and o["margin"] > 0 and o["hold_motion"]
    if held:
        yaw, shift = np.r_[previous[0], yaw], np.r_[[previous[1]], shift]
    if not len(yaw):
        return None
    support = np.zeros(len(yaw))
    for s in range(len(q1)):
        if not (len(q1[s]) and len(q2[s])):
            continue
        moved = _apply(yaw, shift, q2[s])  # (H, m, 2)
        gap = np.linalg.norm(q1[s][None, :, None, :] - moved[:, None, :, :], axis=-1)
        vote = biweight(gap, cutoff)
        weight = _class_weight(classes1[s], classes2[s], other_class)
        if weight is not None:
            vote = vote * weight[None]
        support += vote.max(axis=2).sum(axis=1)
        if priors[s] is not None:
            anchors = priors[s][0]
            gap = np.linalg.norm(moved - anchors[None], axis=-1)
            like = np.exp(-(gap**2) / (4 * (o["spread"] * sigma) ** 2))
            support += o["prior_weight"] * like.mean(axis=1)
    if held:  # the held motion keeps the window unless another beats it by margin per detection
        seen = sum(len(x) for x, y in zip(q1, q2, strict=True) if len(y))
        support[0] += o["margin"] * seen
    h = int(np.argmax(canonical_scores(support)))  # ties: the first hypothesis
    turn, move = rotation(float(yaw[h])), shift[h]
    # observations (s, i, j) for the refinement: every pair within 2 cutoffs of the winner
    src, dst, a, b, cw = [], [], [], [], []
    u1, u2 = tr1[0], tr2[0]
    for s in range(len(q1)):
        if not (len(q1[s]) and len(q2[s])):
            continue
        gap = np.linalg.norm(q1[s][:, None] - (q2[s] @ turn.T + move)[None], axis=-1)
        i, j = np.nonzero(gap <= 2 * cutoff)
        weight = _class_weight(classes1[s], classes2[s], other_class)
        src.append(q2[s][j]), dst.append(q1[s][i])
        a.append(np.searchsorted(u1, ids1[s][i])), b.append(np.searchsorted(u2, ids2[s][j]))
        cw.append(np.ones(len(i)) if weight is None else weight[i, j])
    anchor_src = [q2[s] for s, p in enumerate(priors) if p is not None]
    anchor_dst = [p[0] for p in used]
    anchor_w = [np.full(len(p[0]), o["prior_weight"] / len(p[0])) for p in used]
    anchor_src = np.concatenate(anchor_src) if used else np.zeros((0, 2))
    anchor_dst = np.concatenate(anchor_dst) if used else np.zeros((0, 2))
    anchor_w = np.concatenate(anchor_w) if used else np.zeros(0)
    rounds = 0
    if src and sum(map(len, src)):
        src, dst, a, b, cw = map(np.concatenate, (src, dst, a, b, cw))
        turn, move, rounds = refine_motion(
            turn, move, (src, dst, a, b), (len(u1), len(u2)), cutoff, width,
            (anchor_src, anchor_dst, anchor_w), o["max_iter"], cw, stop_when_unweighted=True,
        )  # fmt: skip
    info = {
        "hypotheses": len(yaw),
        "moving_hypotheses": len(moving[0]),
        "support": float(support[h]),
        "held_motion": bool(held and h == 0),
        "rounds": rounds,
        "yaw_deg": float(np.degrees(np.arctan2(turn[1, 0], turn[0, 0]))),
        "shift_m": [float(move[0]), float(move[1])],
    }
    return (turn, move), info


def trajectory_pose(
    seq: SequenceProblem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    window: int = 5,
    cutoff: float = 3.0,
    width: float = 1.0,
    min_speed: float = 3.0,
    speed_tol: float = 0.3,
    samples: int = 20000,
    hypotheses: int = 64,
    other_class: float = 0.5,
    prior_weight: float = 0.0,
    spread: float = 2.0,
    max_iter: int = 10,
    interval_s: float | None = None,
    margin: float = 0.0,
    hold_motion: bool = True,
) -> list[Matching]:
    """One matching per frame (module docstring). Options: ``window`` (5 frames, causal),
    ``cutoff`` (3 m: the support's biweight and the association's gate), ``width`` (1 m: the
    association likelihood's), ``min_speed`` (3 m/s: a track that proposes from its velocity),
    ``speed_tol`` (0.3: relative speed agreement of such a pair), ``samples`` (20000: at most
    that many segment pairs, a random subset beyond), ``hypotheses`` (64 kept by the Hough vote), ``other_class`` (0.5: weight of a pair of different reported classes),
    ``prior_weight`` (0: off) and ``spread`` (2, × world_sigma) of the GNSS prior's soft term
    where there is one (on cad-v2x-seq's gnss-urban a weight of 1 pulled the motion off: median
    error 6.6 m against 0.3 m without), ``max_iter`` (10) refinement rounds, ``interval_s``
    (s between frames; else ``seq.meta["interval_s"]``, else 0.2), ``margin`` (0: off; score
    units; W >= 2 only): by how much another partner must out-score a track pair's current one
    to take it (issue 61, :mod:`matchers.temporal.partner_hold`); with ``margin`` > 0 and ``hold_motion`` (True) the
    window's motion is held the same way: the previous frame's motion is a hypothesis whose
    support gets ``margin`` per detection of agent 1 in the window (a new motion must out-vote
    it by that much). Scores: the aligned likelihood accumulated along the
    own tracks ([0, 1]). Info per frame: the window's motion (``yaw_deg``, ``shift_m``),
    ``relative_pose`` [x, y, yaw] of agent 2's body in agent 1's at that frame, ``prior``
    (whether a GNSS prior took part)."""
    check_sequence(seq)
    rng_from_seed(seed)
    window = check_count("window", window)
    options = {
        "window": window,
        "cutoff": check_range("cutoff", cutoff, 0.0, 1e6, open_low=True),
        "width": check_range("width", width, 0.0, 1e6, open_low=True),
        "min_speed": check_range("min_speed", min_speed, 0.0, 1e6, open_low=True),
        "speed_tol": check_range("speed_tol", speed_tol, 0.0, 10.0),
        "samples": check_count("samples", samples) if samples else 0,
        "hypotheses": check_count("hypotheses", hypotheses),
        "other_class": check_range("other_class", other_class, 0.0, 1.0),
        "prior_weight": check_range("prior_weight", prior_weight, 0.0, 1e6),
        "spread": check_range("spread", spread, 0.0, 1e6, open_low=True),
        "max_iter": check_count("max_iter", max_iter),
        "margin": check_margin(margin) if window > 1 else 0.0,  # W = 1: one frame, no memory
        "hold_motion": bool(hold_motion),
    }
    interval_s = seq.meta.get("interval_s", 0.2) if interval_s is None else interval_s
    options["interval_s"] = check_range("interval_s", interval_s, 0.0, 1e6, open_low=True)
    window = options["window"]
    q1, q2 = ground_positions(seq, 1), ground_positions(seq, 2)
    classes1 = [f.classes1 for f in seq.frames]
    classes2 = [f.classes2 for f in seq.frames]
    priors = [
        frame_prior(a, b, f) if f.world1 is not None and f.world_sigma is not None else None
        for a, b, f in zip(q1, q2, seq.frames, strict=True)
    ]
    out, held, previous = [], NO_LINKS, None
    for t in range(seq.num_frames):
        started = time.perf_counter()
        lo = max(0, t - window + 1)
        frame = seq.frames[t]
        here = slice(lo, t + 1)
        sigmas = [f.world_sigma for f in seq.frames[here] if f.world_sigma is not None]
        sigma = float(np.mean(sigmas)) if sigmas else 1.0
        found = None
        if frame.n1 and frame.n2:
            rng = np.random.default_rng([0 if seed is None else int(seed), t])
            found = estimate(
                q1[here], q2[here], seq.tracks1[here], seq.tracks2[here],
                [_labels(c, len(x)) for c, x in zip(classes1[here], q1[here], strict=True)],
                [_labels(c, len(x)) for c, x in zip(classes2[here], q2[here], strict=True)],
                priors[here], sigma, options, rng, previous,
            )  # fmt: skip
        if found is None:
            scores = np.zeros((frame.n1, frame.n2))
            info = {"window": window, "prior": False}
            done, held = _finish(seq, t, scores, threshold, started, held, options, 0, info)
            out.append(done)
            continue
        (turn, move), info = found
        previous = (float(np.arctan2(turn[1, 0], turn[0, 0])), np.asarray(move, dtype=float))
        aligned = []
        for s in range(t + 1):
            if s < lo or not (len(q1[s]) and len(q2[s])):
                aligned.append(np.zeros((len(q1[s]), len(q2[s]))))
                continue
            gap = np.linalg.norm(q1[s][:, None] - (q2[s] @ turn.T + move)[None], axis=-1)
            like = np.where(gap <= cutoff, np.exp(-(gap**2) / (4 * width**2)), 0.0)
            weight = _class_weight(classes1[s], classes2[s], other_class)
            aligned.append(like if weight is None else like * weight)
        scores = accumulate(seq, aligned, t, window, "mean")
        o1, o2 = seq.odometry1[t], seq.odometry2[t]
        yaw = np.arctan2(turn[1, 0], turn[0, 0]) + o2[2] - o1[2]
        at = rotation(float(o1[2])).T @ (turn @ o2[:2] + move - o1[:2])
        info |= {
            "window": window,
            "prior": options["prior_weight"] > 0 and any(p is not None for p in priors[here]),
            "relative_pose": [float(at[0]), float(at[1]), float(yaw)],
        }
        rounds = info["rounds"]
        done, held = _finish(seq, t, scores, threshold, started, held, options, rounds, info)
        out.append(done)
    return out


def _finish(seq, t, scores, threshold, started, held, options, rounds, info):
    """Frame t's matching and the held links after it (:mod:`matchers.temporal.partner_hold`)."""
    return hold_partners(
        "trajectory_pose", scores, threshold, started, seq.tracks1[t], seq.tracks2[t], held,
        options["margin"], rounds, info,
    )  # fmt: skip


def _labels(classes, count: int):
    """A frame's reported classes as given, or None (no classes, or an empty view)."""
    return None if classes is None or count == 0 else classes


trajectory_pose.requires = frozenset()
trajectory_pose.deterministic = True
trajectory_pose.temporal = True
