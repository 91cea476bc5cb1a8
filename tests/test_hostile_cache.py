"""The result cache never serves what it cannot stand behind: a re-saved entry whose assignment,
ground truth, sizes, scores or times were changed is refused and recomputed; a ``.npy`` header
declaring absurd sizes is refused in bounded memory; editing a plug-in matcher's source reruns
it; the log says when results come from the cache."""

from __future__ import annotations

import dataclasses
import io
import json
import logging
import resource
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from cadsim.dataset import Dataset
from eval.core.cache import ResultCache
from eval.core.cache_checks import StaleEntry, inconsistent_groups
from eval.core.executor import SerialExecutor
from eval.core.runner import Runner, requests_for
from eval.core.tasks import MatcherSpec

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "eval" / "data" / "dmgm-cad" / "val-070"
PAIRS = 4


def _runner(cache: Path) -> Runner:
    return Runner(ResultCache(cache), SerialExecutor(), version="hostile", progress=False)


def _requests(matcher: str = "appearance"):
    checksum = Dataset(DATA).checksum
    return requests_for([(str(DATA), checksum)], [MatcherSpec(matcher)], [0], limit=PAIRS)


@pytest.fixture
def cached(tmp_path):
    """A cache holding one real run (appearance, 4 frame pairs of a committed dataset): the
    runner, the request, the entry's path and the result as computed."""
    runner = _runner(tmp_path / "cache")
    reqs = _requests()
    (result,) = runner.run(reqs)
    assert runner.stats.computed == 1
    return runner, reqs, runner.cache.path(result.spec), result


def _rewrite(path: Path, edit) -> None:
    """Re-save the ``.npz`` at `path` with ``edit(arrays, meta)`` applied (as a hand edit would)."""
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    meta = json.loads(str(arrays["meta"]))
    edit(arrays, meta)
    arrays["meta"] = np.array(json.dumps(meta))
    with path.open("wb") as f:
        np.savez_compressed(f, **arrays)


def _served_again(runner, reqs, original) -> None:
    """The next run recomputes the entry and returns the original result."""
    (again,) = runner.run(reqs)
    assert (runner.stats.cached, runner.stats.computed) == (0, 1)
    for a, b in zip(original.outcomes, again.outcomes, strict=True):
        np.testing.assert_array_equal(a.assigned, b.assigned)
        np.testing.assert_array_equal(a.gt_pairs, b.gt_pairs)
        np.testing.assert_array_equal(a.scores, b.scores)
    runner.run(reqs)
    assert (runner.stats.cached, runner.stats.computed) == (1, 0)  # the recomputed one is served


def test_an_untouched_entry_is_served_and_the_log_says_so(cached, caplog):
    runner, reqs, _, _ = cached
    with caplog.at_level(logging.INFO, logger="eval.core.runner"):
        runner.run(reqs)
    assert (runner.stats.cached, runner.stats.computed) == (1, 0)
    assert "1 of 1 runs read from the result cache" in caplog.text


def test_assignments_replaced_by_the_ground_truth_are_recomputed(cached, caplog):
    runner, reqs, path, result = cached

    def forge(arrays, meta):
        arrays["assigned"] = arrays["gt_pairs"]
        arrays["assigned_offsets"] = arrays["gt_pairs_offsets"]

    _rewrite(path, forge)
    with pytest.raises(StaleEntry, match="Hungarian"):
        runner.cache.load(result.spec)
    with caplog.at_level(logging.WARNING, logger="eval.core.runner"):
        _served_again(runner, reqs, result)
    assert "refused" in caplog.text


@pytest.mark.parametrize(
    "forge, why",
    [
        (lambda r: setattr(r.outcomes[1], "gt_pairs", np.zeros((0, 2), np.int64)), "ground truth"),
        (lambda r: r.outcomes[0].gt_pairs.__setitem__((0, 1), 0), "ground truth"),
        (lambda r: setattr(r.outcomes[2], "name", "e99999_s00"), "not the dataset's"),
        (lambda r: r.outcomes.pop(), "frame pairs where the dataset has"),
    ],
)
def test_an_entry_that_disagrees_with_the_dataset_is_recomputed(cached, forge, why, caplog):
    """Re-saved through the cache's own writer, so only the dataset can tell."""
    runner, reqs, _, result = cached
    forged = runner.cache.load(result.spec)
    forge(forged)
    runner.cache.store(forged)
    with caplog.at_level(logging.WARNING, logger="eval.core.runner"):
        _served_again(runner, reqs, result)
    assert why in caplog.text


