"""Result cache: keys change with every input, entries round-trip exactly, writes are atomic."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from eval.core import cache as cache_module
from eval.core.cache import ResultCache
from eval.core.tasks import MatcherSpec, PairOutcome, RunResult, RunSpec

BASE = RunSpec(
    "ab" * 32, MatcherSpec.of("maximin", alpha=0.3), seed=0, noise_rate=None, code_version="c0de"
)


@pytest.mark.parametrize(
    "changed",
    [
        dataclasses.replace(BASE, dataset_checksum="cd" * 32),
        dataclasses.replace(BASE, matcher=MatcherSpec.of("mos", alpha=0.3)),
        dataclasses.replace(BASE, matcher=MatcherSpec.of("maximin", alpha=0.5)),
        dataclasses.replace(BASE, matcher=MatcherSpec("maximin")),
        dataclasses.replace(BASE, seed=1),
        dataclasses.replace(BASE, noise_rate=0.0),
        dataclasses.replace(BASE, noise_rate=0.01),
        dataclasses.replace(BASE, code_version="c0df"),
        dataclasses.replace(BASE, limit=10),
        dataclasses.replace(BASE, keep=0.5),
        dataclasses.replace(BASE, keep=0.0),
        dataclasses.replace(BASE, views=(1, 2)),
        dataclasses.replace(BASE, views=(2, 1)),
    ],
)
def test_key_changes_with_every_input(changed):
    assert changed.key() != BASE.key()


def test_key_is_stable_and_option_order_free():
    same = dataclasses.replace(BASE, matcher=MatcherSpec.of("maximin", alpha=0.3))
    assert same.key() == BASE.key()
    a = MatcherSpec.of("tm", k=5, sigma=0.5)
    b = MatcherSpec.of("tm", sigma=0.5, k=5)
    assert a == b and a.label == "tm[k=5,sigma=0.5]"


def test_code_version_changes_when_a_source_file_changes(tmp_path, monkeypatch):
    src = tmp_path / "matchers" / "maximin.py"
    src.parent.mkdir()
    src.write_text("alpha = 0.3\n")
    monkeypatch.setattr(cache_module, "_source_files", lambda: [("matchers/maximin.py", src)])
    cache_module.code_version.cache_clear()
    try:
        before = cache_module.code_version()
        src.write_text("alpha = 0.4\n")
        cache_module.code_version.cache_clear()
        assert cache_module.code_version() != before
    finally:
        cache_module.code_version.cache_clear()


def test_real_code_version_covers_matchers_detection_and_tasks():
    names = [name for name, _ in cache_module._source_files()]
    assert "matchers/core/discretise.py" in names
    assert "eval/core/tasks.py" in names and "eval/core/thinning.py" in names
    assert any(n.startswith("cadsim/dataset/") for n in names)


def _result(spec: RunSpec) -> RunResult:
    rng = np.random.default_rng(0)
    outcomes = []
    for index, (n1, n2) in enumerate([(4, 6), (0, 3), (5, 5)]):
        k = min(n1, n2)
        outcomes.append(
            PairOutcome(
                index=index, name=f"e{index:05d}_s00", episode=index, sim_seed=7 + index,
                checksum=f"{index:064x}", n1=n1, n2=n2,
                gt_pairs=np.array([[i, i] for i in range(min(k, 2))], dtype=np.int64).reshape(-1, 2),
                assigned=np.stack([np.arange(k), np.arange(k)], axis=1).astype(np.int64),
                scores=rng.uniform(size=(n1, n2)), time_s=0.01 * index, iterations=3,
            )
        )  # fmt: skip
    return RunResult(spec, "data/cad", outcomes, wall_s=1.5)


def test_a_two_view_key_does_not_depend_on_the_views_or_sensor_field():
    import hashlib
    import json

    fields = dataclasses.asdict(BASE)
    # the key of a record's own pair and detections is what it was before views and sensor existed
    del fields["views"], fields["sensor"]
    text = json.dumps(fields, sort_keys=True, separators=(",", ":"))
    assert BASE.key() == hashlib.sha256(text.encode()).hexdigest()


def test_store_and_load_round_trip_exactly(tmp_path):
    store = ResultCache(tmp_path)
    result = _result(BASE)
    path = store.store(result)
    assert BASE in store and path == store.path(BASE)
    assert [p.name for p in path.parent.iterdir()] == [path.name]  # no temporary file left
    loaded = store.load(BASE)
    assert loaded.spec == BASE and loaded.dataset_dir == "data/cad" and loaded.wall_s == 1.5
    for a, b in zip(result.outcomes, loaded.outcomes, strict=True):
        for field in dataclasses.fields(PairOutcome):
            x, y = getattr(a, field.name), getattr(b, field.name)
            if isinstance(x, np.ndarray):
                assert x.shape == y.shape and x.dtype == y.dtype
                np.testing.assert_array_equal(x, y)
            else:
                assert x == y, field.name
    thinned = dataclasses.replace(BASE, keep=0.25, limit=3)
    store.store(_result(thinned))
    assert store.load(thinned).spec == thinned
    pair_of_views = dataclasses.replace(BASE, views=(2, 5), localisation="denied")
    store.store(_result(pair_of_views))
    assert store.load(pair_of_views).spec == pair_of_views


def test_missing_corrupt_and_foreign_entries_are_reported(tmp_path):
    store = ResultCache(tmp_path)
    with pytest.raises(KeyError):
        store.load(BASE)
    path = store.path(BASE)
    path.parent.mkdir(parents=True)
    path.write_bytes(b"not an npz")
    with pytest.raises(ValueError, match="unreadable cache entry"):
        store.load(BASE)
    other = dataclasses.replace(BASE, seed=5)
    store.store(_result(other))
    store.path(other).replace(path)  # an entry under the wrong key
    with pytest.raises(ValueError, match="does not belong"):
        store.load(BASE)


def test_interrupted_write_leaves_no_entry(tmp_path, monkeypatch):
    store = ResultCache(tmp_path)

    def boom(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(np, "savez_compressed", boom)
    with pytest.raises(KeyboardInterrupt):
        store.store(_result(BASE))
    assert BASE not in store
    assert list(store.path(BASE).parent.iterdir()) == []
