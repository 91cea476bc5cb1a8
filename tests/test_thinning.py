"""Thinning non-covisible detections (the regime sweep's knob): every covisible object stays, the
achieved non-covisible share falls with the keep level, the draw is the pair's own."""

from __future__ import annotations

import numpy as np
import pytest

from cadsim.dataset.detections import ViewDetections
from cadsim.dataset.reader import FramePair
from eval.core.thinning import PairIdentity, kept_rows, noncovisible_share, thin_pair

LEVELS = (1.0, 0.75, 0.5, 0.25, 0.0)


def _view(ids, seed):
    rng = np.random.default_rng(seed)
    k = len(ids)
    return ViewDetections(
        positions=rng.normal(size=(k, 3)),
        boxes=rng.uniform(0, 100, size=(k, 4)),
        features=rng.uniform(size=(k, 4)).astype(np.float32),
        object_ids=list(ids),
        true_classes=["car"] * k,
        pixels=rng.integers(1, 500, size=k),
    )


def _pair(index: int, covisible: int = 4, only1: int = 12, only2: int = 9) -> FramePair:
    """A frame pair built in memory: `covisible` shared objects, the rest seen by one view."""
    shared = [f"s{i}" for i in range(covisible)]
    ids1 = shared + [f"a{i}" for i in range(only1)]
    ids2 = [f"b{i}" for i in range(only2)] + shared[::-1]
    entry = {"name": f"p{index}", "episode": index, "slot": 0, "sim_seed": 100 + index}
    entry["checksum"] = f"{index:064x}"
    views = (_view(ids1, index), _view(ids2, index + 50))
    return FramePair("/nonexistent", index, entry, {}, {}, views, noise_rate=0.0)


def _share(pairs) -> float:
    return noncovisible_share(
        [len(p.view1) for p in pairs],
        [len(p.view2) for p in pairs],
        [len(p.gt_pairs) for p in pairs],
    )


def test_thinning_keeps_every_covisible_object_and_the_share_falls_with_keep():
    pairs = [_pair(k) for k in range(20)]
    shares = []
    for keep in LEVELS:
        thinned = [thin_pair(p, keep) for p in pairs]
        for before, after in zip(pairs, thinned, strict=True):
            covisible = {before.view1.object_ids[i] for i, _ in before.gt_pairs}
            assert covisible <= set(after.view1.object_ids)
            assert covisible <= set(after.view2.object_ids)
            assert len(after.gt_pairs) == len(before.gt_pairs)
            # ground truth follows the kept objects
            for i, j in after.gt_pairs:
                assert after.view1.object_ids[i] == after.view2.object_ids[j]
        shares.append(_share(thinned))
    assert shares[0] == pytest.approx(_share(pairs)) and shares[-1] == 0.0
    assert all(a > b for a, b in zip(shares, shares[1:], strict=False))
    # Roughly the expected share at keep 0.5: 21 distractors per pair, half kept, 8 covisible.
    assert shares[2] == pytest.approx(10.5 / 18.5, abs=0.08)


def test_levels_are_nested_and_the_draw_belongs_to_the_pair_not_the_call():
    pair = _pair(3)
    identity = PairIdentity.of(pair)
    kept = {}
    for keep in LEVELS:
        rows = kept_rows(identity, len(pair.view1), len(pair.view2), pair.gt_pairs, keep)
        again = kept_rows(identity, len(pair.view1), len(pair.view2), pair.gt_pairs, keep)
        assert all(np.array_equal(a, b) for a, b in zip(rows, again, strict=True))
        kept[keep] = [set(r.tolist()) for r in rows]
    for high, low in zip(LEVELS, LEVELS[1:], strict=False):
        assert kept[low][0] <= kept[high][0] and kept[low][1] <= kept[high][1]
    assert thin_pair(pair, 1.0) is pair
    other = kept_rows(
        identity._replace(slot=1), len(pair.view1), len(pair.view2), pair.gt_pairs, 0.5
    )
    assert [set(r.tolist()) for r in other] != kept[0.5]  # another pair, other draws
    redraw = kept_rows(identity, len(pair.view1), len(pair.view2), pair.gt_pairs, 0.5, draw=1)
    assert [set(r.tolist()) for r in redraw] != kept[0.5]  # another draw of the same pair


def test_the_draw_depends_on_the_identity_not_on_the_stored_bytes():
    pair = _pair(4)
    changed = _pair(4)
    changed.checksum = "e" * 64  # a last-bit change of a stored pose changes the checksum ...
    changed.view1.positions[0, 0] = np.nextafter(changed.view1.positions[0, 0], 1.0)
    for draw in range(3):
        a, b = thin_pair(pair, 0.5, draw), thin_pair(changed, 0.5, draw)
        assert a.view1.object_ids == b.view1.object_ids  # ... but not which objects stay
        assert a.view2.object_ids == b.view2.object_ids
    with pytest.raises(ValueError, match="draw"):
        thin_pair(pair, 0.5, draw=-1)


def test_draws_of_one_level_are_independent_replicates():
    pair = _pair(6, covisible=2, only1=40, only2=40)
    kept = [len(thin_pair(pair, 0.5, d).view1) - 2 for d in range(40)]
    assert len(set(kept)) > 5  # the kept count varies across draws ...
    assert np.mean(kept) == pytest.approx(20, abs=2.5)  # ... around keep × 40


def test_thinned_pair_problem_has_the_kept_detections():
    pair = _pair(5)
    thinned = thin_pair(pair, 0.0)
    problem = thinned.problem()
    assert (problem.n1, problem.n2) == (4, 4)
    rows1 = [pair.view1.object_ids.index(o) for o in thinned.view1.object_ids]
    np.testing.assert_array_equal(problem.points1, pair.view1.positions[rows1])


@pytest.mark.parametrize("keep", [-0.1, 1.5, float("nan"), "x"])
def test_keep_outside_zero_one_is_rejected(keep):
    with pytest.raises(ValueError, match="keep"):
        thin_pair(_pair(0), keep)