def _view_grown(r):
    o = r.outcomes[0]
    o.n1 += 1
    o.scores = np.vstack([o.scores, np.zeros((1, o.n2))])
    o.points1 = np.vstack([o.points1, np.zeros((1, o.points1.shape[1]))])


@pytest.mark.parametrize(
    "forge, why",
    [
        (lambda r: r.outcomes[0].scores.__setitem__((0, 0), np.nan), "finite values in [0, 1]"),
        (lambda r: r.outcomes[1].scores.__setitem__((0, 0), 7.0), "finite values in [0, 1]"),
        (lambda r: setattr(r, "wall_s", float("nan")), "wall_s nan"),
        (lambda r: setattr(r.outcomes[0], "time_s", -1.0), "time_s -1.0"),
        (lambda r: setattr(r.outcomes[0], "gt_pairs", np.array([[0, 99]])), "outside"),
        (lambda r: setattr(r.outcomes[0], "assigned", np.array([[0, 0], [0, 1]])), "twice"),
        (_view_grown, "objects where the dataset has"),
    ],
)
def test_impossible_scores_times_indices_and_sizes_are_recomputed(cached, forge, why, caplog):
    runner, reqs, _, result = cached
    forged = runner.cache.load(result.spec)
    forge(forged)
    runner.cache.store(forged)
    with caplog.at_level(logging.WARNING, logger="eval.core.runner"):
        _served_again(runner, reqs, result)
    assert why in caplog.text


def _huge_header_npz(path: Path) -> None:
    """A valid entry whose ``scores`` member now declares 10¹² float64 items (a 100-byte body)."""
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, value in arrays.items():
            member = io.BytesIO()
            np.save(member, value)
            body = member.getvalue()
            if name == "scores":
                header = {"descr": "<f8", "fortran_order": False, "shape": (10**12,)}
                member = io.BytesIO()
                np.lib.format.write_array_header_1_0(member, header)
                body = member.getvalue() + b"\0" * 100
            archive.writestr(f"{name}.npy", body)
    path.write_bytes(buffer.getvalue())


def test_a_header_declaring_a_trillion_items_is_refused_in_bounded_memory(cached):
    runner, reqs, path, result = cached
    _huge_header_npz(path)
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    mapped = next(
        int(line.split()[1]) * 1024
        for line in Path("/proc/self/status").read_text().splitlines()
        if line.startswith("VmSize:")
    )
    limit = mapped + 2**30
    resource.setrlimit(resource.RLIMIT_AS, (limit if hard < 0 else min(limit, hard), hard))
    try:
        with pytest.raises(StaleEntry, match=r"declares shape \(1000000000000,\)"):
            runner.cache.load(result.spec)
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))
    _served_again(runner, reqs, result)


PLUGIN = """
import numpy as np
from matchers.core.result import finish
import time

def match(problem, seed=0, threshold=None, **options):
    n1, n2 = len(problem.points1), len(problem.points2)
    return finish("plug", np.full((n1, n2), {value}), threshold, time.perf_counter())
"""


def test_editing_a_plug_in_matchers_source_reruns_it(tmp_path, monkeypatch):
    module = tmp_path / "hostile_cache_plugin.py"
    module.write_text(PLUGIN.format(value=0.75))
    monkeypatch.syspath_prepend(str(tmp_path))
    runner = _runner(tmp_path / "cache")
    reqs = _requests("hostile_cache_plugin:match")
    (first,) = runner.run(reqs)
    assert runner.stats.computed == 1 and first.outcomes[0].scores.max() == 0.75
    runner.run(reqs)
    assert runner.stats.cached == 1  # unchanged: served
    module.write_text(PLUGIN.format(value=0.0))
    sys.modules.pop("hostile_cache_plugin", None)  # what a new process does
    (edited,) = runner.run(reqs)
    assert runner.stats.computed == 1 and edited.outcomes[0].scores.max() == 0.0
    assert edited.spec.code_version.startswith("hostile+")
    sys.modules.pop("hostile_cache_plugin", None)


def test_runs_on_the_same_data_that_disagree_on_the_ground_truth_are_all_refused(cached):
    runner, _, _, result = cached
    other = dataclasses.replace(result, spec=dataclasses.replace(result.spec, seed=3))
    twin = runner.cache.load(result.spec)
    twin.spec = dataclasses.replace(result.spec, matcher=MatcherSpec("sm"))
    assert inconsistent_groups([result, twin, other]) == set()
    twin.outcomes[3].gt_pairs = twin.outcomes[3].gt_pairs[:1]
    assert inconsistent_groups([result, twin, other]) == {0, 1}
