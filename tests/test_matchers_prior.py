"""The localisation prior: Problem fields, and the matchers that use it (pose, pose_refine,
pose_appearance, maximin_pose)."""

import numpy as np
import pytest

from matchers import Problem, get, requires
from matchers.blocks.prior import prior_likelihood
from matchers.blocks.rigid2d import procrustes_2d, robust_rigid_2d, rotation
from matchers.maximin import maximin

PRIOR = ["pose", "pose_refine", "pose_appearance", "maximin_pose"]


def two_views(seed, n_common=8, n_only=3, extent=60.0, spacing=6.0):
    """Objects in a world frame (x, y horizontal, z up): n_common seen by both agents,
    n_only more by each alone, at least ``spacing`` metres apart. Each view lists its
    objects in its own camera frame (a random rigid motion) and in shuffled order.
    Returns (world1, world2, camera1, camera2, truth pairs as a set)."""
    rng = np.random.default_rng(seed)
    count = n_common + 2 * n_only
    xy = np.empty((0, 2))
    while len(xy) < count:
        cand = rng.uniform(-extent / 2, extent / 2, 2)
        if not len(xy) or np.min(np.linalg.norm(xy - cand, axis=1)) >= spacing:
            xy = np.vstack([xy, cand])
    world = np.column_stack([xy, rng.uniform(0.5, 2.0, count)])
    ids1 = rng.permutation(np.r_[0:n_common, n_common : n_common + n_only])
    ids2 = rng.permutation(np.r_[0:n_common, n_common + n_only : count])
    truth = {(i, int(np.flatnonzero(ids2 == k)[0])) for i, k in enumerate(ids1) if k < n_common}

    def camera(points):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        return points @ (q * np.sign(np.linalg.det(q))).T + rng.normal(size=3) * 10

    return world[ids1], world[ids2], camera(world[ids1]), camera(world[ids2]), truth


def as_set(pairs):
    return {(int(i), int(j)) for i, j in pairs}


# --- Problem fields -----------------------------------------------------------------------


def test_problem_keeps_and_validates_the_optional_fields():
    p = Problem(
        np.zeros((2, 3)),
        np.zeros((3, 3)),
        pixels1=[[1, 2], [3, 4]],
        pixels2=np.zeros((3, 2)),
        world1=np.ones((2, 3)),
        world2=np.ones((3, 3)),
        world_sigma=1,
    )
    assert p.pixels1.dtype == float and p.world2.shape == (3, 3) and p.world_sigma == 1.0
    plain = Problem(np.zeros((2, 3)), np.zeros((3, 3)))
    assert plain.pixels1 is None and plain.world1 is None and plain.world_sigma is None
    empty = Problem(np.zeros((0, 3)), np.zeros((3, 3)), world1=[], world2=np.zeros((3, 3)))
    assert empty.world1.shape == (0, 3)


@pytest.mark.parametrize(
    ("fields", "named"),
    [
        ({"pixels1": np.zeros((2, 2))}, "pixels1/pixels2"),
        ({"world2": np.zeros((3, 3))}, "world1/world2"),
        ({"pixels1": np.zeros((2, 3)), "pixels2": np.zeros((3, 2))}, "pixels1"),
        ({"pixels1": np.zeros((2, 2)), "pixels2": np.zeros((4, 2))}, "pixels2"),
        ({"world1": np.zeros((2, 2)), "world2": np.zeros((3, 3))}, "world1"),
        ({"world1": np.zeros((2, 3)), "world2": np.full((3, 3), np.nan)}, "world2"),
        ({"pixels1": np.full((2, 2), np.inf), "pixels2": np.zeros((3, 2))}, "pixels1"),
        ({"world_sigma": 1.0}, "world_sigma"),
        (
            {"world1": np.zeros((2, 3)), "world2": np.zeros((3, 3)), "world_sigma": 0.0},
            "world_sigma",
        ),
        (
            {"world1": np.zeros((2, 3)), "world2": np.zeros((3, 3)), "world_sigma": -1},
            "world_sigma",
        ),
        (
            {"world1": np.zeros((2, 3)), "world2": np.zeros((3, 3)), "world_sigma": np.nan},
            "world_sigma",
        ),
        (
            {"world1": np.zeros((2, 3)), "world2": np.zeros((3, 3)), "world_sigma": "1"},
            "world_sigma",
        ),
        (
            {"world1": np.zeros((2, 3)), "world2": np.zeros((3, 3)), "world_sigma": True},
            "world_sigma",
        ),
    ],
)
def test_problem_rejects_bad_optional_fields_by_name(fields, named):
    with pytest.raises(ValueError, match=named):
        Problem(np.zeros((2, 3)), np.zeros((3, 3)), **fields)


