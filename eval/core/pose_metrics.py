"""Pose metrics: the relative pose between the two vehicles that a matcher's declared matches
recover, scored against the true one (V2X-Reg++'s success@λ, FreeAlign's and CoAlign's pose
errors). One implementation for every matcher, table and sweep.

From the declared matches (i, j) — view 1 detection i is view 2 detection j — the least-squares
rigid transform T (rotation R, translation t; no scale) with p1_i ≈ R p2_j + t is fitted by the
Kabsch/Umeyama SVD on the detections' 3-D positions (metres, each view's camera frame). Fewer
than 3 matches, or matches whose view-2 points are (nearly) collinear, leave the rotation
undetermined: the fit *fails*. Against the true transform (view 2's camera at the time its
message was made, into view 1's camera: ``FramePair.true_relative_pose``):

    RTE = ||t − t_true||  (m)        RRE = angle of R R_trueᵀ  (degrees)

success@(1 m, 2°) and success@(2 m, 5°): RTE and RRE both within the bounds. A failed fit
counts as unsuccessful, is left out of the medians and is counted in ``pose_failure_rate``.
The localisation prior's own error (what a vehicle has with no matching) is the same two numbers
for the transform its two noisy poses imply (:func:`prior_transform`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from matchers.blocks.local_context import prior_motion
from matchers.blocks.local_context import rigid_fit as fit_motion

MIN_MATCHES = 3  # fewer matches, or collinear ones (the rotation about the line is free): a failure
SUCCESS_BOUNDS: tuple[tuple[float, float], ...] = ((1.0, 2.0), (2.0, 5.0))
"""(RTE m, RRE degrees) of the success rates reported."""
RTE_DECIMALS = 4  # 0.1 mm
RRE_DECIMALS = 4  # 0.0001°
"""Every RTE and RRE is rounded to these decimals (DESIGN §10): the fit's SVD and products run
in BLAS/LAPACK, whose kernels differ by CPU in the last bits, and the arccos of a rotation
within microdegrees of the truth turns those bits into differences of ~1e-6°."""
COLUMNS = (
    "rte_m_median",
    "rre_deg_median",
    "success_1m_2deg",
    "success_2m_5deg",
    "pose_failure_rate",
)


def rigid_fit(src: np.ndarray, dst: np.ndarray) -> np.ndarray | None:
    """4x4 rigid transform T with dst ≈ R src + t in least squares (Kabsch; a proper rotation,
    :func:`matchers.blocks.local_context.rigid_fit`), or None with fewer than
    :data:`MIN_MATCHES` points or collinear ``src``. src, dst: (k, 3)."""
    src = np.asarray(src, dtype=float).reshape(-1, 3)
    return _homogeneous(fit_motion(src, np.asarray(dst, dtype=float).reshape(-1, 3)))


def _homogeneous(motion: tuple[np.ndarray, np.ndarray] | None) -> np.ndarray | None:
    """A (R (3, 3), t (3,)) motion as a 4x4 transform; None stays None."""
    if motion is None:
        return None
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = motion
    return out


def pose_error(estimate: np.ndarray | None, truth: np.ndarray) -> tuple[float, float]:
    """(RTE metres, RRE degrees) of a 4x4 estimate against the 4x4 truth; (nan, nan) when the
    estimate is None (a failed fit)."""
    if estimate is None:
        return float("nan"), float("nan")
    estimate, truth = np.asarray(estimate, dtype=float), np.asarray(truth, dtype=float)
    rte = float(np.linalg.norm(estimate[:3, 3] - truth[:3, 3]))
    cos = (np.trace(estimate[:3, :3] @ truth[:3, :3].T) - 1.0) / 2.0
    rre = float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
    return round(rte, RTE_DECIMALS), round(rre, RRE_DECIMALS)


def matched_pose_error(
    points1: np.ndarray, points2: np.ndarray, pairs: np.ndarray, truth: np.ndarray
) -> tuple[float, float]:
    """(RTE, RRE) of the transform fitted to the declared matches ``pairs`` ((k, 2) int (i, j))
    between view 2's ``points2`` and view 1's ``points1``; (nan, nan) for a failed fit."""
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    fit = rigid_fit(np.asarray(points2)[pairs[:, 1]], np.asarray(points1)[pairs[:, 0]])
    return pose_error(fit, truth)


def prior_transform(
    points1: np.ndarray, world1: np.ndarray, points2: np.ndarray, world2: np.ndarray
) -> np.ndarray | None:
    """The 4x4 view-2-to-view-1 transform the localisation prior implies
    (:func:`matchers.blocks.local_context.prior_motion`: each view's positions against its own
    noisy world positions); None when a view has too few non-collinear detections."""
    return _homogeneous(prior_motion(points1, world1, points2, world2))


def summarise(rte: Sequence[float], rre: Sequence[float]) -> dict[str, float]:
    """The :data:`COLUMNS` of per-pair errors (nan: a failed fit): medians over successful fits
    (nan when every fit failed), success rates and the failure rate over all pairs."""
    rte, rre = np.asarray(rte, dtype=float), np.asarray(rre, dtype=float)
    if not rte.size:
        return dict.fromkeys(COLUMNS, float("nan"))
    ok = np.isfinite(rte) & np.isfinite(rre)
    out = {
        "rte_m_median": float(np.median(rte[ok])) if ok.any() else float("nan"),
        "rre_deg_median": float(np.median(rre[ok])) if ok.any() else float("nan"),
    }
    for (metres, degrees), key in zip(SUCCESS_BOUNDS, COLUMNS[2:4], strict=True):
        out[key] = float(np.mean(ok & (rte <= metres) & (rre <= degrees)))
    out["pose_failure_rate"] = float(np.mean(~ok))
    return out


def outcome_pose(outcome, pairs: np.ndarray) -> dict[str, float | bool]:
    """Per-pair pose columns of one outcome (``eval.core.tasks.PairOutcome``) with its declared
    matches ``pairs``: ``pose_scored`` (a true pose is known), ``rte_m``/``rre_deg`` (NaN for a
    failed fit or none scored), and the prior's own ``prior_rte_m``/``prior_rre_deg`` with
    ``prior_scored`` (the run had a prior)."""
    scored = outcome.true_pose is not None and outcome.points1 is not None
    rte, rre = (
        matched_pose_error(outcome.points1, outcome.points2, pairs, outcome.true_pose)
        if scored
        else (float("nan"), float("nan"))
    )
    prior = outcome.prior_error
    return {
        "pose_scored": bool(scored),
        "rte_m": rte,
        "rre_deg": rre,
        "prior_scored": prior is not None,
        "prior_rte_m": float("nan") if prior is None else prior[0],
        "prior_rre_deg": float("nan") if prior is None else prior[1],
    }


def summarise_pose(per_pair, by: Sequence[str], prefix: str = ""):
    """One row per ``by`` group of a per-pair table (columns of :func:`outcome_pose`) with the
    :data:`COLUMNS` over its scored pairs and runs pooled (``prefix`` "prior_": the prior's own
    error); groups with nothing scored are left out."""
    import pandas as pd

    flag = "prior_scored" if prefix else "pose_scored"
    if flag not in per_pair.columns:
        return pd.DataFrame(columns=[*by, *COLUMNS])
    scored = per_pair[per_pair[flag].astype(bool)]
    rows = []
    for key, group in scored.groupby(list(by), sort=False):
        key = key if isinstance(key, tuple) else (key,)
        summary = summarise(group[f"{prefix}rte_m"], group[f"{prefix}rre_deg"])
        rows.append(dict(zip(by, key, strict=True)) | summary)
    return pd.DataFrame(rows, columns=[*by, *COLUMNS])
