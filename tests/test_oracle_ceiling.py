"""The oracle as a ceiling (eval/protocol/oracle_ceiling.py): the paired difference of a matcher's
pose success against the oracle's, with an episode interval, and the committed pose tables, where
no matcher is above the oracle beyond its interval."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from eval.protocol.oracle_ceiling import oracle_ceiling

ROOT = Path(__file__).resolve().parents[1]


def _frames(matcher_ok: np.ndarray, oracle_ok: np.ndarray, per_episode: int = 2) -> pd.DataFrame:
    n = len(matcher_ok)
    good, bad = (0.5, 0.5), (3.0, 4.0)
    rows = []
    for k in range(n):
        m, o = (good if matcher_ok[k] else bad), (good if oracle_ok[k] else bad)
        for name, (rte, rre) in (("lucky", m), ("same", o)):
            rows.append({"matcher": name, "split": "test", "pair": k, "episode": k // per_episode,
                         "rte_m": rte, "rre_deg": rre, "oracle_rte_m": o[0], "oracle_rre_deg": o[1]})  # fmt: skip
    return pd.DataFrame(rows)


def test_one_lucky_frame_is_above_within_noise_and_the_oracle_itself_is_at_or_below():
    oracle_ok = np.arange(26) % 3 != 0
    matcher_ok = oracle_ok.copy()
    matcher_ok[0] = True  # one frame where the matcher's fit lands and the oracle's does not
    table = oracle_ceiling(_frames(matcher_ok, oracle_ok)).set_index("matcher")
    assert table.loc["lucky", "difference"] == pytest.approx(1 / 26)
    assert table.loc["lucky", "ci_low"] < 0 < table.loc["lucky", "ci_high"]
    assert table.loc["lucky", "verdict"] == "above, within noise"
    assert table.loc["same", "difference"] == 0 and table.loc["same", "verdict"] == "at or below"
    assert table.loc["lucky", "clusters"] == 13


def test_a_matcher_above_on_many_frames_is_above():
    oracle_ok = np.zeros(26, dtype=bool)
    matcher_ok = np.arange(26) % 2 == 0  # one frame of every episode
    table = oracle_ceiling(_frames(matcher_ok, oracle_ok)).set_index("matcher")
    assert table.loc["lucky", "ci_low"] > 0 and table.loc["lucky", "verdict"] == "above"


def test_a_failed_fit_counts_as_unsuccessful():
    frames = _frames(np.ones(4, dtype=bool), np.ones(4, dtype=bool))
    frames.loc[frames["matcher"] == "lucky", "rte_m"] = np.nan
    table = oracle_ceiling(frames).set_index("matcher")
    assert table.loc["lucky", "success"] == 0 and table.loc["lucky", "difference"] == -1


@pytest.mark.parametrize(
    "path",
    sorted((ROOT / "results").glob("v2x*/*/metrics_per_pair.csv")),
    ids=lambda p: f"{p.parent.parent.name}/{p.parent.name}",
)
def test_no_matcher_is_above_the_oracle_beyond_its_interval_in_the_committed_tables(path):
    table = oracle_ceiling(pd.read_csv(path))
    # a common-region folder holds the sensor comparison's validation-chosen matchers only
    assert len(table) >= (1 if path.parent.name.endswith("_common") else 10)
    assert (table["verdict"] != "above").all(), table[table["verdict"] == "above"]