@pytest.mark.parametrize("name", PRIOR)
def test_prior_matchers_name_what_is_missing(name):
    assert requires(name) == {"world1", "world2", "world_sigma"}
    with pytest.raises(ValueError, match="world1"):
        get(name)(Problem(np.zeros((3, 3)), np.zeros((3, 3))))
    no_sigma = Problem(
        np.zeros((3, 3)), np.zeros((3, 3)), world1=np.zeros((3, 3)), world2=np.zeros((3, 3))
    )
    with pytest.raises(ValueError, match="world_sigma"):
        get(name)(no_sigma)


@pytest.mark.parametrize("name", ["appearance", "sm", "maximin", "consistency", "none"])
def test_other_matchers_need_nothing_and_ignore_the_prior(name):
    assert requires(name) == frozenset()
    w1, w2, c1, c2, _ = two_views(3)
    plain = get(name)(Problem(c1, c2))
    with_prior = get(name)(Problem(c1, c2, world1=w1 + 50, world2=w2, world_sigma=0.1))
    np.testing.assert_array_equal(plain.scores, with_prior.scores)
    np.testing.assert_array_equal(plain.pairs, with_prior.pairs)


# --- the likelihood and the rigid fit -------------------------------------------------------


def test_prior_likelihood_ignores_height_and_gates():
    xy1 = np.array([[0.0, 0.0]])
    assert prior_likelihood(xy1, np.array([[3.0, 4.0]]), sigma=1.0, spread=2.0, gate=8.0)[
        0, 0
    ] == pytest.approx(np.exp(-25 / 16))
    assert prior_likelihood(xy1, np.array([[3.0, 4.0]]), sigma=1.0, gate=4.9)[0, 0] == 0.0
    w1, w2 = np.array([[0.0, 0.0, 0.0]]), np.array([[0.0, 0.0, 30.0]])
    p = Problem(np.zeros((1, 3)), np.zeros((1, 3)), world1=w1, world2=w2, world_sigma=1.0)
    assert get("pose")(p).scores[0, 0] == 1.0  # z (height) is not part of the distance


def test_procrustes_recovers_a_planted_motion_and_robust_fit_ignores_outliers():
    rng = np.random.default_rng(0)
    source = rng.uniform(-30, 30, (10, 2))
    turn, shift = rotation(np.radians(5.0)), np.array([3.0, -2.0])
    target = source @ turn.T + shift
    r, t = procrustes_2d(source, target, np.ones(10))
    np.testing.assert_allclose(r, turn, atol=1e-12)
    np.testing.assert_allclose(t, shift, atol=1e-10)
    corrupted = target.copy()
    corrupted[:2] += [[15.0, 0.0], [0.0, -12.0]]  # two wrong matches
    r, t, inliers = robust_rigid_2d(source, corrupted, np.ones(10), cutoff=5.0, with_rotation=True)
    np.testing.assert_allclose(r, turn, atol=1e-9)
    np.testing.assert_allclose(t, shift, atol=1e-8)
    assert inliers.tolist() == [False, False] + [True] * 8
    r, t = procrustes_2d(source, target, np.zeros(10))
    assert np.array_equal(r, np.eye(2)) and np.array_equal(t, np.zeros(2))


# --- pose ----------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_pose_is_exact_on_a_noise_free_prior(seed):
    w1, w2, c1, c2, truth = two_views(seed)
    problem = Problem(c1, c2, world1=w1, world2=w2, world_sigma=0.5)
    matching = get("pose")(problem, threshold=0.5)
    assert as_set(matching.pairs) == truth
    assert all(matching.scores[i, j] == 1.0 for i, j in truth)
    assert matching.scores.max() <= 1.0 and matching.scores.min() >= 0.0


def test_pose_scores_fall_with_distance_and_the_gate_cuts():
    w1, w2, c1, c2, truth = two_views(4)
    shifted = Problem(c1, c2, world1=w1, world2=w2 + [2.0, 0.0, 0.0], world_sigma=1.0)
    scores = get("pose")(shifted, spread=2.0).scores
    assert all(scores[i, j] == pytest.approx(np.exp(-4 / 16)) for i, j in truth)
    wider = get("pose")(shifted).scores  # the default spread, 3: exp(-d^2 / (4 (3 sigma)^2))
    assert all(wider[i, j] == pytest.approx(np.exp(-4 / 36)) for i, j in truth)
    gated = get("pose")(shifted, gate=1.5).scores
    assert all(gated[i, j] == 0.0 for i, j in truth)


# --- pose_refine ------------------------------------------------------------------------------


