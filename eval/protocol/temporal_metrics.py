"""Temporal association metrics for matchers run on sequences (issue 41).

Inputs per frame t: ``pairs[t]`` (k, 2) declared (i, j); ``true1[t]`` (n_t,) and ``true2[t]``
(m_t,) the true object id of each detection (-1: clutter, no object). The true pairs of a frame
are the (i, j) with ``true1[i] == true2[j] >= 0``.

* **Partner changes** (:func:`partner_changes`): a true object o of view 1 matched at t and at
  t + 1 to detections of *different* view-2 identities (true id; clutter is never the same
  identity twice) while o and its partner at t are both still visible at t + 1 — counted once
  per such (o, t), and reported per 100 covisible object-frames (the number of true pairs
  summed over frames). Consecutive frames only; a change *from* a wrong partner counts too.
* **Cross-agent IDSW** (:func:`cross_agent_idsw`): CLEAR-MOT's identity switches of the
  cross-agent links. A ground-truth detection is a true pair (named by its object), a tracker
  hypothesis a declared pair named by its two own track ids; a hypothesis matches a true pair
  when it is that pair. An IDSW is a true pair matched at t whose hypothesis id differs from
  the one it was last matched to (at any earlier frame, gaps allowed), per 100 covisible
  object-frames.
* **Frames to the first correct association** (:func:`frames_to_first_correct`): per object
  covisible at some frame, the frames from its first covisible frame to the first frame it is
  correctly matched (0: at once); objects never matched correctly are counted apart.
* **HOTA** (:func:`hota`, per-alpha counts :func:`hota_arrays`; over sequences
  :func:`combine_sequences`, TrackEval 1.3's ``HOTA.combine_sequences``: TP, FN, FP summed per
  alpha, AssA averaged per alpha weighted by each sequence's TP, then DetA and HOTA from those,
  then the mean over alphas), Luiten et al., IJCV 2021, as TrackEval computes it (PyPI ``trackeval``
  is a fork with opencv and pycocotools as hard dependencies: docs/matchers.md); for a
  correspondence sequence (:func:`correspondence_hota`) a "ground-truth detection" is a true
  pair, identified by its object, and a "tracker detection" a declared pair, identified by its
  pair of own track ids; similarity 1 when the declared pair is a true pair, else 0.
* **Time-offset error** (:func:`time_offset_error`): where a method estimates the age of the
  other agent's message (``temporal_pose``'s ``time_offset_s``), the absolute error against
  the true latency, seconds, over the frames that have an estimate.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

ALPHAS = np.arange(0.05, 0.99, 0.05)  # TrackEval's 19 localisation thresholds
_EPS = np.finfo(float).eps


def _partner_ids(pairs, true1, true2, t):
    """dict object id of view 1 -> identity of its view-2 partner at frame t."""
    out = {}
    for i, j in np.asarray(pairs, dtype=np.int64).reshape(-1, 2):
        obj = int(true1[i])
        if obj < 0:
            continue
        other = int(true2[j])
        out[obj] = other if other >= 0 else ("clutter", t, int(j))
    return out


def partner_changes(pairs, true1, true2) -> dict:
    """``switches``, ``object_frames`` (covisible) and ``per_100`` (module docstring)."""
    switches, object_frames = 0, 0
    partners = [
        _partner_ids(p, a, b, t)
        for t, (p, a, b) in enumerate(zip(pairs, true1, true2, strict=True))
    ]
    for t in range(len(pairs)):
        object_frames += int(len(np.intersect1d(true1[t][true1[t] >= 0], true2[t][true2[t] >= 0])))
        if t + 1 == len(pairs):
            break
        visible1, visible2 = set(true1[t + 1].tolist()), set(true2[t + 1].tolist())
        for obj, partner in partners[t].items():
            later = partners[t + 1].get(obj)
            stays = obj in visible1 and isinstance(partner, int) and partner in visible2
            if later is not None and stays and later != partner:
                switches += 1
    per_100 = 100.0 * switches / object_frames if object_frames else 0.0
    return {"switches": switches, "object_frames": object_frames, "per_100": per_100}


def frames_to_first_correct(pairs, true1, true2) -> dict:
    """``per_object`` {object: frames or None}, ``mean`` over those matched (NaN if none),
    ``never`` (count never matched correctly)."""
    first_seen: dict[int, int] = {}
    first_right: dict[int, int] = {}
    for t, (p, a, b) in enumerate(zip(pairs, true1, true2, strict=True)):
        for obj in np.intersect1d(a[a >= 0], b[b >= 0]).tolist():
            first_seen.setdefault(int(obj), t)
        for i, j in np.asarray(p, dtype=np.int64).reshape(-1, 2):
            if a[i] >= 0 and a[i] == b[j]:
                first_right.setdefault(int(a[i]), t)
    per_object = {
        o: (first_right[o] - s if o in first_right else None) for o, s in first_seen.items()
    }
    got = [v for v in per_object.values() if v is not None]
    return {
        "per_object": per_object,
        "mean": float(np.mean(got)) if got else float("nan"),
        "never": sum(v is None for v in per_object.values()),
    }


def hota(gt_ids: Sequence, tracker_ids: Sequence, similarity: Sequence) -> dict:
    """HOTA, DetA, AssA, LocA (means over :data:`ALPHAS`) of one sequence (arguments:
    :func:`hota_arrays`); all 0 (LocA 1 without ground truth) when either side is empty."""
    arrays = hota_arrays(gt_ids, tracker_ids, similarity)
    if arrays["TP"].sum() + arrays["FN"].sum() == 0 or arrays["TP"].sum() + arrays["FP"].sum() == 0:
        empty = arrays["FN"].sum() == 0
        return {"HOTA": 0.0, "DetA": 0.0, "AssA": 0.0, "LocA": 1.0 if empty else 0.0}
    return _final(arrays)


def _final(arrays: dict) -> dict:
    """HOTA, DetA, AssA, LocA (means over alphas) from per-alpha TP, FN, FP, AssA, LocA."""
    det_a = arrays["TP"] / np.maximum(1, arrays["TP"] + arrays["FN"] + arrays["FP"])
    return {
        "HOTA": float(np.mean(np.sqrt(det_a * arrays["AssA"]))),
        "DetA": float(np.mean(det_a)),
        "AssA": float(np.mean(arrays["AssA"])),
        "LocA": float(np.mean(arrays["LocA"])),
    }


def combine_sequences(per_sequence: Sequence[dict]) -> dict:
    """HOTA, DetA, AssA, LocA over sequences as TrackEval 1.3's ``HOTA.combine_sequences``:
    per alpha TP, FN, FP summed, AssA = Σ AssA_k TP_k / max(1, Σ TP_k), LocA = max(1e-10,
    Σ LocA_k TP_k) / max(1e-10, Σ TP_k); DetA = TP / max(1, TP + FN + FP), HOTA = sqrt(DetA ·
    AssA); each the mean over alphas. ``per_sequence``: :func:`hota_arrays` of each."""
    if not per_sequence:
        return {"HOTA": float("nan"), "DetA": float("nan"), "AssA": float("nan"),
                "LocA": float("nan")}  # fmt: skip
    tp = sum(a["TP"] for a in per_sequence)
    combined = {
        "TP": tp,
        "FN": sum(a["FN"] for a in per_sequence),
        "FP": sum(a["FP"] for a in per_sequence),
        "AssA": sum(a["AssA"] * a["TP"] for a in per_sequence) / np.maximum(1.0, tp),
        "LocA": np.maximum(1e-10, sum(a["LocA"] * a["TP"] for a in per_sequence))
        / np.maximum(1e-10, tp),
    }
    return _final(combined)


def hota_arrays(gt_ids: Sequence, tracker_ids: Sequence, similarity: Sequence) -> dict:
    """Per alpha of :data:`ALPHAS` (arrays of 19): ``TP``, ``FN``, ``FP`` (counts), ``AssA``,
    ``LocA`` of one sequence, as TrackEval's ``HOTA.eval_sequence`` leaves them. Per frame t:
    ``gt_ids[t]`` (g_t,) and ``tracker_ids[t]`` (k_t,) any hashable ids, ``similarity[t]``
    (g_t, k_t) in [0, 1]. Follows TrackEval's ``HOTA.eval_sequence`` step for step: the global
    alignment score from similarity-weighted potential matches, a per-frame Hungarian on it
    times the similarity, then per alpha the matches with similarity >= alpha."""
    gt_keys = {g: k for k, g in enumerate(dict.fromkeys(x for ids in gt_ids for x in ids))}
    tr_keys = {g: k for k, g in enumerate(dict.fromkeys(x for ids in tracker_ids for x in ids))}
    gts = [np.array([gt_keys[x] for x in ids], dtype=np.int64) for ids in gt_ids]
    trs = [np.array([tr_keys[x] for x in ids], dtype=np.int64) for ids in tracker_ids]
    sims = [
        np.asarray(s, dtype=float).reshape(len(g), len(k))
        for s, g, k in zip(similarity, gts, trs, strict=True)
    ]
    n_gt, n_tr = len(gt_keys), len(tr_keys)
    total_gt, total_tr = sum(map(len, gts)), sum(map(len, trs))
    if total_gt == 0 or total_tr == 0:  # TrackEval's early return
        zeros = np.zeros(len(ALPHAS))
        return {"TP": zeros, "FN": zeros + total_gt, "FP": zeros + total_tr,
                "AssA": zeros.copy(), "LocA": np.ones(len(ALPHAS))}  # fmt: skip
    potential = np.zeros((n_gt, n_tr))
    gt_count, tr_count = np.zeros((n_gt, 1)), np.zeros((1, n_tr))
    for g, k, s in zip(gts, trs, sims, strict=True):
        denom = s.sum(0)[None, :] + s.sum(1)[:, None] - s
        iou = np.where(denom > _EPS, s / np.where(denom > _EPS, denom, 1.0), 0.0)
        potential[g[:, None], k[None, :]] += iou
        gt_count[g] += 1
        tr_count[0, k] += 1
    alignment = potential / (gt_count + tr_count - potential)
    tp, fn, fp, loc = (np.zeros(len(ALPHAS)) for _ in range(4))
    matches = np.zeros((len(ALPHAS), n_gt, n_tr))
    for g, k, s in zip(gts, trs, sims, strict=True):
        if not len(g) or not len(k):
            fp += len(k)
            fn += len(g)
            continue
        rows, cols = linear_sum_assignment(-(alignment[g[:, None], k[None, :]] * s))
        for a, alpha in enumerate(ALPHAS):
            keep = s[rows, cols] >= alpha - _EPS
            r, c = rows[keep], cols[keep]
            tp[a] += len(r)
            fn[a] += len(g) - len(r)
            fp[a] += len(k) - len(r)
            loc[a] += s[r, c].sum()
            matches[a, g[r], k[c]] += 1
    ass_a = np.array(
        [(m * (m / np.maximum(1, gt_count + tr_count - m))).sum() for m in matches]
    ) / np.maximum(1, tp)
    loc_a = np.maximum(1e-10, loc) / np.maximum(1e-10, tp)
    return {"TP": tp, "FN": fn, "FP": fp, "AssA": ass_a, "LocA": loc_a}


def correspondence_hota(pairs, true1, true2, tracks1, tracks2, arrays: bool = False) -> dict:
    """:func:`hota` of a matcher's declared pairs over a sequence (module docstring):
    ``tracks1[t]``/``tracks2[t]`` the own track ids that name a declared pair over time;
    ``arrays``: :func:`hota_arrays`' per-alpha counts instead (for :func:`combine_sequences`)."""
    gt_ids, tr_ids, sims = [], [], []
    for p, a, b, ta, tb in zip(pairs, true1, true2, tracks1, tracks2, strict=True):
        p = np.asarray(p, dtype=np.int64).reshape(-1, 2)
        ti, tj = np.nonzero((a[:, None] == b[None, :]) & (a[:, None] >= 0))
        gt_ids.append([int(a[i]) for i in ti])
        tr_ids.append([(int(ta[i]), int(tb[j])) for i, j in p])
        sims.append((ti[:, None] == p[None, :, 0]) & (tj[:, None] == p[None, :, 1]))
    return (hota_arrays if arrays else hota)(gt_ids, tr_ids, sims)


