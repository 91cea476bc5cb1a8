"""One agent's own tracker for traffic: constant velocity, a gate that grows with speed and
time, confirmation and deletion. It sees only the agent's own detections and odometry (never
a true id).

Every detection is first put into the agent's frame-0 ground plane
(:func:`matchers.core.sequence_problem.ground_positions`), where a parked object stands still
whatever the agent does. A track k holds a position p_k and a velocity v_k (m/s) in that plane,
its hit count h_k and the frame it was last seen. Frame t, Δ_k = (t - seen_k) · dt seconds
(dt: ``interval_s``):

    predicted_k = p_k + v_k · Δ_k
    gate_k      = gate + speed_gate · |v_k| · Δ_k      (h_k >= 2: velocity known)
                = gate + max_speed · Δ_k               (h_k = 1: any speed up to max_speed)
    e           = predicted_k - z_d,  split along u_d (the unit ray from the agent's sensor
                  to z_d) and across it
    cost_kd     = sqrt((e·u_d / (gate_k + range_gate · r_d²))² + (|e × u_d| / gate_k)²)
                                                       (> 1: forbidden)

r_d (m) is the detection's range from the sensor (``origins``): a camera's depth error grows with
the square of the depth and lies along the ray (σ = noise_rate · d², docs/scenarios.md), so the
gate is stretched along the ray by ``range_gate`` · r² and not across it (0, or no origins: a
round gate).

Confirmed tracks (h_k >= ``confirm``) are assigned first (Hungarian on cost), the tentative ones
then take what is left (a cascade: a new track never steals a detection from a confirmed one).
A detection taken by a track updates it:

    second hit   v_k = (z_d - p_k) / Δ_k,  p_k = z_d     (velocity from the first two detections)
    later hits   r = z_d - predicted_k,  p_k = predicted_k + alpha · r,  v_k += beta · r / Δ_k

(an alpha-beta filter: the steady-state Kalman filter of a constant-velocity model). The other
detections start tentative tracks. A confirmed track unseen for more than ``max_age`` frames is
deleted, a tentative one after ``tentative_age`` frames. Track ids are 0, 1, 2, … in order of
creation. Distances read the canonical grid (:func:`~matchers.core.discretise.canonical_scores`,
2^-40) so that equal costs tie exactly, the same way on every CPU. The loop runs over frames; each
frame's costs are one vectorised array. Why our own rather than a library: docs/matchers.md
("Each agent's own tracks").
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from matchers.core.discretise import canonical_scores
from matchers.core.options import check_count, check_range

_FORBIDDEN = 1e9


def _assign(cost: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of the Hungarian assignment of normalised ``cost`` with cost > 1 forbidden."""
    if not cost.size:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    rows, cols = linear_sum_assignment(np.where(cost <= 1.0, cost, _FORBIDDEN))
    keep = cost[rows, cols] <= 1.0
    return rows[keep], cols[keep]


def _cost(
    predicted: np.ndarray, reach: np.ndarray, xy: np.ndarray, ray: np.ndarray, stretch: np.ndarray
) -> np.ndarray:
    """(k, d) normalised cost of tracks (predicted (k, 2), gate ``reach`` (k,)) against
    detections ``xy`` (d, 2) with unit rays (d, 2) (zero: no direction) and stretch (d,)."""
    e = predicted[:, None, :] - xy[None, :, :]
    along = (e * ray[None]).sum(-1)
    across = e[..., 0] * ray[None, :, 1] - e[..., 1] * ray[None, :, 0]
    round_ = ~np.any(ray, axis=1)[None, :]
    across = np.where(round_, np.linalg.norm(e, axis=-1), across)
    g = reach[:, None]
    cost = np.hypot(along / (g + stretch[None, :]), across / g)
    return canonical_scores(cost)


