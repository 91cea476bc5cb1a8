"""``v2x_reg``: V2X-Reg++'s box association (Zhang et al., "V2X-Reg++: A Real-Time Global
Registration Method for Multi-End Sensing System in Urban Intersections", T-ITS 2025; the
v2i-calib repository), implemented from the paper's and repository's description, pose-free.

1. Box selection (:func:`~matchers.blocks.box_selection.top_k_boxes`): each view's boxes
   within 120 m of its sensor, bus / truck / car first, the first ``top_k``.
2. Hypotheses: every pair (i, j) of selected boxes of the same class proposes the rigid motion
   that lays view 2's box j onto view 1's box i — here on the ground plane: the yaw that turns
   j's heading onto i's (and the flipped one, a box's front and back being alike; the better of
   the two counts), the shift that then joins their centres.
3. Affinity KP_ij: view 2's selected boxes moved by that motion; a box of view 1 and one of view
   2 of the same class correspond when their centres lie within the class's distance (car 1.0
   m; truck, van, bus 1.5 m; pedestrian, cyclist, cone and the other small classes 0.5 m;
   others 1.0 m; × ``distance_scale``); KP_ij = the number of corresponding boxes − 1 (the pair
   itself not counted).
4. Matches: Hungarian on KP; pairs with KP ≥ ``min_support`` are kept (their
   "thresholdRetained", 4), or, when the best KP is 5 or less, the pairs with the best KP.

Scores: (KP + 1) / min(n, m) of the kept pairs — the share of the smaller view that the pair's
motion aligns — 0 elsewhere; then the shared Hungarian + threshold. The extrinsic V2X-Reg++
solves next (weighted SVD over the matched boxes' corners) is cadsim's one pose fit of every
matcher's matches (eval.core.pose_metrics).

Where we differ, and why: a :class:`~matchers.core.problem.Problem` holds box centres, classes
and (box-only records) headings, not corners: the distance is the centres' (theirs averages the
centre distance and the mean corner distance), the motion is planar, correspondences are
counted one-to-one as min(view-1 boxes with a partner, view-2 boxes with a partner) rather than
greedily, and without headings (camera detections) a pair's yaws are those that also align
one of each box's 3 nearest same-view neighbours with one of the other's (9 hypotheses). The selection ranks by range where theirs ranks by
volume. Imports nothing from ``cadsim`` or ``eval``.
"""

from __future__ import annotations

import time

import numpy as np

from matchers.blocks.box_selection import DISTANCE_M, ground_xy, top_k_boxes
from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.options import check_count, check_range, rng_from_seed
from matchers.core.problem import Problem
from matchers.core.result import finish

CLASS_DISTANCE_M = {
    "car": 1.0,
    "truck": 1.5,
    "van": 1.5,
    "bus": 1.5,
    "pedestrian": 0.5,
    "cyclist": 0.5,
    "motorcyclist": 0.5,
    "tricyclist": 0.5,
    "barrowlist": 0.5,
    "trafficcone": 0.5,
}
"""Correspondence distance per class (metres; V2X-Reg++'s configuration)."""
OTHER_DISTANCE_M = 1.0
CHUNK = 256  # hypotheses scored at once: (CHUNK, n, m) residuals
NEAREST = 3  # without headings: the neighbours whose directions propose a pair's yaw


def _classes(names, k: int) -> np.ndarray:
    return np.array([str(c).lower() for c in names] if names is not None else [""] * k)


def _yaws(g1, g2, rows, cols, headings, same1, same2) -> np.ndarray:
    """(P, 2) candidate yaws (radians, on the ground plane's (x, z)) of the pairs (rows, cols)."""
    if headings is not None:
        h1, h2 = headings
        base = h2[cols] - h1[rows]  # turns heading (sin h, cos h) of j onto i's
        return np.stack([base, base + np.pi], axis=1)
    # no headings: the yaws that also lay one of each box's nearest same-view neighbours on one
    # of the other's (every combination of the NEAREST nearest of each)
    u1 = g1[same1[rows]] - g1[rows, None]  # (P, a, 2)
    u2 = g2[same2[cols]] - g2[cols, None]  # (P, b, 2)
    a1, a2 = np.arctan2(u1[..., 1], u1[..., 0]), np.arctan2(u2[..., 1], u2[..., 0])
    return (a1[:, :, None] - a2[:, None, :]).reshape(len(rows), -1)


def _nearest(g: np.ndarray) -> np.ndarray:
    """(k, NEAREST) indices of each point's nearest other points (repeated when there are fewer;
    the point itself when alone)."""
    if len(g) < 2:
        return np.repeat(np.arange(len(g))[:, None], NEAREST, axis=1)
    d = np.hypot(*(g[:, None, :] - g[None, :, :]).transpose(2, 0, 1))
    np.fill_diagonal(d, np.inf)
    order = np.argsort(d, axis=1, kind="stable")[:, : min(NEAREST, len(g) - 1)]
    return np.pad(order, ((0, 0), (0, NEAREST - order.shape[1])), mode="edge")