def cross_agent_idsw(pairs, true1, true2, tracks1, tracks2) -> dict:
    """``idsw`` (CLEAR-MOT identity switches of the cross-agent links, module docstring),
    ``object_frames`` (covisible) and ``per_100``.

    >>> t = [np.array([0, 1])] * 3
    >>> cross_agent_idsw([np.array([[0, 0]])] * 3, t, t, [np.array([5, 6]), np.array([7, 6]),
    ...                  np.array([7, 6])], t)["idsw"]
    1
    """
    last: dict[int, tuple[int, int]] = {}
    idsw, object_frames = 0, 0
    for p, a, b, ta, tb in zip(pairs, true1, true2, tracks1, tracks2, strict=True):
        object_frames += int(len(np.intersect1d(a[a >= 0], b[b >= 0])))
        for i, j in np.asarray(p, dtype=np.int64).reshape(-1, 2):
            if a[i] < 0 or a[i] != b[j]:
                continue
            obj, hyp = int(a[i]), (int(ta[i]), int(tb[j]))
            idsw += obj in last and last[obj] != hyp
            last[obj] = hyp
    per_100 = 100.0 * idsw / object_frames if object_frames else 0.0
    return {"idsw": int(idsw), "object_frames": object_frames, "per_100": per_100}


def time_offset_error(estimates: Sequence[float | None], true_s: float) -> dict:
    """{"mean_abs_s", "median_abs_s", "max_abs_s", "frames"}: the absolute error (s) of the
    per-frame time-offset ``estimates`` (None: no estimate that frame, left out) against the
    true latency ``true_s``; NaN errors and 0 frames when no frame has one.

    >>> time_offset_error([0.1, None, 0.15], 0.1)["mean_abs_s"]
    0.025
    """
    found = np.array([e for e in estimates if e is not None], dtype=float)
    if not found.size:
        nan = float("nan")
        return {"mean_abs_s": nan, "median_abs_s": nan, "max_abs_s": nan, "frames": 0}
    error = np.abs(found - float(true_s))
    return {
        "mean_abs_s": float(np.round(error.mean(), 12)),
        "median_abs_s": float(np.round(np.median(error), 12)),
        "max_abs_s": float(np.round(error.max(), 12)),
        "frames": int(found.size),
    }


