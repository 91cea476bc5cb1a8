"""The robust planar fit of the pose metrics: gross outliers among the true matches are
downweighted, so the oracle (every true match) stays the ceiling of a matcher that drops them."""

from __future__ import annotations

import numpy as np
from test_v2x_baselines import _mounted

from eval.core.pose_metrics import (
    match_scales,
    matched_planar_error,
    planar_fit,
    pose_error,
    robust_ground_motion,
)
from matchers.blocks.rigid2d import procrustes_2d


def _with_outliers(seed: int, shared: int = 10, bad: int = 3, noise: float = 0.05):
    """A planted mounted frame (:func:`test_v2x_baselines._mounted`): view 2's detections carry
    a camera's position error, N(0, (noise · (d / 30 m)²)²) per axis at range d, and the first
    ``bad`` true matches' view-2 detections are 6–9 m off (a gross detection error); (points1,
    points2, true pairs, mounts, truth, indices of the bad pairs in ``pairs``)."""
    p1, p2, pairs, mounts, truth = _mounted(seed, shared=shared)
    rng = np.random.default_rng(seed + 100)
    ranges = np.linalg.norm(p2, axis=1, keepdims=True)
    p2 = p2 + rng.normal(0.0, 1.0, p2.shape) * noise * (ranges / 30.0) ** 2
    worst = np.arange(bad)
    offset = rng.uniform(6.0, 9.0, bad)[:, None] * np.array([[1.0, 0.0, 0.0]])
    p2 = p2.copy()
    p2[pairs[worst, 1]] += offset * rng.choice([-1.0, 1.0], (bad, 1))
    return p1, p2, pairs, mounts, truth, worst


def _least_squares_error(p1, p2, pairs, mounts, truth) -> tuple[float, float]:
    """(RTE, RRE) of the plain least-squares planar fit (the fit before the robust one)."""
    a = p2[pairs[:, 1]] @ mounts[1][:3, :3].T + mounts[1][:3, 3]
    b = p1[pairs[:, 0]] @ mounts[0][:3, :3].T + mounts[0][:3, 3]
    turn, shift = procrustes_2d(a[:, :2], b[:, :2], np.ones(len(a)))
    body = np.eye(4)
    body[:2, :2], body[:2, 3], body[2, 3] = turn, shift, np.mean(b[:, 2] - a[:, 2])
    return pose_error(np.linalg.inv(mounts[0]) @ body @ mounts[1], truth)


def test_the_robust_fit_recovers_the_motion_that_gross_outliers_pull_least_squares_from():
    for seed in range(3):
        p1, p2, pairs, mounts, truth, _ = _with_outliers(seed)
        rte, rre = matched_planar_error(p1, p2, pairs, mounts, truth)
        assert rte < 0.1 and rre < 0.3, (seed, rte, rre)  # 5 cm noise at 30 m, 7 good matches
        ls_rte, ls_rre = _least_squares_error(p1, p2, pairs, mounts, truth)
        assert ls_rte > 1.0, (seed, ls_rte, ls_rre)  # 3 of 10 matches off by 6–9 m
        assert ls_rte > 10 * rte and ls_rre > 5 * rre


def test_the_robust_fit_is_exact_without_noise_and_its_outliers_carry_little_weight():
    p1, p2, pairs, mounts, truth = _mounted(5, shared=8)
    fit = planar_fit(p2[pairs[:, 1]], p1[pairs[:, 0]], mounts[1], mounts[0])
    np.testing.assert_allclose(fit, truth, atol=1e-9)
    p1, p2, pairs, mounts, truth, worst = _with_outliers(6, noise=0.0)
    src, dst = p2[pairs[:, 1]], p1[pairs[:, 0]]
    a = src @ mounts[1][:3, :3].T + mounts[1][:3, 3]
    b = dst @ mounts[0][:3, :3].T + mounts[0][:3, 3]
    scales = match_scales(src, dst)
    _, _, weight = robust_ground_motion(a[:, :2], b[:, :2], scales)
    trust = weight * scales**2  # the Cauchy factor 1 / (1 + (r / c s)²), the range scaling out
    good = np.setdiff1d(np.arange(len(pairs)), worst)
    assert trust[worst].max() < 0.2 and trust[good].min() > 0.99
    rte, rre = matched_planar_error(p1, p2, pairs, mounts, truth)
    assert rte < 0.1 and rre < 0.2  # Cauchy's pull of an outlier fades but never quite ends


def test_the_fit_is_deterministic_to_the_bit():
    p1, p2, pairs, mounts, _, _ = _with_outliers(7, noise=0.3)
    fits = [planar_fit(p2[pairs[:, 1]], p1[pairs[:, 0]], mounts[1], mounts[0]) for _ in range(2)]
    assert fits[0].tobytes() == fits[1].tobytes()


def test_the_2d_motion_does_not_move_when_numpys_transcendentals_move_by_an_ulp():
    """As on a CPU whose SIMD exp/log/arctan differ in the last bit (tests/cpu_dispatch.py)."""
    from cpu_dispatch import TRANSCENDENTAL, inject_ulp_faults

    p1, p2, pairs, mounts, _, _ = _with_outliers(8, noise=0.5)
    src, dst = p2[pairs[:, 1]], p1[pairs[:, 0]]
    a = src @ mounts[1][:3, :3].T + mounts[1][:3, 3]
    b = dst @ mounts[0][:3, :3].T + mounts[0][:3, 3]

    def motion() -> bytes:
        fit = robust_ground_motion(a[:, :2], b[:, :2], match_scales(src, dst))
        return b"".join(np.asarray(x).tobytes() for x in fit)

    clean = motion()
    originals = {name: getattr(np, name) for name in TRANSCENDENTAL}
    try:
        inject_ulp_faults(share=1.0)
        faulty = motion()
    finally:
        for name, ufunc in originals.items():
            setattr(np, name, ufunc)
    assert faulty == clean


def test_the_oracle_is_at_least_as_good_as_a_matcher_that_drops_the_outliers():
    """Over planted frames with detection noise and gross outliers, the oracle's success (every
    true match) is not below that of a matcher declaring only the good true matches, nor of one
    declaring a handful of them."""
    oracle, dropping, few = [], [], []
    for seed in range(12):
        p1, p2, pairs, mounts, truth, worst = _with_outliers(seed, noise=0.5)
        good = np.setdiff1d(np.arange(len(pairs)), worst)
        for out, subset in ((oracle, pairs), (dropping, pairs[good]), (few, pairs[good[:3]])):
            rte, rre = matched_planar_error(p1, p2, subset, mounts, truth)
            out.append(rte <= 1.0 and rre <= 2.0)
    assert np.mean(oracle) >= np.mean(dropping) >= np.mean(few)
    assert np.mean(oracle) == 1.0  # 0.5 m noise at 30 m on 7 good matches: within (1 m, 2°)
