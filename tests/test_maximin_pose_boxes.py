"""``maximin_pose`` on box-only data with a prior (a generated DAIR-V2X-C-layout folder): it never
scores 0 where ``pose`` alone matches. The refinement's consensus vote once counted a target
near many sources many times and voted with the gate's width (19–38 m for ``maximin_pose``), so
a shift that dropped the roadside's few boxes into the vehicle's crowd outvoted the true one
and every true pair fell outside the tightened gate."""

from __future__ import annotations

import numpy as np
import pytest

import matchers
from cadsim.dataset import Dataset
from cadsim.importers.dair_v2x import import_dair_v2x
from eval.bench.dair_import import write_dair_layout
from matchers.blocks.rigid2d import consensus_translation


@pytest.fixture(scope="module")
def boxes(tmp_path_factory) -> Dataset:
    tmp = tmp_path_factory.mktemp("dair")
    src = write_dair_layout(tmp / "src", frames=12, seed=3)  # frame 10 collapsed before
    return Dataset(import_dair_v2x(src, tmp / "data").out)


def _true_found(pair, name: str, preset: str, seed: int) -> int:
    problem = pair.localise_preset(preset, seed=seed).problem()
    found = matchers.get(name)(problem, seed=0, threshold=0.5).pairs
    gt = {tuple(p) for p in np.asarray(pair.gt_pairs).tolist()}
    return len({tuple(p) for p in np.asarray(found).tolist()} & gt)


@pytest.mark.parametrize("preset", ["gnss-open-sky", "gnss-urban"])
def test_maximin_pose_never_scores_zero_where_pose_matches(boxes, preset):
    for pair in boxes:
        for seed in range(3):
            pose = _true_found(pair, "pose", preset, seed)
            if pose:
                assert _true_found(pair, "maximin_pose", preset, seed) > 0, (pair.name, seed)


def test_the_vote_counts_an_object_once_on_the_sparser_side():
    """Three sources and a crowd of targets: the true shift (2, 0) aligns all three; a wrong one
    drops one source into a crowd of five targets, each within the cutoff of it."""
    source = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]])
    crowd = np.array([[30.0, 30.0]]) + np.array([[0, 0], [0.5, 0], [0, 0.5], [-0.5, 0], [0, -0.5]])
    target = np.vstack([source + [2.0, 0.0], crowd])
    candidates = np.ones((len(target), len(source)), dtype=bool)
    np.testing.assert_allclose(consensus_translation(source, target, candidates, 1.0), [2.0, 0.0])
