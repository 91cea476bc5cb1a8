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
        assert a.prior_error == b.prior_error and a.prior_error is not None


def test_the_v2x_table_has_its_columns_a_prior_row_and_an_interval():
    import pandas as pd

    from eval.studies.v2x_table import COLUMNS, PRIOR_ROW, best_against_runner_up, v2x_table

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
                        | {"prior_scored": preset != "denied", "prior_rte_m": 3.0}
                        | {"prior_rre_deg": 1.5}
                    )
    per_pair = pd.DataFrame(rows)
    table = v2x_table(per_pair)
    assert list(table.columns) == list(COLUMNS)
    prior = table[table["matcher"] == PRIOR_ROW].set_index("preset")
    assert prior.loc["exact", "rte_m_median"] == 3.0 and prior.loc["exact", "success_1m_2deg"] == 0
    assert prior.loc["denied", "pose_failure_rate"] == 1.0
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