def planted_offset(seed, yaw_deg=4.0, shift=(4.0, -3.0), confusers=2):
    """View 2's prior moved by one rigid motion (yaw about the origin + shift); ``confusers``
    of view 2's own objects sit exactly where two covisible objects would be without the
    offset, so the raw prior matches them wrongly."""
    w1, w2, c1, c2, truth = two_views(seed, n_common=10, n_only=3)
    moved = w2.copy()
    moved[:, :2] = w2[:, :2] @ rotation(np.radians(yaw_deg)).T + np.asarray(shift)
    only2 = sorted(set(range(len(w2))) - {j for _, j in truth})
    for k, (i, _) in zip(only2[:confusers], sorted(truth)[:confusers], strict=False):
        moved[k, :2] = w1[i, :2]
    return Problem(c1, c2, world1=w1, world2=moved, world_sigma=1.2), truth


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_pose_refine_recovers_a_planted_rigid_offset_with_outliers(seed):
    problem, truth = planted_offset(seed)
    plain = as_set(get("pose")(problem, threshold=0.5).pairs)
    assert plain != truth  # the raw prior is misled by the confusers
    matching = get("pose_refine")(problem, threshold=0.5, rotation=True)
    assert as_set(matching.pairs) == truth
    assert matching.info["converged"] and 1 <= matching.info["rounds"] <= 5
    assert matching.info["yaw_deg"] == pytest.approx(-4.0, abs=1e-6)  # the inverse motion


def test_pose_refine_translation_only_on_request():
    problem, truth = planted_offset(5, yaw_deg=0.0, shift=(5.0, 2.0))
    matching = get("pose_refine")(problem, threshold=0.5, rotation=False)
    assert as_set(matching.pairs) == truth
    assert matching.info["yaw_deg"] == 0.0
    assert matching.info["shift_m"] == pytest.approx([-5.0, -2.0], abs=1e-6)


def test_pose_refine_without_confident_pairs_keeps_the_prior():
    w1, w2, c1, c2, _ = two_views(6)
    far = Problem(c1, c2, world1=w1, world2=w2 + [500.0, 0, 0], world_sigma=1.0)
    matching = get("pose_refine")(far)
    assert matching.info["rounds"] == 0 and np.all(matching.scores == 0)


# --- pose_appearance and maximin_pose ----------------------------------------------------


def test_pose_appearance_lets_appearance_break_a_tie_of_the_prior():
    w = np.array([[0.0, 0.0, 0.0], [0.5, 0.0, 0.0]])
    f1 = np.array([[1.0, 0.0], [0.0, 1.0]])
    problem = Problem(
        np.zeros((2, 3)), np.zeros((2, 3)), f1, f1[::-1], world1=w, world2=w[::-1], world_sigma=2.0
    )
    assert get("pose_appearance")(problem, threshold=0.1).pairs.tolist() == [[0, 1], [1, 0]]
    no_features = Problem(np.zeros((2, 3)), np.zeros((2, 3)), world1=w, world2=w, world_sigma=2.0)
    np.testing.assert_array_equal(
        get("pose_appearance")(no_features, refine=False).scores,
        get("pose")(no_features, spread=4.0).scores,
    )


def test_maximin_first_order_hook_is_neutral_and_maximin_pose_uses_the_prior():
    w1, w2, c1, c2, truth = two_views(7)
    rng = np.random.default_rng(7)
    f1, f2 = rng.random((len(c1), 5)), rng.random((len(c2), 5))  # uninformative appearance
    problem = Problem(c1, c2, f1, f2, world1=w1, world2=w2 + [1.0, 1.0, 0.0], world_sigma=1.0)
    from matchers.blocks.appearance_similarity import appearance_similarity

    same = maximin(problem, first_order=appearance_similarity(problem))
    np.testing.assert_array_equal(same.scores, maximin(problem).scores)
    assert as_set(maximin(problem, threshold=0.25).pairs) != truth  # geometry + noise alone fail
    matching = get("maximin_pose")(problem, threshold=0.25)
    assert matching.name == "maximin_pose"
    assert as_set(matching.pairs) == truth
    assert as_set(get("maximin_pose")(problem, threshold=0.25, refine=True).pairs) == truth
    with pytest.raises(ValueError, match="first_order"):
        maximin(problem, first_order=np.ones((2, 2)))
    with pytest.raises(TypeError, match="first_order"):
        get("maximin_pose")(problem, first_order=np.ones((len(c1), len(c2))))


@pytest.mark.parametrize(
    ("name", "option", "value"),
    [
        ("pose", "spread", 0.0),
        ("pose", "gate", -1.0),
        ("pose_appearance", "spread", np.nan),
        ("pose_refine", "tighten", 1.5),
        ("pose_refine", "confident", -0.1),
        ("pose_refine", "max_iter", 0),
        ("maximin_pose", "gate", "wide"),
    ],
)
def test_bad_prior_options_are_named(name, option, value):
    w1, w2, c1, c2, _ = two_views(8)
    problem = Problem(c1, c2, world1=w1, world2=w2, world_sigma=1.0)
    with pytest.raises(ValueError, match=option):
        get(name)(problem, **{option: value})
