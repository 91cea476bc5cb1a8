"""``temporal_pose``: the planar relative pose of the two agents estimated over a window of
frames jointly with the association, and the association read from the refined pose.

Each agent's detections are put into its own frame-0 ground plane through its mount and
odometry (:func:`~matchers.core.sequence_problem.ground_positions`). One planar rigid motion
T (yaw, shift) then maps agent 2's frame-0 plane onto agent 1's for the whole window — objects
may move, since both views of one object are taken at the same instant. For the window of
frames s = t - W + 1 .. t:

    GNSS prior   per frame, each view's detections fitted to its own world positions
                 (procrustes_2d) give the map M_k,s of agent k's frame-0 plane into the world;
                 anchors_s = M_1,s^-1(world2_s): view 2's detections where the two GNSS poses
                 put them in agent 1's plane. Candidates: (s, i, j) within gate * sigma there.
    hypotheses   every candidate *track pair* (a, b) proposes T from its own observations
                 (weighted Procrustes over the frames where both exist; the prior's yaw when
                 they do not spread over 0.5 m), plus the prior's own mean motion; the
                 ``hypotheses`` best by summed prior likelihood are scored by support:
                 sum over (s, i) of max_j biweight(|q1_si - T q2_sj|, cutoff)  (a vote)
    refinement   from the best, IRLS: track pairs associated by Hungarian on their mean aligned
                 likelihood; a fit (procrustes_2d) of their observations (biweight weights) plus
                 the GNSS anchors as a soft term (``prior_weight`` per frame, spread over its
                 anchors); until the motion stops changing or ``max_iter`` rounds.
    association  per frame s, the aligned prior likelihood L_s (width spread * tighten * sigma,
                 gate * tighten * sigma), accumulated along the own tracks over the window
                 (mean, :func:`matchers.temporal.windowed.accumulate`), Hungarian, threshold.

time offset  (``max_offset_s`` > 0: latency unknown) the window's motion is estimated for each
             candidate age Δt of agent 2's detections, moved forward along agent 2's own
             tracks by their velocity · Δt (:mod:`matchers.temporal.time_offset`); the largest
             support wins.

cutoff = gate * tighten * sigma (as ``pose_refine``). The hypotheses' ranking and the choice of
the best read canonical values (:func:`~matchers.core.discretise.canonical_scores`): ties go to
the first on every CPU. Vectorised: candidates, hypotheses and
support are arrays; the loops run over frames and refinement rounds only.
"""

from __future__ import annotations

import time

import numpy as np

from matchers.blocks.prior import PRIOR_FIELDS, check_prior_options, ground_plane, prior_likelihood
from matchers.blocks.rigid2d import biweight, procrustes_2d, rotation
from matchers.core.discretise import canonical_scores
from matchers.core.matching import Matching
from matchers.core.options import check_count, check_range, rng_from_seed
from matchers.core.sequence_problem import SequenceProblem, ground_positions
from matchers.temporal.partner_hold import NO_LINKS, check_margin, hold_partners
from matchers.temporal.time_offset import compensated, offset_grid, track_velocities
from matchers.temporal.track_motion import refine_motion
from matchers.temporal.windowed import accumulate, check_sequence

MIN_SPREAD_M = 0.5


def frame_prior(
    q1: np.ndarray, q2: np.ndarray, frame
) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray]] | None:
    """(anchors (m, 2) of view 2 in agent 1's frame-0 plane, the prior's motion (R, t) of agent
    2's frame-0 plane into agent 1's) of one frame from each view's frame-0 positions ``q1``,
    ``q2`` and the frame's GNSS world positions; None without a prior or with < 2 detections."""
    if frame.world1 is None or frame.n1 < 2 or frame.n2 < 2:
        return None
    r1, t1 = procrustes_2d(q1, ground_plane(frame.world1), np.ones(len(q1)))
    r2, t2 = procrustes_2d(q2, ground_plane(frame.world2), np.ones(len(q2)))
    anchors = (ground_plane(frame.world2) - t1) @ r1
    return anchors, (r1.T @ r2, r1.T @ (t2 - t1))


