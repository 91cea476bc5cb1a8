"""The field's pose-free V2X association baselines (cbm, freealign, optimal_transport and their
prior variants) and the pose metrics every matcher is scored with."""

from __future__ import annotations

import numpy as np
import pytest

from eval.protocol.pose_metrics import (
    matched_pose_error,
    pose_error,
    prior_transform,
    rigid_fit,
    summarise,
)
from matchers import Problem, get

BASELINES = ("cbm", "freealign", "optimal_transport")


def _rotation_z(theta: float) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _transform(rotation: np.ndarray, translation) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = rotation, translation
    return out


def _planted(seed: int, shared: int = 8, extra: int = 3, noise: float = 0.05):
    """View 2 = a rigid motion of view 1's first `shared` objects (shuffled) plus clutter; the
    truth maps view 2 into view 1."""
    rng = np.random.default_rng(seed)
    p1 = np.column_stack(
        [rng.uniform(-25, 25, (shared + extra, 2)), rng.uniform(0, 2, shared + extra)]
    )
    rotation, translation = _rotation_z(rng.uniform(-np.pi, np.pi)), np.array([7.0, -4.0, 0.3])
    order = rng.permutation(shared)
    common = (p1[:shared][order] - translation) @ rotation  # view-2 frame: R^T (p - t)
    p2 = np.vstack([common + rng.normal(0, noise, common.shape), rng.uniform(-25, 25, (extra, 3))])
    truth = {(int(order[k]), k) for k in range(shared)}
    return p1, p2, truth, _transform(rotation, translation)


def test_pose_metrics_are_exact_on_a_planted_transform():
    p1, p2, truth, true_pose = _planted(0, noise=0.0)
    pairs = np.array(sorted(truth))
    fit = rigid_fit(p2[pairs[:, 1]], p1[pairs[:, 0]])
    np.testing.assert_allclose(fit, true_pose, atol=1e-9)
    rte, rre = matched_pose_error(p1, p2, pairs, true_pose)
    assert rte < 1e-9 and rre < 1e-5
    moved = _transform(_rotation_z(np.radians(3.0)), true_pose[:3, 3] + [1.5, 0, 0]) @ np.eye(4)
    moved[:3, :3] = _rotation_z(np.radians(3.0)) @ true_pose[:3, :3]
    rte, rre = pose_error(moved, true_pose)
    assert rte == pytest.approx(1.5) and rre == pytest.approx(3.0)


def test_fewer_than_three_matches_or_collinear_ones_are_a_failure():
    p1, p2, truth, true_pose = _planted(1)
    pairs = np.array(sorted(truth))
    assert np.isnan(matched_pose_error(p1, p2, pairs[:2], true_pose)).all()
    line = np.column_stack([np.arange(4.0), np.zeros(4), np.zeros(4)])
    assert rigid_fit(line, line) is None
    summary = summarise([0.5, 1.5, np.nan, 3.0], [1.0, 4.0, np.nan, 1.0])
    assert summary["pose_failure_rate"] == 0.25
    assert summary["success_1m_2deg"] == 0.25 and summary["success_2m_5deg"] == 0.5
    assert summary["rte_m_median"] == 1.5 and summary["rre_deg_median"] == 1.0


def test_the_prior_transform_is_what_the_two_noisy_poses_imply():
    p1, p2, _, true_pose = _planted(2, noise=0.0)
    world_from_1 = _transform(_rotation_z(0.4), [100.0, 50.0, 0.0])
    world_from_2 = world_from_1 @ true_pose
    w1 = p1 @ world_from_1[:3, :3].T + world_from_1[:3, 3]
    w2 = p2 @ world_from_2[:3, :3].T + world_from_2[:3, 3]
    np.testing.assert_allclose(prior_transform(p1, w1, p2, w2), true_pose, atol=1e-8)


@pytest.mark.parametrize("name", BASELINES)
@pytest.mark.parametrize("seed", range(4))
def test_each_baseline_recovers_a_planted_correspondence_without_a_prior(name, seed):
    # their own assumption: positions precise to well within the tolerance (1 cm, 20 cm)
    p1, p2, truth, _ = _planted(seed, noise=0.01)
    result = get(name)(Problem(p1, p2), tolerance=0.2)
    found = {tuple(p) for p in result.pairs.tolist()}
    assert truth <= found
    true_scores = [result.scores[i, j] for i, j in truth]
    false_scores = [result.scores[i, j] for i, j in found - truth]
    assert min(true_scores) > max(false_scores, default=0.0)  # a threshold separates them


@pytest.mark.parametrize("name", ["cbm", "freealign"])
@pytest.mark.parametrize("seed", range(3))
def test_the_geometric_baselines_need_no_tuning_on_a_planted_scene(name, seed):
    p1, p2, truth, _ = _planted(seed)  # 5 cm noise, default tolerance
    result = get(name)(Problem(p1, p2), threshold=0.5)
    assert {tuple(p) for p in result.pairs.tolist()} == truth


@pytest.mark.parametrize("name", BASELINES)
def test_each_prior_variant_uses_the_prior_when_geometry_cannot_tell(name):
    # a regular grid: every local context looks alike, so only the prior can break the symmetry
    grid = np.array([[x, y, 0.0] for x in (0.0, 10.0, 20.0) for y in (0.0, 10.0)])
    shift = np.array([0.3, -0.2, 0.0])
    problem = Problem(grid, grid + shift, world1=grid, world2=grid + shift, world_sigma=1.0)
    result = get(f"{name}_pose")(problem, threshold=0.2)
    assert sorted(map(tuple, result.pairs.tolist())) == [(k, k) for k in range(6)]
    assert get(f"{name}_pose").requires and get(name).deterministic
