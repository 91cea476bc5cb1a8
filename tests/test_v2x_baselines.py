"""The field's pose-free V2X association baselines (cbm, freealign, optimal_transport and their
prior variants) and the pose metrics every matcher is scored with."""

from __future__ import annotations

import numpy as np
import pytest

from eval.core.pose_metrics import (
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


# -- cbm / freealign scores: the share of the verified set that agrees with a declared pair --------

GEOMETRIC = ("cbm", "freealign")


def _with_outliers(seed: int, shared: int = 10, extra: int = 7, noise: float = 0.3):
    """Each view holds `shared` common objects and `extra` objects of its own (7 of 17: 41 %
    without a partner); both views' positions noisy; view 2 shuffled. Truth: (view 1, view 2)."""
    rng = np.random.default_rng(seed)

    def scatter(count):
        return np.column_stack([rng.uniform(-25, 25, (count, 2)), rng.uniform(0, 2, count)])

    p1 = scatter(shared + extra)
    rotation, translation = _rotation_z(rng.uniform(-np.pi, np.pi)), np.array([7.0, -4.0, 0.3])
    common = (p1[:shared] - translation) @ rotation
    view2 = np.vstack([common + rng.normal(0, noise, common.shape), scatter(extra)])
    p1 = p1 + rng.normal(0, noise, p1.shape)
    perm = rng.permutation(len(view2))
    where = np.argsort(perm)
    return p1, view2[perm], {(k, int(where[k])) for k in range(shared)}


# view-2 column of each view-1 row, as the matchers declared them before their scores became
# support shares (default tolerance, 0.3 m noise: seeds where they fail included)
PREVIOUS_ASSIGNMENT = {
    ("cbm", 0): [15, 9, 5, 10, 6, 1, 11, 3, 13, 12, 8, 2, 0, 7, 16, 4, 14],
    ("cbm", 1): [16, 12, 6, 1, 8, 10, 5, 0, 7, 2, 3, 4, 14, 11, 15, 13, 9],
    ("cbm", 2): [7, 6, 12, 15, 13, 2, 10, 0, 8, 16, 14, 11, 1, 4, 3, 5, 9],
    ("cbm", 3): [14, 3, 1, 16, 6, 12, 7, 10, 9, 5, 0, 2, 11, 15, 4, 13, 8],
    ("freealign", 0): [13, 14, 4, 3, 1, 7, 5, 2, 0, 11, 6, 15, 9, 8, 10, 16, 12],
    ("freealign", 1): [14, 15, 5, 2, 3, 6, 12, 4, 16, 9, 13, 8, 7, 0, 10, 11, 1],
    ("freealign", 2): [0, 5, 7, 8, 2, 4, 3, 13, 14, 12, 10, 9, 15, 16, 11, 6, 1],
    ("freealign", 3): [14, 3, 1, 16, 6, 12, 7, 8, 9, 0, 5, 2, 11, 15, 4, 13, 10],
}


@pytest.mark.parametrize(("name", "seed"), sorted(PREVIOUS_ASSIGNMENT))
def test_the_declared_pairs_are_the_ones_declared_before(name, seed):
    from matchers.core.discretise import discretise

    p1, p2, _ = _with_outliers(seed)
    result = get(name)(Problem(p1, p2))
    assert result.pairs[:, 0].tolist() == list(range(17))
    assert result.pairs[:, 1].tolist() == PREVIOUS_ASSIGNMENT[(name, seed)]
    # every declared pair scores above 0, every other entry 0: none outranks a declared pair
    declared = np.zeros(result.scores.shape, dtype=bool)
    declared[result.pairs[:, 0], result.pairs[:, 1]] = True
    assert np.all(result.scores[declared] > 0) and np.all(result.scores[~declared] == 0)
    assert np.array_equal(discretise(result.scores), result.pairs)
    assert result.scores.min() >= 0 and result.scores.max() <= 1


def _mirrored_clutter_scene():
    """Six common objects (view 2 = a rigid motion of view 1, exact) and one object of each view's
    own: view 2's is the image of view 1's mirrored across the vertical plane through objects 0
    and 1, so its distances to those two agree exactly while it lies 14 m away."""
    common = np.array(
        [[0, 0, 0], [10, 0, 0.5], [3, 12, 1], [-8, 6, 0.2], [14, 9, 1.5], [-5, -11, 0.8]], float
    )
    own1, mirrored = np.array([6.0, -7.0, 0.4]), np.array([6.0, 7.0, 0.4])
    rotation, translation = _rotation_z(0.7), np.array([3.0, -2.0, 0.1])
    order = np.array([4, 0, 6, 2, 5, 1, 3])  # view-2 row k shows object order[k]
    world2 = np.vstack([common, mirrored])[order]
    p1, p2 = np.vstack([common, own1]), (world2 - translation) @ rotation
    where = np.argsort(order)
    return p1, p2, {(k, int(where[k])) for k in range(6)}, (6, int(where[6]))


def _share(p1, p2, pair, reference, eps):
    """The documented score, entry by entry: the mean over the reference pairs other than `pair`
    of exp(-2 (delta / eps)^2) within eps (0 beyond, 0 for a pair sharing one object)."""
    (i, j), total, count = pair, 0.0, 0
    for k, other in reference:
        if (k, other) == (i, j):
            continue
        count += 1
        if k == i or other == j:
            continue
        delta = abs(np.linalg.norm(p1[i] - p1[k]) - np.linalg.norm(p2[j] - p2[other]))
        total += np.exp(-2 * (delta / eps) ** 2) if delta <= eps else 0.0
    return total / count


@pytest.mark.parametrize("name", GEOMETRIC)
def test_a_declared_pair_scores_the_share_of_the_verified_set_that_agrees_with_it(name):
    p1, p2, truth, own = _mirrored_clutter_scene()
    result = get(name)(Problem(p1, p2), tolerance=0.2)
    assert {tuple(p) for p in result.pairs.tolist()} == truth | {own}
    assert result.info.get("inliers", result.info.get("subgraph")) == 6  # the six common objects
    for pair in truth:
        assert result.scores[pair] == pytest.approx(1.0, abs=1e-9)  # agrees with all 5 others
    expected = _share(p1, p2, own, truth, 0.2)
    assert expected == pytest.approx(2 / 6, abs=1e-9)  # objects 0 and 1 agree, the rest do not
    assert result.scores[own] == pytest.approx(expected, abs=1e-9)  # not its residual's exp(-2450)
    assert result.scores.sum() == pytest.approx(6 + expected, abs=1e-9)  # nothing else scores


@pytest.mark.parametrize("name", GEOMETRIC)
@pytest.mark.parametrize("seed", range(6))
def test_a_threshold_drops_the_pairs_of_objects_seen_in_one_view_only(name, seed):
    p1, p2, truth = _with_outliers(seed, noise=0.05)  # 41 % of each view without a partner
    problem = Problem(p1, p2)
    result = get(name)(problem, tolerance=0.3)
    found = {tuple(p) for p in result.pairs.tolist()}
    assert truth <= found and len(found - truth) == 7  # the Hungarian pairs up the seven others
    true_scores = [result.scores[p] for p in truth]
    outlier_scores = [result.scores[p] for p in found - truth]
    assert min(true_scores) > 0.45 and max(outlier_scores) < 0.15  # on an absolute scale
    kept = get(name)(problem, threshold=0.3, tolerance=0.3)
    assert {tuple(p) for p in kept.pairs.tolist()} == truth  # abstains on every outlier


@pytest.mark.parametrize("name", GEOMETRIC)
def test_the_geometric_baselines_keep_degenerate_views_safe(name):
    import warnings

    from test_matchers_degenerate import check_valid

    identical = np.zeros((4, 3))
    line = np.column_stack([np.arange(5.0), np.zeros(5), np.zeros(5)])
    cases = [
        (np.zeros((0, 3)), np.zeros((3, 3))),
        (np.ones((1, 3)), np.ones((1, 3))),
        (np.ones((1, 3)), np.arange(9.0).reshape(3, 3)),
        (np.array([[0.0, 0, 0], [4, 0, 0]]), np.array([[1.0, 1, 0], [1, 5, 0]])),
        (identical, identical + 2.0),
        (line, line[::-1] + 1.0),
    ]
    for p1, p2 in cases:
        for threshold in (None, 0.0, 0.5):
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                result = get(name)(Problem(p1, p2), threshold=threshold)
            check_valid(result, len(p1), len(p2), threshold)
    one = get(name)(Problem(np.ones((1, 3)), np.ones((1, 3))), threshold=None)
    assert one.pairs.tolist() == [[0, 0]] and np.all(one.scores == 0)  # declared, no evidence
    assert len(get(name)(Problem(np.ones((1, 3)), np.ones((1, 3))), threshold=1e-12).pairs) == 0
    # too few objects for a motion: the declared pairs are each other's reference
    two = np.array([[0.0, 0, 0], [4, 0, 0]])
    agree = get(name)(Problem(two, np.array([[1.0, 1, 0], [1, 5, 0]])), tolerance=0.2)
    assert agree.scores[agree.pairs[:, 0], agree.pairs[:, 1]].tolist() == [1.0, 1.0]
    differ = get(name)(Problem(two, np.array([[1.0, 1, 0], [1, 9, 0]])), tolerance=0.2)
    assert np.all(differ.scores < 1e-9) and len(differ.pairs) == 2  # declared, unsupported


@pytest.mark.parametrize("name", GEOMETRIC)
def test_the_geometric_baselines_survive_random_degenerate_views(name):
    import warnings

    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st
    from test_matchers_degenerate import check_valid, degenerate_views

    @settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(problem=degenerate_views(), threshold=st.sampled_from([None, 0.0, 0.5]))
    def check(problem, threshold):
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # no RuntimeWarning (division by zero, NaN)
            result = get(name)(problem, threshold=threshold)
        check_valid(result, problem.n1, problem.n2, threshold)
        if threshold is None and result.scores.size:
            declared = np.zeros(result.scores.shape, dtype=bool)
            declared[result.pairs[:, 0], result.pairs[:, 1]] = True
            assert not np.any(result.scores[~declared] > 0)

    check()


@pytest.mark.parametrize("name", BASELINES)
def test_each_prior_variant_uses_the_prior_when_geometry_cannot_tell(name):
    # a regular grid: every local context looks alike, so only the prior can break the symmetry
    grid = np.array([[x, y, 0.0] for x in (0.0, 10.0, 20.0) for y in (0.0, 10.0)])
    shift = np.array([0.3, -0.2, 0.0])
    problem = Problem(grid, grid + shift, world1=grid, world2=grid + shift, world_sigma=1.0)
    result = get(f"{name}_pose")(problem, threshold=0.2)
    assert sorted(map(tuple, result.pairs.tolist())) == [(k, k) for k in range(6)]
    assert get(f"{name}_pose").requires and get(name).deterministic


# -- the pose columns and the V2X table ----------------------------------------------------------


def test_evaluate_with_a_preset_writes_the_pose_columns(tmp_path):
    import pandas as pd
    from test_gnss_error import _generated

    from cadsim.cli import main
    from eval.core.pose_metrics import COLUMNS

    data = _generated(tmp_path / "t", {})
    val = _generated(tmp_path / "v", {}, seed=1011)
    out = tmp_path / "urban"
    args = ["evaluate", str(data.path), "--val", str(val.path), "--matchers", "pose,sm,freealign"]
    args += ["--runs", "2", "--workers", "1", "--cache", str(tmp_path / "cache"), "--no-progress"]
    assert main([*args, "--localisation", "gnss-urban", "--out", str(out)]) == 0
    table = pd.read_csv(out / "table1.csv").set_index("matcher")
    assert set(COLUMNS) <= set(table.columns)
    assert table[list(COLUMNS[2:])].apply(lambda c: c.between(0, 1)).all().all()
    per_pair = pd.read_csv(out / "metrics_per_pair.csv")
    assert per_pair["pose_scored"].all()  # simulated records: the true pose is known
    assert per_pair.loc[per_pair["matcher"] == "pose", "prior_scored"].all()


def test_a_no_prior_matcher_runs_once_per_latency_whatever_the_preset(tmp_path):
    from test_gnss_error import _generated

    from eval.core.cache import ResultCache
    from eval.core.executor import SerialExecutor
    from eval.core.runner import Runner, requests_for
    from eval.core.tasks import MatcherSpec

    data = _generated(tmp_path, {})
    runner = Runner(ResultCache(tmp_path / "cache"), SerialExecutor(), progress=False)
    dataset = [(str(data.path), data.checksum)]
    specs = [MatcherSpec("sm"), MatcherSpec("pose")]
    first = runner.run(requests_for(dataset, specs, [0], localisation="gnss-urban"))
    runner.run(requests_for(dataset, specs, [0], localisation="gnss-urban*3"))
    assert runner.stats.cached == 1 and runner.stats.computed == 1  # sm shared; pose re-drawn
    runner.run(requests_for(dataset, specs, [0], localisation="gnss-urban+300ms"))
    assert runner.stats.computed == 2  # another latency: both again
    again = runner.run(requests_for(dataset, specs, [0], localisation="gnss-urban"))
    sm = [r for r in (first, again) for r in r if r.spec.matcher.name == "sm"]
    assert sm[0].spec.localisation == "gnss-urban"  # results come back under the asked spec
    assert np.array_equal(sm[0].outcomes[0].true_pose, sm[1].outcomes[0].true_pose)


def test_the_cache_keeps_the_pose_fields(tmp_path):
    from test_gnss_error import _generated

    from eval.core.cache import ResultCache
    from eval.core.executor import SerialExecutor
    from eval.core.runner import Runner, requests_for
    from eval.core.tasks import MatcherSpec

    data = _generated(tmp_path, {"preset": "gnss-open-sky"})
    cache = ResultCache(tmp_path / "cache")
    runner = Runner(cache, SerialExecutor(), progress=False)
    (run,) = runner.run(requests_for([(str(data.path), data.checksum)], [MatcherSpec("pose")], [0]))
    loaded = cache.load(run.spec)
    for a, b in zip(run.outcomes, loaded.outcomes, strict=True):
        np.testing.assert_array_equal(a.points1, b.points1)
        np.testing.assert_array_equal(a.points2, b.points2)
        np.testing.assert_array_equal(a.true_pose, b.true_pose)
        np.testing.assert_array_equal(a.prior_pose, b.prior_pose)
        np.testing.assert_array_equal(a.extrinsics, b.extrinsics)
        assert a.prior_pose is not None and a.extrinsics.shape == (2, 4, 4)


def test_the_v2x_table_has_its_columns_a_prior_row_and_an_interval():
    import pandas as pd

    from eval.studies.v2x.table import (
        COLUMNS,
        ORACLE_ROW,
        PRIOR_ROW,
        best_against_runner_up,
        v2x_table,
    )

    rng = np.random.default_rng(0)
    rows = []
    for preset in ("exact", "denied"):
        for matcher, level in (("pose", 0.9), ("freealign", 0.6), ("sm", 0.4)):
            given = preset != "denied" or matcher != "pose"
            for seed in range(2):
                for pair in range(12):
                    tp = int(rng.random() < level) * 5 if given else 0
                    rows.append(
                        {"preset": preset, "matcher": matcher, "seed": seed, "pair": pair}
                        | {
                            "episode": pair // 3,
                            "f1": tp / 5,
                            "tp": tp,
                            "n_pred": 5 if given else 0,
                        }
                        | {"n_gt": 5, "time_s": 0.001, "pose_scored": True}
                        | {"rte_m": 0.5 if tp else np.nan, "rre_deg": 1.0 if tp else np.nan}
                        | {"rte_m_6dof": 1.5, "rre_deg_6dof": 1.0}
                        | {"oracle_rte_m": 0.5 if pair % 2 else 1.5, "oracle_rre_deg": 1.0}
                        | {"prior_scored": preset != "denied", "prior_rte_m": 3.0}
                        | {"prior_rre_deg": 1.5}
                    )
    per_pair = pd.DataFrame(rows)
    table = v2x_table(per_pair)
    assert list(table.columns) == list(COLUMNS)
    prior = table[table["matcher"] == PRIOR_ROW].set_index("preset")
    assert prior.loc["exact", "rte_m_median"] == 3.0 and prior.loc["exact", "success_1m_2deg"] == 0
    assert prior.loc["denied", "pose_failure_rate"] == 1.0
    oracle = table[table["matcher"] == ORACLE_ROW].set_index("preset")
    assert oracle.loc["exact", "success_1m_2deg"] == 0.5  # the odd pairs' fits are within 1 m
    assert oracle.loc["exact", "success_low"] < 0.5 < oracle.loc["exact", "success_high"]
    rows = table.set_index(["preset", "matcher"])
    pose = rows.loc[("exact", "pose")]
    assert pose.share_of_oracle == pytest.approx(pose.success_1m_2deg / 0.5)
    assert pose.success_1m_2deg_6dof == 0.0  # 1.5 m off: the secondary column reads its own fit
    assert pose.f1_low <= pose.f1_mean <= pose.f1_high
    intervals = best_against_runner_up(per_pair).set_index("preset")
    assert (
        intervals.loc["exact", "best"] == "pose" and intervals.loc["denied", "best"] == "freealign"
    )
    assert (
        intervals.loc["exact", "ci_low"]
        <= intervals.loc["exact", "f1_diff"]
        <= intervals.loc["exact", "ci_high"]
    )
    assert intervals.loc["exact", "episodes"] == 4
    # The best and the runner-up are chosen on validation when its figures are given.
    validation = {"exact": {"sm": 0.9, "freealign": 0.8, "pose": 0.1}}
    chosen = best_against_runner_up(per_pair, validation).set_index("preset")
    assert (chosen.loc["exact", "best"], chosen.loc["exact", "runner_up"]) == ("sm", "freealign")
    exact = per_pair[per_pair["preset"] == "exact"].groupby("matcher")["f1"].mean()
    assert chosen.loc["exact", "f1_diff"] == pytest.approx(exact["sm"] - exact["freealign"])


# -- the planar fit, the oracle and the prior rows -------------------------------------------------


def _mounted(seed: int, shared: int = 6, extra: int = 2, noise: float = 0.0):
    """Two roof cameras (OpenCV axes, 1.6 m up, looking forward) on bodies related by a ground
    motion (yaw + (x, y)); objects on the ground plane seen by both: (points1, points2 in camera
    frames, true pairs (k, 2), extrinsics (2, 4, 4) camera → body, true camera2 → camera1)."""
    rng = np.random.default_rng(seed)
    cam_to_body = np.eye(4)
    cam_to_body[:3, :3] = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    cam_to_body[:3, 3] = [0.5, 0.0, 1.6]
    body = _transform(_rotation_z(rng.uniform(-np.pi, np.pi)), [rng.uniform(-20, 20), 6.0, 0.0])
    world1 = np.column_stack([rng.uniform(5, 40, shared + extra), rng.uniform(-10, 10, shared + extra), rng.uniform(0, 2, shared + extra)])  # fmt: skip
    order = rng.permutation(shared)
    in_body2 = (world1[:shared][order] - body[:3, 3]) @ body[:3, :3]
    to_cam = np.linalg.inv(cam_to_body)
    p1 = world1 @ to_cam[:3, :3].T + to_cam[:3, 3]
    p2 = in_body2 @ to_cam[:3, :3].T + to_cam[:3, 3]
    p2 = np.vstack([p2 + rng.normal(0, noise, p2.shape), rng.uniform(5, 30, (extra, 3))])
    pairs = np.array(sorted((int(order[k]), k) for k in range(shared)))
    truth = to_cam @ body @ cam_to_body
    return p1, p2, pairs, np.stack([cam_to_body, cam_to_body]), truth


def test_the_planar_fit_is_exact_on_a_noise_free_planted_ground_motion():
    from eval.core.pose_metrics import matched_planar_error, planar_fit

    p1, p2, pairs, mounts, truth = _mounted(3)
    fit = planar_fit(p2[pairs[:, 1]], p1[pairs[:, 0]], mounts[1], mounts[0])
    np.testing.assert_allclose(fit, truth, atol=1e-9)
    rte, rre = matched_planar_error(p1, p2, pairs[:2], mounts, truth)  # two matches suffice
    assert rte < 1e-6 and rre < 1e-4
    assert np.isnan(matched_planar_error(p1, p2, pairs[:1], mounts, truth)).all()
    near = np.array([[0, 0], [0, 0]])  # the same point twice: no spread, the yaw is free
    assert np.isnan(matched_planar_error(p1, p2, near, mounts, truth)).all()


def test_the_oracle_columns_are_the_planar_fit_of_the_true_matches_under_known_noise():
    from eval.core.pose_metrics import matched_planar_error, outcome_pose
    from eval.core.tasks import PairOutcome

    p1, p2, pairs, mounts, truth = _mounted(4, noise=0.3)
    wrong = np.array([[pairs[0, 0], pairs[1, 1]], [pairs[1, 0], pairs[0, 1]]])
    outcome = PairOutcome(
        0, "p", 0, 0, "", len(p1), len(p2), pairs, wrong, np.zeros((len(p1), len(p2))), 0.0, 0,
        points1=p1, points2=p2, true_pose=truth, prior_pose=truth, extrinsics=mounts,
    )  # fmt: skip
    row = outcome_pose(outcome, wrong)
    expected = matched_planar_error(p1, p2, pairs, mounts, truth)
    assert (row["oracle_rte_m"], row["oracle_rre_deg"]) == expected
    assert 0 < expected[0] < 1.0  # 0.3 m noise on 6 points: close, not exact
    assert row["rte_m"] > expected[0]  # swapped matches fit worse than the truth
    assert row["prior_rte_m"] == 0.0 and row["prior_scored"]


def test_the_prior_row_is_the_broadcast_poses_alone(tmp_path):
    from test_gnss_error import _generated

    from eval.core.pose_metrics import pose_error, prior_transform

    urban = _generated(tmp_path, {"preset": "gnss-urban"})
    for pair in urban:
        broadcast = pair.broadcast_relative_pose()
        problem = pair.problem()
        implied = prior_transform(problem.points1, problem.world1, problem.points2, problem.world2)
        if implied is not None:  # the same transform the noisy world positions imply
            np.testing.assert_allclose(broadcast, implied, atol=1e-6)
        # poses only: other detections (a noisier re-detection) leave it unchanged
        noisier = pair.redetect(0.05, seed=3)
        np.testing.assert_array_equal(noisier.broadcast_relative_pose(), broadcast)
        assert pose_error(broadcast, pair.true_relative_pose())[0] > 0  # it carries the GNSS error
        exact = pair.localise_preset("exact", seed=0)
        np.testing.assert_allclose(
            exact.broadcast_relative_pose(), exact.true_relative_pose(), atol=1e-9
        )
        assert pair.localise_preset("denied", seed=0).broadcast_relative_pose() is None


def test_the_prior_row_is_read_off_a_matcher_that_reads_the_prior():
    """A matcher without a prior runs under `exact` (its run shared across presets): its
    broadcast poses are exact, so the prior row must come from a prior-reading matcher's rows."""
    import pandas as pd

    from eval.studies.v2x.table import PRIOR_ROW, v2x_table

    rows = []
    for matcher, prior_rte in (("sm", 0.0), ("pose", 3.0)):  # sm first, as in the table
        for pair in range(6):
            rows.append(
                {"preset": "gnss-urban", "matcher": matcher, "seed": 0, "pair": pair}
                | {"episode": pair // 2, "f1": 1.0, "tp": 1, "n_pred": 1, "n_gt": 1}
                | {"time_s": 0.001, "pose_scored": True, "rte_m": 0.1, "rre_deg": 0.1}
                | {"rte_m_6dof": 0.1, "rre_deg_6dof": 0.1, "oracle_rte_m": 0.1}
                | {"oracle_rre_deg": 0.1, "prior_scored": True, "prior_rte_m": prior_rte}
                | {"prior_rre_deg": 0.5}
            )
    table = v2x_table(pd.DataFrame(rows))
    prior = table[table["matcher"] == PRIOR_ROW].iloc[0]
    assert prior.rte_m_median == 3.0 and prior.success_1m_2deg == 0.0