def _grouped_fit(src, dst, group, count, yaw0):
    """Per group, the rigid motion (yaw (G,), shift (G, 2)) of its src -> dst observations;
    groups spread over less than MIN_SPREAD_M take yaw0."""
    n = np.maximum(np.bincount(group, minlength=count), 1)
    mean_s = np.stack([np.bincount(group, src[:, d], count) for d in (0, 1)], 1) / n[:, None]
    mean_d = np.stack([np.bincount(group, dst[:, d], count) for d in (0, 1)], 1) / n[:, None]
    a, b = src - mean_s[group], dst - mean_d[group]
    cross = np.bincount(group, a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0], count)
    dot = np.bincount(group, (a * b).sum(1), count)
    spread = np.sqrt(np.bincount(group, (a * a).sum(1), count) / n)
    yaw = np.where(spread >= MIN_SPREAD_M, np.arctan2(cross, dot), yaw0)
    c, s = np.cos(yaw), np.sin(yaw)
    turned = np.stack([c * mean_s[:, 0] - s * mean_s[:, 1], s * mean_s[:, 0] + c * mean_s[:, 1]], 1)
    return yaw, mean_d - turned


def _apply(yaw, shift, xy):
    """(H, K, 2): motions (yaw (H,), shift (H, 2)) applied to (K, 2) points."""
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    return np.stack([c * xy[:, 0] - s * xy[:, 1], s * xy[:, 0] + c * xy[:, 1]], -1) + shift[:, None]


def estimate(
    q1, q2, frames, ids1, ids2, sigma, spread, gate, tighten, prior_weight, hypotheses, max_iter
):
    """The window's motion (R, t) and info (module docstring); None without any candidate."""
    priors = [frame_prior(a, b, f) for a, b, f in zip(q1, q2, frames, strict=True)]
    cutoff = gate * tighten * sigma
    rows, cols, frame_of, lik = [], [], [], []
    for s, prior in enumerate(priors):
        if prior is None:
            continue
        like = prior_likelihood(q1[s], prior[0], sigma, spread, gate)
        i, j = np.nonzero(like > 0)
        rows.append(i), cols.append(j), frame_of.append(np.full(len(i), s)), lik.append(like[i, j])
    if not rows or not sum(len(r) for r in rows):
        return None
    rows, cols, frame_of, lik = map(np.concatenate, (rows, cols, frame_of, lik))
    offset1 = np.cumsum([0] + [len(x) for x in q1])
    offset2 = np.cumsum([0] + [len(x) for x in q2])
    all1, all2 = np.concatenate(q1), np.concatenate(q2)
    src, dst = all2[offset2[frame_of] + cols], all1[offset1[frame_of] + rows]
    tr1 = np.concatenate(ids1)[offset1[frame_of] + rows]
    tr2 = np.concatenate(ids2)[offset2[frame_of] + cols]
    u1, a = np.unique(tr1, return_inverse=True)
    u2, b = np.unique(tr2, return_inverse=True)
    key = a * len(u2) + b
    groups, group = np.unique(key, return_inverse=True)
    used = [p for p in priors if p is not None]
    yaw0 = float(np.arctan2(*np.sum([[r[1, 0], r[0, 0]] for _, (r, _) in used], axis=0)))
    shift0 = np.mean([t for _, (_, t) in used], axis=0)
    yaw, shift = _grouped_fit(src, dst, group, len(groups), yaw0)
    weight = np.bincount(group, lik, len(groups))
    best = np.argsort(-canonical_scores(weight), kind="stable")[:hypotheses]
    yaw, shift = np.r_[yaw0, yaw[best]], np.r_[[shift0], shift[best]]
    residual = np.linalg.norm(_apply(yaw, shift, src) - dst, axis=-1)  # (H, K)
    row_key = np.unique(offset1[frame_of] + rows, return_inverse=True)[1]
    vote = np.zeros((len(yaw), row_key.max() + 1))
    np.maximum.at(vote, (slice(None), row_key), biweight(residual, cutoff))
    support = vote.sum(1)
    h = int(np.argmax(canonical_scores(support)))  # tied support: the first hypothesis
    turn, move = rotation(float(yaw[h])), shift[h]
    anchor_src = np.concatenate([q2[s] for s, p in enumerate(priors) if p is not None])
    anchor_dst = np.concatenate([p[0] for p in used])
    anchor_w = np.concatenate([np.full(len(p[0]), prior_weight / len(p[0])) for p in used])
    width = spread * tighten * sigma
    turn, move, rounds = refine_motion(
        turn, move, (src, dst, a, b), (len(u1), len(u2)), cutoff, width,
        (anchor_src, anchor_dst, anchor_w), max_iter,
    )  # fmt: skip
    info = {
        "hypotheses": len(yaw),
        "support": float(support[h]),
        "rounds": rounds,
        "yaw_deg": float(np.degrees(np.arctan2(turn[1, 0], turn[0, 0]))),
        "shift_m": [float(move[0]), float(move[1])],
    }
    return (turn, move), info


