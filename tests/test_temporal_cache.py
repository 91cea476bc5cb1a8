"""The temporal result cache (``eval/studies/temporal/outcome_cache.py``): a second run of the
study reads every preset from it without running a method and writes byte-identical files; a
tampered or truncated entry is refused, logged and recomputed; the key follows the datasets and
the task."""

from __future__ import annotations

import json
import logging
import math

import numpy as np
import pandas as pd
import pytest
import test_sequences as seqs

from eval.core import digest_store
from eval.studies.temporal import evaluation as temporal
from eval.studies.temporal import outcome_cache

METHODS = (("windowed:consistency", (1, 10)), ("temporal_pose", (1,)))
PRESETS = ("denied",)  # temporal_pose abstains there: a row with no number is stored too


@pytest.fixture(scope="module")
def dirs(tmp_path_factory):
    root = tmp_path_factory.mktemp("temporal-cache")
    scenario = seqs._scenario(frames=3)
    seqs._generate(root / "test", scenario, pairs=2)
    seqs._generate(root / "val", scenario, pairs=2, seed=99)
    return root


def _files(out):
    return {
        p.relative_to(out).as_posix(): p.read_bytes() for p in sorted(out.rglob("*")) if p.is_file()
    }


def _study(dirs, out, cache):
    return temporal.evaluate_temporal(
        dirs / "test", dirs / "val", out, METHODS, PRESETS, tune=False, cache=cache
    )


def _no_runs(monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("a preset was run, not read from the cache")

    monkeypatch.setattr(temporal, "evaluate_preset", refuse)


@pytest.fixture(scope="module")
def cold(dirs):
    """The files of a first run, storing into a cache."""
    _study(dirs, dirs / "cold", dirs / "cache")
    return _files(dirs / "cold")


def _but_timing(files: dict) -> dict:
    """`files` without the table's CSV (its ``ms_per_frame`` is measured on each run)."""
    return {k: v for k, v in files.items() if k != "table_temporal.csv"}


def _entry(dirs):
    (entry,) = (dirs / "cache").glob("*.json")
    return entry


def test_a_cached_run_runs_nothing_and_writes_the_same_bytes(dirs, cold, monkeypatch, caplog):
    _study(dirs, dirs / "plain", None)
    assert _but_timing(_files(dirs / "plain")) == _but_timing(cold)  # storing changes nothing
    assert "table_temporal.csv" in cold and "temporal/per_frame.csv" in cold
    _no_runs(monkeypatch)
    with caplog.at_level(logging.INFO, logger="eval.reproduce"):
        _study(dirs, dirs / "warm", dirs / "cache")
    assert _files(dirs / "warm") == cold  # timing columns too: the stored ones
    assert "denied: read from the result cache" in caplog.text


def test_a_numpy_scalar_nan_and_none_round_trip(tmp_path, dirs):
    task = (str(dirs / "test"), str(dirs / "val"), "denied", METHODS, (0,), False)
    outcome = temporal.evaluate_preset(task)
    outcome.rows[0] |= {"tau": math.nan, "frames": np.int64(6), "f1_mean": np.float32(0.5)}
    outcome.continuity[0]["continuity_low"] = None
    nullable = pd.array([1, None, 3], dtype="Int64")
    outcome.per_frame.append(pd.DataFrame({"n": nullable, "f": [0.5, math.nan, -0.0]}))
    cache = outcome_cache.OutcomeCache(tmp_path)
    key = outcome_cache.task_key(task)
    cache.store(key, outcome)
    back = cache.load(key, task)
    assert math.isnan(back.rows[0]["tau"]) and back.continuity[0]["continuity_low"] is None
    assert type(back.rows[0]["frames"]) is int and back.rows[0]["f1_mean"] == 0.5
    for name in ("rows", "gain", "tuned", "continuity"):  # NaN != NaN: compared as JSON
        assert digest_store.dump(getattr(back, name)) == digest_store.dump(getattr(outcome, name))
    for a, b in zip(back.per_frame, outcome.per_frame, strict=True):
        assert a.equals(b) and list(a.dtypes) == list(b.dtypes)


def test_an_outcome_the_format_cannot_hold_is_not_stored(tmp_path, dirs, caplog):
    task = (str(dirs / "test"), str(dirs / "val"), "denied", METHODS, (0,), False)
    outcome = temporal.evaluate_preset(task)
    outcome.rows[0]["params"] = {"not": "a cell"}.keys()
    cache = outcome_cache.OutcomeCache(tmp_path)
    with caplog.at_level(logging.WARNING, logger="eval.reproduce"):
        assert cache.store("k", outcome) is None
    assert "not stored" in caplog.text and not list(tmp_path.iterdir())


def _edit_value(path):
    entry = json.loads(path.read_text())
    entry["payload"]["rows"][0]["f1_pooled"] = 0.999  # a better score than it earned
    path.write_text(json.dumps(entry))


def _drop_key_consistently(path):
    entry = json.loads(path.read_text())
    del entry["payload"]["rows"][0]["f1_pooled"]
    payload = entry["payload"]
    entry["digest"] = digest_store.digest(digest_store.dump(payload))  # a forged digest
    path.write_text(json.dumps(entry))


def _truncate(path):
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])


def _other_key(path):
    entry = json.loads(path.read_text())
    entry["key"] = "0" * 64
    path.write_text(json.dumps(entry))


@pytest.mark.parametrize("tamper", [_edit_value, _drop_key_consistently, _truncate, _other_key])
def test_a_tampered_entry_is_refused_and_recomputed(dirs, cold, tamper, monkeypatch, caplog):
    entry = _entry(dirs)
    good = entry.read_bytes()
    tamper(entry)
    calls = []
    real = temporal.evaluate_preset
    monkeypatch.setattr(temporal, "evaluate_preset", lambda task: calls.append(task) or real(task))
    out = dirs / f"tampered-{tamper.__name__}"
    with caplog.at_level(logging.WARNING, logger="eval.reproduce"):
        _study(dirs, out, dirs / "cache")
    assert len(calls) == 1 and "temporal result cache: refused" in caplog.text
    assert _but_timing(_files(out)) == _but_timing(cold)
    assert json.loads(entry.read_text())["payload"]["rows"][0]["f1_pooled"] != 0.999
    entry.write_bytes(good)  # the next test starts from the first run's entry


def test_the_key_follows_the_task_the_datasets_and_the_code(dirs, monkeypatch):
    import cadsim.dataset

    task = (str(dirs / "test"), str(dirs / "val"), "denied", METHODS, (0,), False)
    key = outcome_cache.task_key(task)
    assert outcome_cache.task_key(task) == key
    assert outcome_cache.task_key((*task[:5], True)) != key  # tune
    assert outcome_cache.task_key((*task[:2], "gnss-urban", *task[3:])) != key
    assert outcome_cache.task_key((*task[:3], METHODS[:1], *task[4:])) != key
    monkeypatch.setattr(outcome_cache, "study_version", lambda: "an edited study")
    assert outcome_cache.task_key(task) != key
    monkeypatch.undo()

    class Regenerated:  # the same folders, other records
        def __init__(self, path):
            self.checksum = "f" * 64

    monkeypatch.setattr(cadsim.dataset, "Dataset", Regenerated)
    assert outcome_cache.task_key(task) != key


def test_the_study_sources_are_in_the_version():
    names = outcome_cache._study_files()
    assert {"eval/studies/temporal/preset.py", "eval/protocol/tuning.py"} <= set(names)
    assert "eval/studies/temporal/outcome_cache.py" in names
