"""The power analysis (eval/engine/power_analysis.py): the clusters a comparison needs, checked
against the closed form on clustered samples of known ICC, and power_analysis.csv written from a
small planted results folder."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from eval.engine.power_analysis import (
    COLUMNS,
    FILE,
    clusters_needed,
    figure_factor,
    needed_clusters,
    paired_row,
    write_power_analysis,
)
from eval.protocol.cluster_correlation import design_effect
from eval.studies import power_checks

Z975, Z80 = 1.959964, 0.841621


def _clustered(rng, groups: int, size: int, icc: float, sd: float = 0.2):
    """Per-item values, G clusters of ``size``, total variance sd², the share ``icc`` between."""
    between = rng.normal(0, sd * math.sqrt(icc), groups)
    within = rng.normal(0, sd * math.sqrt(1 - icc), (groups, size))
    return (between[:, None] + within).reshape(-1), np.repeat(np.arange(groups), size)


@pytest.mark.parametrize(("icc", "size"), [(0.0, 5), (0.3, 5), (0.8, 4)])
def test_needed_clusters_match_the_design_effect_formula(icc, size):
    # the variance of a cluster's mean is sd² · (1 + (m − 1) ICC) / m: the clusters needed for an
    # MDD of 5 points are (z₀.₉₇₅ + z₀.₈)² · that / 0.05², whatever the sample measured it on
    rng = np.random.default_rng(7)
    values, clusters = _clustered(rng, 3000, size, icc)
    true_se = 0.2 * math.sqrt(design_effect(icc, size) / size / 3000)
    got = clusters_needed(values, clusters, 0.05, "mdd")
    assert got == pytest.approx(needed_clusters(true_se, 3000, 0.05, "mdd"), rel=0.1)
    # the closed form, large-sample: (z₀.₉₇₅ + z₀.₈)² · sd² · design effect / (m · 0.05²)
    closed = (Z975 + Z80) ** 2 * 0.2**2 * design_effect(icc, size) / size / 0.05**2
    assert got == pytest.approx(closed, rel=0.25)
    half = clusters_needed(values, clusters, 0.05, "half_width")
    assert half == pytest.approx(needed_clusters(true_se, 3000, 0.05, "half_width"), rel=0.1)
    row = paired_row("s", "c", "p", values, clusters, "mdd")
    assert row["icc"] == pytest.approx(icc, abs=0.05)
    assert row["clusters"] == 3000 and row["items"] == 3000 * size
    assert row["clusters_needed"] == got


@settings(max_examples=60, deadline=None)
@given(
    se=st.floats(1e-4, 0.5),
    clusters=st.integers(2, 500),
    kind=st.sampled_from(["mdd", "half_width"]),
)
def test_needed_clusters_is_the_fewest_that_reach_the_goal(se, clusters, kind):
    g = needed_clusters(se, clusters, 0.05, kind)
    spread = se * math.sqrt(clusters)

    def figure(n):
        return figure_factor(n, kind) * spread / math.sqrt(n)

    assert g is not None and g >= 2
    assert figure(g) <= 0.05
    if g > 2:
        assert figure(g - 1) > 0.05
    # large samples: n_now · (now / goal)², never fewer (t quantiles exceed the normal ones)
    z = Z975 + (Z80 if kind == "mdd" else 0.0)
    assert g >= (z * spread / 0.05) ** 2 - 1


def test_no_spread_or_one_cluster():
    assert needed_clusters(float("nan"), 40) is None
    assert needed_clusters(0.01, 1) is None
    assert clusters_needed(np.ones(5), np.arange(5)) == 2


def _plant(folder, rng):
    """A V2X camera table (two presets, one pair per episode, two runs) and a temporal gain."""
    rows = []
    for preset, shift in (("exact", 0.02), ("denied", 0.1)):
        for pair in range(30):
            for matcher, base in (("a", 0.8 + shift), ("b", 0.8), ("none", 0.0)):
                for seed in (0, 1):
                    f1 = base + rng.normal(0, 0.15 if preset == "denied" else 0.03)
                    rows.append((matcher, seed, pair, pair, f1, preset))
    (folder / "v2x").mkdir()
    per_pair = pd.DataFrame(rows, columns=["matcher", "seed", "pair", "episode", "f1", "preset"])
    per_pair.to_csv(folder / "v2x" / "metrics_per_pair.csv", index=False)
    pd.DataFrame(
        [("exact", "a", "b"), ("denied", "a", "b")], columns=["preset", "best", "runner_up"]
    ).to_csv(folder / "table_v2x_intervals.csv", index=False)
    pd.DataFrame(
        [("denied", "m", "tuned per W", 0.2, 0.1, 0.3, 40)],
        columns=[
            "preset",
            "method",
            "parameters",
            "pooled_diff",
            "pooled_low",
            "pooled_high",
            "clusters",
        ],  # fmt: skip
    ).to_csv(folder / "table_temporal_gain.csv", index=False)
    return per_pair


def test_the_csv_is_written_from_a_results_folder(tmp_path):
    per_pair = _plant(tmp_path, np.random.default_rng(3))
    path = write_power_analysis(tmp_path, power_checks())  # every study's; absent files skipped
    assert path == tmp_path / FILE
    table = pd.read_csv(path)
    assert tuple(table.columns) == COLUMNS
    v2x = table[table["study"] == "v2x"].set_index("condition")
    assert set(v2x.index) == {"exact", "denied"} and set(v2x["kind"]) == {"half_width"}
    # the half-width is that of the per-pair (run-averaged) difference a − b, 30 clusters
    here = per_pair[per_pair["preset"] == "denied"].groupby(["pair", "matcher"])["f1"].mean()
    diff = (here.xs("a", level="matcher") - here.xs("b", level="matcher")).to_numpy()
    expected = figure_factor(30, "half_width") * diff.std(ddof=1) / math.sqrt(30)
    assert v2x.loc["denied", "now"] == pytest.approx(expected, rel=1e-4)
    assert v2x.loc["denied", "clusters"] == 30
    assert v2x.loc["denied", "clusters_needed"] > v2x.loc["exact", "clusters_needed"]
    temporal = table[table["study"] == "temporal"].iloc[0]
    assert temporal["kind"] == "mdd" and temporal["clusters"] == 40
    se = 0.2 / (2 * Z975)  # from the bootstrap interval [0.1, 0.3]
    assert temporal["now"] == pytest.approx(figure_factor(40, "mdd") * se, rel=1e-3)
    assert temporal["clusters_needed"] == needed_clusters(se, 40, 0.05, "mdd")


def test_nothing_written_without_files(tmp_path):
    assert write_power_analysis(tmp_path, power_checks()) is None
    assert not (tmp_path / FILE).exists()


def test_the_report_step_writes_the_csv_and_shows_its_table(tmp_path):
    from eval.readme_results import write_report

    _plant(tmp_path, np.random.default_rng(5))
    report, _ = write_report(tmp_path)
    assert len(pd.read_csv(tmp_path / FILE)) == 3  # two V2X presets, one temporal goal
    table = (tmp_path / "power_analysis.md").read_text()
    assert "| v2x | camera: a − b | denied | half-width ≤ ±5 | 30 |" in table
    assert table.strip() in report.read_text()  # in full in the report's appendix
