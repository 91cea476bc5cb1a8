"""The cold-run budget per added table (eval/claims/budget.py): each table's stages summed from
the last cold run against its share — the paper's part 600 s, each added table with its sweep
240 s (a study of several tables also stated whole), the whole run 1,800 s — stated as point
measurements, in claims.csv and under the report's stage times."""

from __future__ import annotations

import json

from eval.claims import build_claims
from eval.claims.budget import budget_claims, budget_parts
from eval.report.run_part import run_part
from eval.studies import study


def _record(**wall) -> dict:
    return {"wall_s": wall, "git": {"commit": "abc"}, "cold_start": {"cold": True}}


def test_each_added_table_sums_its_own_stages_and_a_study_of_several_is_stated_whole():
    v2x = [s.name for s in study("v2x").stages]
    wall = {name: 100.0 for name in v2x} | {"evaluate": 50.0, "external": 20.0}
    wall |= {"tables_figures": 5.0, "multiagent": 30.0, "total": 1000.0}
    parts = {what: (seconds, bar) for what, seconds, bar in budget_parts(_record(**wall))}
    assert parts["the V2X camera table and its preset sweep"] == (300.0, 240.0)
    assert parts["the V2X box-only table"] == parts["the V2X LiDAR table"] == (100.0, 240.0)
    assert parts["the V2X study as a whole (3 tables, 240 s each)"] == (500.0, 720.0)
    assert parts["the paper's part (Table I, Fig. 4, the sweeps, the external benchmark)"] == (
        75.0,
        600.0,
    )  # Table I's stages, its closing figures and the external benchmark
    assert parts["the multi-agent study"] == (30.0, 240.0)
    assert parts["the whole `make reproduce`"] == (1000.0, 1800.0)
    assert not any("temporal" in what for what in parts)  # none of its stages ran
    assert not any("multi-agent study as a whole" in what for what in parts)  # one table


def test_every_study_s_budget_units_cover_its_stages_once():
    from eval.studies import studies

    for s in studies():
        if not s.budget_units:
            continue
        named = [n for _, names in s.budget_units for n in names]
        assert sorted(named) == sorted(x.name for x in (*s.stages, *s.closing_stages)), s.name


def test_the_claims_say_how_far_within_or_past_and_give_no_verdict(tmp_path):
    assert budget_claims(tmp_path) == []  # no cold run: nothing claimed
    wall = {"temporal": 300.0, "transfer": 60.0, "total": 360.0}
    (tmp_path / "cold_run.json").write_text(json.dumps(_record(**wall)))
    claims = {c.subject: c for c in budget_claims(tmp_path)}
    temporal = claims["the temporal camera table, cold"]
    assert temporal.value == 300.0 and temporal.bar == 240.0
    assert "60 s past the budget" in temporal.statement
    assert "180 s inside the budget" in claims["the transfer study, cold"].statement
    assert {c.verdict for c in claims.values()} == {"point measurement"}
    assert set(build_claims(tmp_path)["subject"]) >= set(claims)  # in claims.csv
    part = "\n".join(run_part(tmp_path, _record(**wall)))
    assert temporal.statement in part  # and under the report's stage times