SPEED_BANDS = (("static", 0.0, 0.5), ("slow", 0.5, 10.0), ("fast", 10.0, np.inf))  # m/s


def track_continuity(tracks, true, speeds, bands=SPEED_BANDS) -> dict:
    """One agent's own tracker against the truth: per speed band (name, low, high m/s) the
    links kept, ``{"band": (kept, links)}``. A *link* is a true object detected in two
    consecutive frames t, t + 1 of the view (``true[t]`` ids, -1 clutter); it is *kept* when both
    detections carry the same own track id (``tracks[t]``). The band is the object's true speed
    at t (``speeds[t]``, m/s, per detection).

    >>> track_continuity([np.array([3]), np.array([3]), np.array([4])],
    ...                  [np.array([0])] * 3, [np.array([12.0])] * 3)["fast"]
    (1, 2)
    """
    out = {name: [0, 0] for name, _, _ in bands}
    for t in range(len(tracks) - 1):
        a, b = np.asarray(true[t]), np.asarray(true[t + 1])
        common, i, j = np.intersect1d(a, b, assume_unique=True, return_indices=True)
        keep = common >= 0
        i, j = i[keep], j[keep]
        same = np.asarray(tracks[t])[i] == np.asarray(tracks[t + 1])[j]
        speed = np.asarray(speeds[t], dtype=float)[i]
        for name, low, high in bands:
            inside = (speed >= low) & (speed < high)
            out[name][0] += int(same[inside].sum())
            out[name][1] += int(inside.sum())
    return {name: (kept, links) for name, (kept, links) in out.items()}
