"""The multi-agent study's fused-row cache (``eval/studies/multiagent/fused_cache.py``): a stored
table comes back equal, dtypes and times included; a tampered, truncated or foreign entry, or one
holding other groups than the task's, is refused; the key follows every input; a fusion that is
not a built-in is never cached. The end-to-end rerun: tests/test_reproduce.py."""

from __future__ import annotations

import json
import logging

import pandas as pd
import pytest
from test_multiagent_study import snapshot_row

from eval.core import digest_store
from eval.studies.multiagent import fused_cache
from matchers.fusion import checked_fusion

GROUP = ("split", "n_agents", "preset", "matcher", "seed", "fusion")


def _table() -> pd.DataFrame:
    rows = [
        snapshot_row(fusion, k, k, 3 + k, 4, 5, split=split, seed=seed)
        for split in ("test", "val")
        for seed in (0, 1)
        for fusion in ("independent", "clear")
        for k in range(3)
    ]
    table = pd.DataFrame(rows)
    table.loc[0, "seconds"] = 0.1 + 0.2  # a float that only round-trips exactly
    return table


def _groups(table: pd.DataFrame) -> set[tuple]:
    return set(table[list(GROUP)].drop_duplicates().itertuples(index=False, name=None))


def test_a_stored_table_comes_back_equal(tmp_path):
    table = _table()
    store = fused_cache.FusedCache(tmp_path)
    assert store.store("k", table) is not None
    back = store.load("k", _groups(table))
    pd.testing.assert_frame_equal(back, table)
    assert back.loc[0, "seconds"] == 0.1 + 0.2


def _edit_value(path):
    entry = json.loads(path.read_text())
    entry["payload"]["per_snapshot"]["values"][2][0] = 99  # a better count than it earned
    path.write_text(json.dumps(entry))


def _drop_column_consistently(path):
    entry = json.loads(path.read_text())
    stored = entry["payload"]["per_snapshot"]
    k = stored["columns"].index("true_positives")
    for part in ("columns", "dtypes", "values"):
        del stored[part][k]
    entry["digest"] = digest_store.digest(digest_store.dump(entry["payload"]))  # forged
    path.write_text(json.dumps(entry))


def _truncate(path):
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])


def _other_key(path):
    entry = json.loads(path.read_text())
    entry["key"] = "other"
    path.write_text(json.dumps(entry))


@pytest.mark.parametrize("tamper", [_edit_value, _drop_column_consistently, _truncate, _other_key])
def test_a_tampered_entry_is_refused(tmp_path, tamper, caplog):
    table = _table()
    store = fused_cache.FusedCache(tmp_path)
    tamper(store.store("k", table))
    with caplog.at_level(logging.WARNING, logger="eval.reproduce"):
        assert store.load("k", _groups(table)) is None
    assert "multi-agent result cache: refused" in caplog.text


def test_an_entry_of_other_groups_is_refused(tmp_path, caplog):
    table = _table()
    store = fused_cache.FusedCache(tmp_path)
    store.store("k", table[table["seed"] == 0])  # a table of one run, asked for two
    with caplog.at_level(logging.WARNING, logger="eval.reproduce"):
        assert store.load("k", _groups(table)) is None
    assert "groups" in caplog.text


def test_the_key_follows_every_input(monkeypatch):
    args = (["run-a", "run-b"], ["sm"], {2: (1, 2)}, ["denied"], [0], ["independent"])
    key = fused_cache.fused_key(*args)
    assert fused_cache.fused_key(*args) == key
    for k, other in enumerate(
        (["run-a", "run-c"], ["maximin"], {2: (1, 3)}, ["gnss-urban"], [0, 1], ["clear"])
    ):
        assert fused_cache.fused_key(*args[:k], other, *args[k + 1 :]) != key
    monkeypatch.setattr(fused_cache, "study_version", lambda: "an edited study")
    assert fused_cache.fused_key(*args) != key


def test_only_built_in_fusions_are_cached():
    assert fused_cache.cacheable({"clear": checked_fusion("clear")})
    plug = "plugin_fakes:fusion_nan_time"
    assert not fused_cache.cacheable({"clear": checked_fusion("clear"), plug: checked_fusion(plug)})
