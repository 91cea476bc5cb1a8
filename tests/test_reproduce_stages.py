"""``make reproduce`` as a declared list of stages (eval/pipeline/): the walk over the
declarations, the ``--no-X`` options derived from them, ``--scale`` on every split's size, and the
committed README and report naming exactly the declared stages. Nothing is generated."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from eval import reproduce
from eval.pipeline.stage import RunState, Stage, walk
from eval.pipeline.stages import STAGES
from eval.readme_results import COLD_BEGIN, COLD_END, cold_time, stage_table, stage_table_names
from eval.report.run_record import StageTimer

ROOT = Path(__file__).resolve().parents[1]
NAMES = [stage.name for stage in STAGES]


def _leaves(tree, path=()):
    """(dotted path, value) of every number in a nested dict / list."""
    if isinstance(tree, dict):
        for key, value in tree.items():
            yield from _leaves(value, (*path, str(key)))
    elif isinstance(tree, list):
        for i, value in enumerate(tree):
            yield from _leaves(value, (*path, str(i)))
    elif isinstance(tree, int) and not isinstance(tree, bool):
        yield ".".join(path), tree


@pytest.mark.parametrize("options", [[], ["--pairs", "3", "--val-pairs", "2"]])
def test_scale_2_doubles_every_split_size_in_the_run_record(options):
    parse = reproduce.build_parser().parse_args
    one = dict(_leaves(reproduce.planned_sizes(parse(options)).record()))
    two = dict(_leaves(reproduce.planned_sizes(parse([*options, "--scale", "2"])).record()))
    assert one.pop("scale") == 1 and two.pop("scale") == 2
    for key in ("temporal.test.sequences", "multiagent.test.snapshots", "v2x.test.pairs"):
        assert key in one  # the run record's keys that other work reads
    assert "datasets.0.test_pairs" in one and "v2x.lidar.val.pairs" in one
    assert two == {key: 2 * value for key, value in one.items()}


def test_scale_1_is_the_sizes_the_options_give():
    args = reproduce.build_parser().parse_args(["--pairs", "3", "--sweep-pairs", "0"])
    sizes = reproduce.planned_sizes(args)
    assert [d[1:] for d in sizes.datasets] == [(3, 3)] * len(sizes.datasets)
    assert (
        sizes.v2x == {"test": 3, "val": 3, "train": 3}
        and sizes.lidar == {"test": 3, "val": 3}
        and sizes.temporal["test"] == 3
    )
    assert sizes.sweep is None  # 0: every test pair, at any scale
    assert sizes.data_root(Path("data")) == Path("data")
    assert replace(sizes, scale=3).data_root(Path("data")) == Path("data/scale-3")


@pytest.mark.parametrize("bad", ["0", "-1", "2.5", "two"])
def test_a_bad_scale_is_one_line_and_exit_2(bad, capsys):
    with pytest.raises(SystemExit) as stop:
        reproduce.build_parser().parse_args(["--scale", bad])
    assert stop.value.code == 2
    assert "argument --scale: expected an integer >= 1" in capsys.readouterr().err


def test_every_declared_skip_is_an_option_and_names_its_stages():
    parser = reproduce.build_parser()
    for skip in ("boxes", "lidar", "transfer", "temporal"):  # the options users already pass
        assert getattr(parser.parse_args([f"--no-{skip}"]), f"no_{skip}") is True
    helps = {a.option_strings[0]: a.help for a in parser._actions if a.option_strings}
    assert "temporal_generate and temporal" in helps["--no-temporal"]


def test_the_declarations_are_unique_and_within_the_thirty_minute_goal():
    assert len(set(NAMES)) == len(NAMES) and NAMES[-1] == "tables_figures"
    assert sum(stage.budget_s for stage in STAGES) <= 30 * 60
    assert all(stage.budget_s > 0 and stage.writes for stage in STAGES)


def _state(tmp_path, **options) -> RunState:
    args = reproduce.build_parser().parse_args(["--workers", "1", "--cache", str(tmp_path / "c")])
    for key, value in options.items():
        setattr(args, key, value)
    return RunState(args, None, tmp_path, tmp_path, [], [], [0])


def test_the_walk_runs_in_order_times_every_stage_and_honours_skips(tmp_path):
    seen = []
    (tmp_path / "old.csv").write_text("stale")

    def runs(state):
        seen.append(("runs", state.runner is not None))
        state.runner.totals.computed += 3

    quiet = {"executor": False, "counts_runs": False}
    stages = (
        Stage("first", (), ("a",), lambda s: seen.append("first"), 1, **quiet),
        Stage(
            "skipped", (), ("old.csv",), lambda s: seen.append("skipped"), 1,
            skip="temporal", stale=("old.csv",), **quiet,
        ),
        Stage("matching", (), ("b",), runs, 1),
        Stage("last", (), ("c",), lambda s: seen.append(("last", s.runner is not None)), 1, **quiet),
    )  # fmt: skip
    timer = StageTimer()
    counted = walk(stages, _state(tmp_path, no_temporal=True), timer)
    assert seen == ["first", ("runs", True), ("last", True)]
    assert list(timer.seconds) == ["first", "skipped", "matching", "last"]
    assert not (tmp_path / "old.csv").exists()  # a skipped stage leaves no earlier table behind
    assert counted["matching"]["computed"] == 3 and "last" not in counted


def test_the_committed_report_and_readme_name_the_declared_stages():
    cold = json.loads((ROOT / "results" / "cold_run.json").read_text())
    assert [k for k in cold["wall_s"] if k != "total"] == NAMES
    report = (ROOT / "results" / "README.md").read_text()
    assert stage_table_names(report) == NAMES
    assert stage_table_names("\n".join(stage_table(cold))) == NAMES
    readme = (ROOT / "README.md").read_text()
    stated = readme.split(COLD_BEGIN, 1)[1].split(COLD_END, 1)[0]
    assert stated == cold_time(ROOT / "results", ROOT)  # read from cold_run.json, not typed


def test_a_stage_counting_runs_needs_the_runner():
    with pytest.raises(ValueError, match="stage x: counts_runs needs executor"):
        Stage("x", (), (), print, 1, executor=False)


def test_a_new_stage_makes_the_committed_stage_table_stale():
    report = (ROOT / "results" / "README.md").read_text()
    assert stage_table_names(report) != [*NAMES, "lidar_temporal"]


def test_a_dashed_skip_name_is_one_option_for_its_stages():
    import argparse

    from eval.pipeline.stage import add_skip_options, skipped

    stages = [Stage(n, (), (), print, 1, skip="lidar-temporal") for n in ("gen", "table")]
    parser = argparse.ArgumentParser()
    add_skip_options(parser, stages)
    args = parser.parse_args(["--no-lidar-temporal"])
    assert all(skipped(args, s) for s in stages)
    assert not any(skipped(parser.parse_args([]), s) for s in stages)


def test_a_scaled_run_says_so_in_the_report_and_the_stated_cold_time(tmp_path):
    from eval.readme_results import report_markdown
    from eval.report.run_record import keep_cold_record

    record = {"cold_start": {"cold": True}, "scale": 2, "git": {"commit": "abcdef123"}}
    record |= {"wall_s": {"generate": 100.0, "total": 130.4}, "runs": {}, "created": "today"}
    record |= {"budget_s": {"generate": 110}}
    (tmp_path / "run_record.json").write_text(json.dumps(record))
    keep_cold_record(tmp_path, record)
    assert cold_time(tmp_path, tmp_path) == (
        "a cold `make reproduce SCALE=2` took 2 min 10 s (130 s, `./cold_run.json`, commit "
        "`abcdef1`)"
    )
    report = report_markdown(tmp_path)
    assert "every split × 2" in report and stage_table_names(report) == ["generate"]
    assert "| generate | 100 |  |  | 110 |" in report


def test_no_function_of_the_reproduce_module_or_its_stages_is_over_80_lines():
    import ast

    files = [ROOT / "eval" / "reproduce.py", *sorted((ROOT / "eval" / "pipeline").glob("*.py"))]
    long = [
        f"{path.name}:{node.name} ({node.end_lineno - node.lineno + 1} lines)"
        for path in files
        for node in ast.walk(ast.parse(path.read_text()))
        if isinstance(node, ast.FunctionDef) and node.end_lineno - node.lineno + 1 > 80
    ]
    assert long == []


def test_the_run_record_names_the_executor(monkeypatch):
    monkeypatch.delenv("CADSIM_SCHEDULER", raising=False)
    assert reproduce.executor_record(3, None) == {"kind": "local processes", "workers": 3}
    dask = reproduce.executor_record(3, "tcp://10.0.0.1:8786")
    assert dask == {"kind": "dask", "scheduler": "tcp://10.0.0.1:8786"}
    monkeypatch.setenv("CADSIM_SCHEDULER", "tcp://h:1")
    assert reproduce.executor_record(None, None)["scheduler"] == "tcp://h:1"