def temporal_pose(
    seq: SequenceProblem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    window: int = 5,
    spread: float = 2.0,
    gate: float = 8.0,
    tighten: float = 0.5,
    prior_weight: float = 1.0,
    hypotheses: int = 64,
    max_iter: int = 10,
    max_offset_s: float = 0.0,
    offset_step_s: float = 0.05,
    interval_s: float | None = None,
    margin: float = 0.0,
) -> list[Matching]:
    """One matching per frame (module docstring). Options: ``window`` (5 frames, causal),
    ``spread`` (2) and ``gate`` (8) of the candidate prior likelihood (multiples of
    world_sigma, as ``pose``), ``tighten`` (0.5) once aligned, ``prior_weight`` (1: one frame's
    GNSS prior weighs as much as one matched observation), ``hypotheses`` (64) scored,
    ``max_iter`` (10) refinement rounds. ``max_offset_s`` (0: latency known, none estimated)
    > 0 estimates the age Δt of agent 2's detections per window (:mod:`~matchers.temporal.
    time_offset`): every offset 0, ``offset_step_s`` (0.05 s), … ≤ ``max_offset_s`` moves agent
    2's detections forward along its own tracks (``interval_s`` s between frames, else
    ``seq.meta["interval_s"]``), the window's motion is estimated for each, and the one with the
    largest support wins (ties: the smaller offset); info ``time_offset_s``. ``margin`` (0: off;
    score units; W >= 2 only): by how much another partner must out-score a track pair's
    current one to take it (issue 61, :mod:`matchers.temporal.partner_hold`). Scores: the
    aligned likelihood accumulated along the own tracks (absolute, [0, 1]). Info per frame: the window's motion of agent 2's frame-0 plane into
    agent 1's (``yaw_deg``, ``shift_m``) and ``relative_pose`` [x, y, yaw] of agent 2's body
    into agent 1's at that frame. Needs world1/world2/world_sigma on every non-empty frame.
    Deterministic; ``seed`` unused."""
    check_sequence(seq)
    rng_from_seed(seed)
    window = check_count("window", window)
    spread, gate = check_prior_options(spread, gate)
    tighten = check_range("tighten", tighten, 0.0, 1.0, open_low=True)
    prior_weight = check_range("prior_weight", prior_weight, 0.0, 1e6)
    hypotheses = check_count("hypotheses", hypotheses)
    max_iter = check_count("max_iter", max_iter)
    margin = check_margin(margin) if window > 1 else 0.0  # W = 1: one frame, no memory
    max_offset_s = check_range("max_offset_s", max_offset_s, 0.0, 10.0)
    offsets = np.zeros(1)
    if max_offset_s > 0:
        offset_step_s = check_range("offset_step_s", offset_step_s, 0.0, 10.0, open_low=True)
        interval_s = seq.meta.get("interval_s") if interval_s is None else interval_s
        if interval_s is None:
            raise ValueError(
                "interval_s: estimating a time offset needs the time between frames "
                "(interval_s, or seq.meta['interval_s'])"
            )
        interval_s = check_range("interval_s", interval_s, 0.0, 1e6, open_low=True)
        offsets = offset_grid(max_offset_s, offset_step_s)
    for t, frame in enumerate(seq.frames):
        if frame.n1 and frame.n2 and (frame.world1 is None or frame.world_sigma is None):
            raise ValueError(
                f"world1: frame {t}: temporal_pose needs the localisation prior "
                "(world1/world2/world_sigma) on every frame"
            )
    q1, q2 = ground_positions(seq, 1), ground_positions(seq, 2)
    out, held = [], NO_LINKS
    for t in range(seq.num_frames):
        started = time.perf_counter()
        lo = max(0, t - window + 1)
        sigmas = [f.world_sigma for f in seq.frames[lo : t + 1] if f.world_sigma is not None]
        frame = seq.frames[t]
        found, offset, here2 = None, 0.0, q2
        if sigmas and frame.n1 and frame.n2:
            sigma = float(np.mean(sigmas))
            tried = []
            if len(offsets) > 1:  # velocities from the window's own frames only (causal)
                v2 = track_velocities(q2[lo : t + 1], seq.tracks2[lo : t + 1], interval_s)
            for delta in offsets:  # one candidate (0) unless a time offset is estimated
                moved = q2[lo : t + 1]
                if delta > 0:
                    moved = compensated(moved, v2, float(delta))
                moved = [*q2[:lo], *moved]
                result = estimate(
                    q1[lo : t + 1], moved[lo : t + 1], seq.frames[lo : t + 1],
                    seq.tracks1[lo : t + 1], seq.tracks2[lo : t + 1],
                    sigma, spread, gate, tighten, prior_weight, hypotheses, max_iter,
                )  # fmt: skip
                tried.append((result, float(delta), moved))
            support = [-np.inf if r is None else r[1]["support"] for r, _, _ in tried]
            best = int(np.argmax(canonical_scores(np.array(support))))  # ties: smaller offset
            found, offset, here2 = tried[best]
        if found is None:
            scores = np.zeros((frame.n1, frame.n2))
            done, held = hold_partners(
                "temporal_pose", scores, threshold, started, seq.tracks1[t], seq.tracks2[t],
                held, margin, 0, {"window": window},
            )  # fmt: skip
            out.append(done)
            continue
        (turn, move), info = found
        cut = gate * tighten
        scores_by_frame = {
            s: prior_likelihood(q1[s], here2[s] @ turn.T + move, sigma, spread * tighten, cut)
            for s in range(lo, t + 1)
        }
        aligned = [scores_by_frame.get(s, np.zeros((0, 0))) for s in range(t + 1)]
        scores = accumulate(seq, aligned, t, window, "mean")
        o1, o2 = seq.odometry1[t], seq.odometry2[t]
        yaw = np.arctan2(turn[1, 0], turn[0, 0]) + o2[2] - o1[2]
        at = rotation(float(o1[2])).T @ (turn @ o2[:2] + move - o1[:2])
        info |= {"window": window, "relative_pose": [float(at[0]), float(at[1]), float(yaw)]}
        if len(offsets) > 1:
            info["time_offset_s"] = offset
        done, held = hold_partners(
            "temporal_pose", scores, threshold, started, seq.tracks1[t], seq.tracks2[t], held,
            margin, info["rounds"], info,
        )  # fmt: skip
        out.append(done)
    return out


temporal_pose.requires = PRIOR_FIELDS
temporal_pose.deterministic = True
temporal_pose.temporal = True
