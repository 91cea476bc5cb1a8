"""Validation data: the published-results parser, the CMU House loader, the problem generators."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.distance import pdist

from eval.validation import published
from eval.validation.coid_synthetic import SceneConfig, make_frame_pair
from eval.validation.house import BASELINES, house_pairs, load_house_landmarks
from eval.validation.point_sets import make_point_sets


def test_published_synthetic_known_numbers():
    tables = published.load_synthetic()
    assert {"def_20inlier", "out_003def_15scale"} <= set(tables)
    deformation = tables["def_20inlier"]
    np.testing.assert_allclose(
        deformation.accuracy("TM"), [1.0, 0.979, 0.937, 0.832, 0.712, 0.593, 0.494, 0.433, 0.339]
    )
    np.testing.assert_allclose(deformation.accuracy("RRWHM")[-1], 0.446)
    outliers = tables["out_003def_15scale"]
    bcagm = outliers.accuracy("BCAGM")
    assert bcagm.shape == (21,)  # 0, 10, ..., 200 outliers
    np.testing.assert_allclose(
        bcagm[[0, 2, 5, 10, 15, 20]], [0.998, 0.985, 0.94, 0.839, 0.741, 0.487]
    )
    np.testing.assert_allclose(outliers.time_s("TM")[-1], 1.139)
    with pytest.raises(KeyError, match="NOPE"):
        deformation.accuracy("NOPE")


def test_published_house_known_numbers():
    tables = published.load_house()
    assert sorted(tables) == [5, 10, 15, 20, 30]
    np.testing.assert_allclose(
        tables[20].accuracy["RRWHM"], [1, 1, 1, 0.998, 0.989, 0.969, 0.915, 0.876, 0.812, 0.75]
    )
    np.testing.assert_allclose(tables[10].accuracy["BCAGM"][-1], 0.655)
    assert tables[30].time_s["TM"] == pytest.approx(3.137)


def test_published_parser_rejects_garbage(tmp_path):
    bad = tmp_path / "bad.txt"
    bad.write_text("nothing here\n")
    with pytest.raises(ValueError, match="bad.txt"):
        published.load_synthetic(bad)
    bad.write_text("===== def_x.mat\nmean acc: rows\nTM [1.0 0.x 0.5]\n")
    with pytest.raises(ValueError, match="cannot parse"):
        published.load_synthetic(bad)


def test_house_loader_shape_and_identity_truth():
    frames = load_house_landmarks()
    assert frames.shape == (111, 30, 2)
    assert np.isfinite(frames).all() and 0 < frames.min() and frames.max() < 1000  # pixels
    pairs = list(house_pairs(frames, 20, 30))
    assert len(pairs) == 111 - 30
    for pair in pairs[::20]:
        assert pair.points1.shape == (20, 2) and pair.points2.shape == (30, 2)
        # identity ground truth, seen through the seeded shuffle of view 2
        np.testing.assert_array_equal(pair.points2[pair.truth], frames[pair.u + 30, :20])
        np.testing.assert_array_equal(pair.points1, frames[pair.u, :20])
    assert [len(list(house_pairs(frames, 30, b))) for b in BASELINES] == list(range(101, 10, -10))


def test_house_loader_names_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="house1.txt"):
        load_house_landmarks(tmp_path)


def test_point_sets_follow_the_protocol():
    rng = np.random.default_rng(3)
    ps = make_point_sets(rng, 10, 40, sigma=0.0, scale=1.5, rotation_rad=0.7)
    assert ps.points1.shape == (10, 2) and ps.points2.shape == (50, 2)
    assert len(set(ps.truth.tolist())) == 10
    # noise-free inliers are an exact similarity of view 1: distances scale by 1.5
    np.testing.assert_allclose(pdist(ps.points2[ps.truth]), 1.5 * pdist(ps.points1))
    again = make_point_sets(
        np.random.default_rng(3), 10, 40, sigma=0.0, scale=1.5, rotation_rad=0.7
    )
    np.testing.assert_array_equal(again.points2, ps.points2)


def test_coid_frame_pair_ground_truth_is_consistent():
    cfg = SceneConfig(position_noise_m=0.0, view_noise=0.0, object_spread=0.0)
    for seed in range(5):
        fp = make_frame_pair(np.random.default_rng(seed), cfg)
        n1, n2 = len(fp.ids1), len(fp.ids2)
        assert fp.points1.shape == (n1, 3) and fp.points2.shape == (n2, 3)
        assert fp.features1.shape[0] == n1 and (fp.features1 >= 0).all()
        i, j = fp.truth.T
        # covisible pairs are the same object, and only they are
        np.testing.assert_array_equal(fp.ids1[i], fp.ids2[j])
        assert len(set(fp.ids1) & set(fp.ids2)) == len(fp.truth)
        assert n1 > len(fp.truth) and n2 > len(fp.truth)  # distractors on both sides
        # noise-free: the covisible positions are related by a rigid transform
        np.testing.assert_allclose(pdist(fp.points1[i]), pdist(fp.points2[j]), atol=1e-9)
        np.testing.assert_allclose(fp.features1[i], fp.features2[j])
        # look-alike appearance: fewer distinct looks than objects
        assert len(np.unique(fp.features1.round(9), axis=0)) <= cfg.prototypes


def test_coid_frame_pair_noise_moves_positions():
    fp = make_frame_pair(np.random.default_rng(0), SceneConfig(position_noise_m=0.5))
    i, j = fp.truth.T
    err = np.abs(pdist(fp.points1[i]) - pdist(fp.points2[j]))
    assert 0.05 < err.mean() < 3.0