def affinity(
    g1: np.ndarray,
    g2: np.ndarray,
    classes1: np.ndarray,
    classes2: np.ndarray,
    headings: tuple[np.ndarray, np.ndarray] | None,
    distance_scale: float = 1.0,
) -> np.ndarray:
    """(n, m) KP of steps 2-3 (module docstring) on ground-plane centres ``g1`` (n, 2) and ``g2``
    (m, 2); −1 for pairs of different classes."""
    n, m = len(g1), len(g2)
    same = classes1[:, None] == classes2[None, :]
    kp = np.full((n, m), -1.0)
    rows, cols = np.nonzero(same)
    if not len(rows):
        return kp
    radius = np.array([CLASS_DISTANCE_M.get(c, OTHER_DISTANCE_M) for c in classes1])
    radius = radius * distance_scale
    yaws = _yaws(g1, g2, rows, cols, headings, _nearest(g1), _nearest(g2))  # (P, 2)
    best = np.full(len(rows), -1.0)
    for flip in range(yaws.shape[1]):
        for start in range(0, len(rows), CHUNK):
            r, c = rows[start : start + CHUNK], cols[start : start + CHUNK]
            cos, sin = (
                np.cos(yaws[start : start + CHUNK, flip]),
                np.sin(yaws[start : start + CHUNK, flip]),
            )
            turn = np.stack([np.stack([cos, -sin], -1), np.stack([sin, cos], -1)], -2)  # (h, 2, 2)
            shift = g1[r] - np.einsum("hab,hb->ha", turn, g2[c])
            moved = np.einsum("hab,mb->hma", turn, g2) + shift[:, None, :]  # (h, m, 2)
            gap = np.linalg.norm(g1[None, :, None, :] - moved[:, None, :, :], axis=-1)
            near = (gap < radius[None, :, None]) & same[None]
            count = np.minimum(near.any(axis=2).sum(axis=1), near.any(axis=1).sum(axis=1))
            best[start : start + CHUNK] = np.maximum(best[start : start + CHUNK], count - 1.0)
    kp[rows, cols] = best
    return kp


def v2x_memory(problem: Problem, top_k=25, **options) -> float:
    """Bytes of :func:`v2x_reg`'s largest arrays: a chunk of hypotheses' (h, n, m) residuals
    and masks over the selected boxes, and the per-pair yaws (9 without headings)."""
    n, m = problem.n1, problem.n2
    if isinstance(top_k, int | np.integer) and not isinstance(top_k, bool) and top_k > 0:
        n, m = min(n, int(top_k)), min(m, int(top_k))
    pairs = float(n * m)
    return 40.0 * min(CHUNK, pairs) * pairs + 8.0 * NEAREST**2 * pairs + 64.0 * pairs


@budgeted(v2x_memory, "the number of objects or top_k")
def v2x_reg(
    problem: Problem,
    seed: int | None = 0,
    threshold: float | None = None,
    *,
    top_k: int = 25,
    distance_scale: float = 1.0,
    min_support: int = 4,
    distance_m: float = DISTANCE_M,
) -> Matching:
    """V2X-Reg++'s association (module docstring): ``top_k`` (25; 0: every box) boxes per view
    within ``distance_m`` (120 m), correspondence distances × ``distance_scale`` (1), pairs
    kept with KP ≥ ``min_support`` (4). Uses classes (``problem.classes1/2``; all one class
    without) and, when the problem's ``meta["headings"]`` gives both views' box headings
    (radians, ``atan2(d_x, d_z)`` in the camera-frame convention), the boxes' yaw. Needs no
    prior and no features. Deterministic; ``seed`` unused.

    >>> rng = np.random.default_rng(4)
    >>> xz = rng.uniform(-30, 30, (6, 2))
    >>> pts = np.column_stack([xz[:, 0], np.zeros(6), xz[:, 1]])
    >>> turn = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # a quarter turn
    >>> p = Problem(pts, (pts - [5.0, 0.0, 2.0]) @ turn, classes1=("car",) * 6, classes2=("car",) * 6)
    >>> v2x_reg(p, threshold=0.5).pairs.tolist()
    [[0, 0], [1, 1], [2, 2], [3, 3], [4, 4], [5, 5]]
    """
    started = time.perf_counter()
    rng_from_seed(seed)
    top_k = int(check_range("top_k", top_k, 0, 10_000))
    distance_scale = check_range("distance_scale", distance_scale, 0.0, 100.0, open_low=True)
    check_count("min_support", min_support)
    distance_m = check_range("distance_m", distance_m, 0.0, 1e6, open_low=True)
    n, m = problem.n1, problem.n2
    scores = np.zeros((n, m))
    sel1 = top_k_boxes(problem.points1, problem.classes1, top_k, distance_m)
    sel2 = top_k_boxes(problem.points2, problem.classes2, top_k, distance_m)
    info = {"selected": [len(sel1), len(sel2)]}
    if not len(sel1) or not len(sel2):
        return finish("v2x_reg", scores, threshold, started, 0, info)
    headings = (problem.meta or {}).get("headings")
    if headings is not None:
        h1, h2 = (np.asarray(h, dtype=float).reshape(-1) for h in headings)
        headings = (h1[sel1], h2[sel2]) if (len(h1), len(h2)) == (n, m) else None
    kp = affinity(
        ground_xy(problem.points1)[sel1], ground_xy(problem.points2)[sel2],
        _classes(problem.classes1, n)[sel1], _classes(problem.classes2, m)[sel2],
        headings, distance_scale,
    )  # fmt: skip
    top = kp.max()
    keep = kp >= (min_support if top > 5 else top)
    kept = np.where(keep & (kp > 0), (kp + 1.0) / min(len(sel1), len(sel2)), 0.0)
    scores[np.ix_(sel1, sel2)] = np.clip(kept, 0.0, 1.0)
    info |= {"best_support": float(top), "headings": headings is not None}
    return finish("v2x_reg", scores, threshold, started, 1, info)


v2x_reg.deterministic = True  # the result does not depend on `seed`

__all__ = ["CLASS_DISTANCE_M", "affinity", "v2x_memory", "v2x_reg"]