def link(
    positions: list[np.ndarray],
    interval_s: float = 0.2,
    gate: float = 1.5,
    speed_gate: float = 0.5,
    max_speed: float = 15.0,
    alpha: float = 0.6,
    beta: float = 0.3,
    confirm: int = 2,
    max_age: int = 2,
    tentative_age: int = 1,
    range_gate: float = 0.002,
    origins: np.ndarray | None = None,
) -> list[np.ndarray]:
    """Per frame, the (n_t,) int track id of each of the (n_t, 2) ``positions`` (one agent's
    detections in its frame-0 ground plane, metres; frames ``interval_s`` seconds apart).
    ``gate`` (m): the gate of a track at its predicted position; ``speed_gate`` (s): added
    metres per m/s of the track's speed per second unseen; ``max_speed`` (m/s): the fastest
    object a track seen once may be; ``alpha``, ``beta``: the filter's gains; ``confirm``: hits
    before a track is confirmed; ``max_age`` / ``tentative_age``: frames a confirmed / tentative
    track may go unseen and still continue; ``range_gate`` (1/m): the gate's stretch along the
    ray per squared metre of range, ``origins`` (T, 2) the sensor's position per frame in the
    same plane (None: no stretch) (module docstring). Defaults chosen on cad-v2x-seq's
    validation split (docs/matchers.md, "Each agent's own tracks").

    >>> frames = [np.array([[0.0, 0.0], [9.0, 5.0]]), np.array([[3.0, 0.0], [9.1, 5.0]])]
    >>> [ids.tolist() for ids in link(frames + [np.array([[6.0, 0.0], [9.0, 5.1]])])]
    [[0, 1], [0, 1], [0, 1]]
    """
    dt = check_range("interval_s", interval_s, 0.0, 1e6, open_low=True)
    gate = check_range("gate", gate, 0.0, 1e6, open_low=True)
    speed_gate = check_range("speed_gate", speed_gate, 0.0, 1e6)
    max_speed = check_range("max_speed", max_speed, 0.0, 1e6)
    alpha = check_range("alpha", alpha, 0.0, 1.0)
    beta = check_range("beta", beta, 0.0, 2.0)
    confirm = check_count("confirm", confirm)
    max_age = check_count("max_age", max_age)
    tentative_age = check_count("tentative_age", tentative_age)
    range_gate = check_range("range_gate", range_gate, 0.0, 1e6)
    if origins is not None:
        origins = np.asarray(origins, dtype=float).reshape(-1, 2)
        if len(origins) != len(positions):
            raise ValueError(f"origins: expected {len(positions)} rows, got {len(origins)}")
    pos = np.zeros((0, 2))
    vel = np.zeros((0, 2))
    hits = np.zeros(0, dtype=np.int64)
    seen = np.zeros(0, dtype=np.int64)
    out: list[np.ndarray] = []
    for t, xy in enumerate(positions):
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        ids = np.full(len(xy), -1, dtype=np.int64)
        ray, stretch = np.zeros_like(xy), np.zeros(len(xy))
        if origins is not None and range_gate > 0 and len(xy):
            offset = xy - origins[t]
            distance = np.linalg.norm(offset, axis=1)
            ray = offset / np.maximum(distance, 1e-9)[:, None]
            stretch = range_gate * distance**2
        age = t - seen
        confirmed = hits >= confirm
        alive = np.where(confirmed, age <= max_age, age <= tentative_age)
        elapsed = age * dt
        predicted = pos + vel * elapsed[:, None]
        reach = np.where(
            hits >= 2,
            gate + speed_gate * np.linalg.norm(vel, axis=1) * elapsed,
            gate + max_speed * elapsed,
        )
        free = np.ones(len(xy), dtype=bool)
        for stage in (alive & confirmed, alive & ~confirmed):  # the cascade
            tracks = np.flatnonzero(stage)
            dets = np.flatnonzero(free)
            if not (len(tracks) and len(dets)):
                continue
            cost = _cost(predicted[tracks], reach[tracks], xy[dets], ray[dets], stretch[dets])
            rows, cols = _assign(cost)
            k, d = tracks[rows], dets[cols]
            ids[d] = k
            free[d] = False
            first = hits[k] == 1
            span = elapsed[k][:, None]
            residual = xy[d] - predicted[k]
            vel[k] = np.where(
                first[:, None], (xy[d] - pos[k]) / span, vel[k] + beta * residual / span
            )
            pos[k] = np.where(first[:, None], xy[d], predicted[k] + alpha * residual)
            hits[k] += 1
            seen[k] = t
        new = np.flatnonzero(ids < 0)
        ids[new] = len(pos) + np.arange(len(new))
        pos = np.concatenate([pos, xy[new]])
        vel = np.concatenate([vel, np.zeros((len(new), 2))])
        hits = np.concatenate([hits, np.ones(len(new), dtype=np.int64)])
        seen = np.concatenate([seen, np.full(len(new), t, dtype=np.int64)])
        out.append(ids)
    return out
