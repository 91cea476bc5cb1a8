"""Abstention is not a score (DESIGN §3, ``eval/core/abstention.py``): a matcher that needs
the localisation prior gets no number where the condition gives none (``denied``) — in the rule
itself, in the two-view V2X table path (CSV, Markdown, README parts, "best", comparisons). The
temporal path is tested in tests/test_temporal_study.py."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from eval.core.abstention import NO_NUMBER, cannot_run, problem_lacks
from eval.core.result_files import write_csv
from matchers import Problem
from matchers.blocks.prior import PRIOR_FIELDS
from matchers.core.registry import requires, usable

READERS = [n for n in usable() if requires(n) & PRIOR_FIELDS]


def test_the_rule_reads_the_matchers_declared_requirement_not_a_list_of_names():
    assert {"pose", "pose_refine", "pose_appearance", "maximin_pose"} <= set(READERS)
    for name in READERS:
        assert cannot_run(name, "denied") and cannot_run(name, "denied*2+300ms")
        assert not cannot_run(name, "gnss-urban") and not cannot_run(name, None)
        assert cannot_run(f"windowed:{name}", "denied", temporal=True)
    for name in ("maximin", "mos", "freealign", "none", "appearance"):
        assert not cannot_run(name, "denied")
    assert cannot_run("temporal_pose", "denied", temporal=True)
    assert not cannot_run("windowed:consistency", "denied", temporal=True)
    assert not cannot_run("oracle", "denied")  # a reference row, not a matcher
    with pytest.raises(ValueError, match="preset"):
        cannot_run("pose", "nowhere")


def test_a_problem_without_the_prior_lacks_what_a_prior_reader_requires():
    points = np.random.default_rng(0).random((4, 3))
    bare = Problem(points, points)
    assert problem_lacks(PRIOR_FIELDS, bare) and not problem_lacks((), bare)
    given = Problem(points, points, world1=points, world2=points, world_sigma=1.0)
    assert not problem_lacks(PRIOR_FIELDS, given)


def _per_pair() -> pd.DataFrame:
    """Two presets, three matchers, 2 runs × 12 pairs in 4 episodes. Under ``denied`` ``pose``
    declares nothing, and a third of the pairs have no true pair: the per-pair convention would
    give it F1 1 there (mean 1/3), pooled 0 — neither may show."""
    rng = np.random.default_rng(0)
    rows = []
    for preset in ("gnss-urban", "denied"):
        for matcher, level in (("pose", 0.9), ("freealign", 0.6), ("sm", 0.4)):
            given = preset != "denied" or matcher != "pose"
            for seed in range(2):
                for pair in range(12):
                    n_gt = 0 if pair % 3 == 0 else 5
                    tp = int(rng.random() < level) * n_gt if given else 0
                    n_pred = n_gt if given else 0
                    f1 = 1.0 if n_gt == n_pred == 0 else (tp / n_gt if n_gt else 0.0)
                    rows.append(
                        {"preset": preset, "matcher": matcher, "seed": seed, "pair": pair}
                        | {"episode": pair // 3, "f1": f1, "tp": tp, "n_pred": n_pred}
                        | {"n_gt": n_gt, "time_s": 0.001, "pose_scored": True}
                        | {"rte_m": 0.5 if tp else np.nan, "rre_deg": 1.0 if tp else np.nan}
                        | {"rte_m_6dof": 1.5, "rre_deg_6dof": 1.0}
                        | {"oracle_rte_m": 0.5, "oracle_rre_deg": 1.0}
                        | {"prior_scored": preset != "denied", "prior_rte_m": 3.0}
                        | {"prior_rre_deg": 1.5}
                    )
    return pd.DataFrame(rows)


# validation that would choose the prior reader everywhere if it were allowed to
VALIDATION = {p: {"pose": 0.99, "freealign": 0.7, "sm": 0.5} for p in ("gnss-urban", "denied")}


def test_a_prior_reader_under_denied_gets_no_number_in_the_v2x_table(tmp_path):
    from eval.studies.v2x.markdown import to_markdown
    from eval.studies.v2x.table import COLUMNS, v2x_table

    table = v2x_table(_per_pair())
    rows = table.set_index(["preset", "matcher"])
    assert rows.loc[("denied", "pose"), list(COLUMNS[2:])].isna().all()
    assert rows.loc[("gnss-urban", "pose"), "f1_mean"] > 0.5  # where the prior is given
    assert rows.loc[("denied", "freealign"), "f1_mean"] > 0  # no prior needed: a number
    write_csv(table, tmp_path / "t.csv")
    line = next(x for x in (tmp_path / "t.csv").read_text().splitlines() if x.startswith("pose,d"))
    assert line == "pose,denied" + "," * (len(COLUMNS) - 2)  # every cell empty
    md = to_markdown(table, pd.DataFrame(), "X")
    assert f"| denied | pose | {NO_NUMBER} |" in md
    assert "| denied | pose | 0.0" not in md and "| denied | pose | 33.3" not in md


def test_a_prior_reader_under_denied_is_in_no_ranking_and_no_comparison():
    from eval.studies.v2x.report import chosen_row, compact, goals
    from eval.studies.v2x.table import best_against_runner_up, ranked_on_validation, v2x_table

    per_pair = _per_pair()
    table = v2x_table(per_pair)
    assert chosen_row(table, "gnss-urban", VALIDATION)[0] == "pose"
    assert chosen_row(table, "denied", VALIDATION)[0] == "freealign"
    denied = per_pair[per_pair["preset"] == "denied"]
    assert ranked_on_validation(denied, VALIDATION["denied"]) == ["freealign", "sm"]
    intervals = best_against_runner_up(per_pair, VALIDATION).set_index("preset")
    assert tuple(intervals.loc["denied", ["best", "runner_up"]]) == ("freealign", "sm")
    assert intervals.loc["gnss-urban", "best"] == "pose"
    shown = compact(table, VALIDATION)
    assert not ((shown["preset"] == "denied") & (shown["matcher"] == "pose")).any()
    assert any("`denied` F1 ≥ 80" in g and "`freealign`" in g for g in goals(table, VALIDATION))


def test_the_readme_parts_say_n_a_for_a_prior_reader_under_denied(tmp_path):
    from eval.report import summary
    from eval.studies.v2x.markdown import to_markdown
    from eval.studies.v2x.report import readme_part
    from eval.studies.v2x.table import v2x_table

    table = v2x_table(_per_pair())
    table = table.assign(matcher=table["matcher"].replace({"pose": "pose_refine"}))
    write_csv(table.round(6), tmp_path / "table_v2x.csv")
    (tmp_path / "table_v2x.md").write_text(to_markdown(table, pd.DataFrame(), "X"))
    (tmp_path / "v2x").mkdir()
    planted = [
        {"preset": p, "matcher": "pose_refine" if m == "pose" else m, "val_f1": f}
        for p, scores in VALIDATION.items()
        for m, f in scores.items()
    ]
    write_csv(pd.DataFrame(planted), tmp_path / "v2x" / "validation_f1.csv")
    lines = summary.v2x(tmp_path)
    denied = next(x for x in lines if x.startswith("| denied |"))
    assert NO_NUMBER in denied and "0.0" not in denied.split("|")[-2]
    urban = next(x for x in lines if x.startswith("| gnss-urban |"))
    assert NO_NUMBER not in urban
    part = "\n".join(readme_part(tmp_path, "results"))
    assert "`denied`: chosen on validation `freealign`" in part
    assert "`gnss-urban`: chosen on validation `pose_refine`" in part


def test_a_prior_reader_under_denied_gets_no_number_in_the_multiagent_table():
    from test_multiagent_study import snapshot_row

    from eval.studies.multiagent import evaluation as ma
    from eval.studies.multiagent import report as mar

    rows = []
    for matcher in ("maximin", "pose_refine"):
        for snapshot in range(4):
            where = {"matcher": matcher, "preset": "denied"}
            declared = 0 if matcher == "pose_refine" else 10  # it declares nothing
            for fusion, tp in (("independent", 5), ("clear", 7)):
                tp = tp if declared else 0
                rows.append(
                    snapshot_row(fusion, snapshot, snapshot // 2, tp, declared, 10, **where)
                )
    table = ma.multiagent_table(pd.DataFrame(rows), resamples=200)
    assert list(table["matcher"]) == ["maximin", "maximin", "pose_refine", "pose_refine"]
    mine = table[table["matcher"] == "pose_refine"]
    figures = [c for c in ma.COLUMNS if c not in ma.BY]
    assert mine[figures].isna().all().all()
    fused = table[(table["matcher"] == "maximin") & (table["fusion"] == "clear")]
    assert (fused["gain_family"] == 1).all()  # the reader's gain is in no Holm family
    md = mar.to_markdown(table, ma.LABEL)
    assert f"| denied | 4 | pose_refine | clear | {NO_NUMBER} |" in md
