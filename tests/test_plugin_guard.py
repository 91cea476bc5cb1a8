"""Issue 40: a plug-in matcher or fusion (register(), an entry point, an import path) that raises,
returns the wrong thing or never returns ends in one line naming it — never a traceback, a hang,
or NaN in a table — and one broken entry point does not break ``all``. The plug-ins are in
tests/plugin_fakes.py, one way of breaking the contract each.

Every test here fails with the checks removed: the harness would accept the result (NaN scores,
a negative time), raise something else (a traceback), or wait forever (the hang tests carry a
timeout of their own, so that they fail rather than hang)."""

from __future__ import annotations

import logging
import sys
import textwrap

import numpy as np
import pytest
from frame_pair_fakes import make_dataset

import matchers
from cadsim.cli import main
from eval.core import tasks
from eval.core.cache import ResultCache
from eval.core.executor import SerialExecutor
from eval.core.runner import RunFailed, Runner, requests_for
from eval.core.tasks import MatcherSpec
from eval.engine.matcher_list import parse_matchers
from matchers import PluginError, PluginTimeout, Problem, get
from matchers.core import named_lookup, registry
from matchers.core.plugin_guard import TIME_LIMIT_ENV, check_matching, time_limit_s
from matchers.fusion import PairwiseEvidence, checked_fusion, get_fusion, usable_fusions
from matchers.fusion import registry as fusion_registry
from matchers.fusion.checks import check_universe

LIMIT = 0.5  # seconds: the time limit of the hang tests
DATA = "data/plugin-fake"


@pytest.fixture
def runner(tmp_path, monkeypatch):
    dataset = make_dataset(100, 2)
    monkeypatch.setattr(tasks, "open_dataset", lambda path: dataset)
    return Runner(
        ResultCache(tmp_path / "cache"),
        SerialExecutor(),
        version="v",
        progress=False,
        plugin_time_limit_s=LIMIT,
    )


def _run(runner, name: str):
    requests = requests_for([(DATA, "sum-cad-fake-100")], [MatcherSpec(name)], [0])
    return runner.run(requests)


def _failure(runner, name: str) -> PluginError:
    with pytest.raises(RunFailed) as failed:
        _run(runner, name)
    assert failed.value.user_error  # the CLI prints one line, exit status 2
    (error,) = failed.value.errors
    assert isinstance(error, PluginError)
    assert f"matcher {name!r}" in str(error)
    assert "frame pair e00000_s00" in str(error)  # where it happened
    assert "\n" not in str(error)
    return error


# --- matchers: each family through the runner (eval.core.tasks._pair_outcomes) ---


@pytest.mark.parametrize(
    "name, words",
    [
        ("raises", "raised ZeroDivisionError: division by zero"),
        ("none", "returned None, expected a matchers.Matching"),
        ("a_tuple", "(a tuple), expected a matchers.Matching"),
        ("flat_pairs", "pairs of shape (4,), expected (k, 2)"),
        ("float_pairs", "pairs of dtype float64, expected integers"),
        ("scores_of_another_shape", "scores of shape (11, 9), expected (10, 9)"),
        ("flat_scores", "scores of shape (90,), expected (10, 9)"),
        ("pair_outside", "pairs with (10, 1) at row 1, outside the views' 10 x 9 objects"),
        ("negative_index", "pairs with (0, -1) at row 0, outside"),
        ("repeated_i", "pairs that match i = 0 2 times, expected one-to-one pairs"),
        ("repeated_j", "pairs that match j = 1 2 times, expected one-to-one pairs"),
        ("nan_scores", "scores with 1 NaN and 0 infinite values (the first at (1, 2))"),
        ("inf_scores", "scores with 0 NaN and 1 infinite values (the first at (0, 0))"),
        ("scores_above_one", "scores in [1.5, 1.5], expected values in [0, 1]"),
        ("negative_time", "time_s -1.0 (a float), expected a finite number ≥ 0"),
        ("nan_time", "time_s nan (a float), expected a finite number ≥ 0"),
        ("no_iterations", "iterations None, expected a non-negative integer"),
    ],
)
def test_a_plugin_matcher_that_breaks_its_contract_is_named_in_one_line(runner, name, words):
    error = _failure(runner, f"plugin_fakes:{name}")
    assert words in str(error)
    assert not isinstance(error, PluginTimeout)


@pytest.mark.timeout(60)
@pytest.mark.parametrize("name", ["sleeps_forever", "spins_forever"])
def test_a_plugin_matcher_that_never_returns_meets_the_time_limit(runner, name):
    error = _failure(runner, f"plugin_fakes:{name}")
    assert isinstance(error, PluginTimeout)
    assert f"time limit of {LIMIT:g} s per problem" in str(error)
    assert TIME_LIMIT_ENV in str(error)


def test_a_good_plugin_runs_and_its_result_is_used_as_returned(runner):
    (run,) = _run(runner, "plugin_fakes:good")
    assert len(run.outcomes) == 2
    for outcome in run.outcomes:
        assert np.all(outcome.scores == 0.5) and outcome.time_s == 1e-3
    problem = Problem(np.zeros((3, 2)), np.zeros((4, 2)))
    guarded = registry.checked("plugin_fakes:good", time_limit_s=LIMIT)
    assert guarded is not get("plugin_fakes:good")  # a plug-in goes through the guard
    import plugin_fakes

    result = guarded(problem)
    reference = plugin_fakes.good(problem)
    np.testing.assert_array_equal(result.pairs, reference.pairs)
    np.testing.assert_array_equal(result.scores, reference.scores)


def test_builtins_are_not_wrapped_so_their_results_stay_bit_identical():
    for name in registry._BUILTIN:
        assert registry.checked(name) is get(name), name
    assert registry.checked("matchers.rrwm:rrwm") is get("rrwm")  # a built-in by import path
    for name in fusion_registry._BUILTIN:
        assert checked_fusion(name) is get_fusion(name), name


def test_every_builtin_keeps_the_contract_the_plugins_are_held_to():
    # the checks describe the contract the built-ins honour: none of them would fail it
    from learned_fixture import needed_options, synthetic_pair

    problem, _ = synthetic_pair(np.random.default_rng(5))
    for name in registry._BUILTIN:
        result = get(name)(problem, seed=0, **needed_options(name))
        check_matching(name, result, problem.n1, problem.n2)
    evidence = _evidence()
    for name in fusion_registry._BUILTIN:
        check_universe(name, get_fusion(name)(evidence), evidence)


def test_the_time_limit_comes_from_the_environment_and_is_checked(monkeypatch, tmp_path):
    monkeypatch.delenv(TIME_LIMIT_ENV, raising=False)
    assert time_limit_s() == 600.0
    monkeypatch.setenv(TIME_LIMIT_ENV, "2.5")
    assert time_limit_s() == 2.5
    assert Runner(ResultCache(tmp_path), SerialExecutor(), version="v").plugin_time_limit_s == 2.5
    for bad in ("0", "-1", "nan", "inf", "soon"):
        monkeypatch.setenv(TIME_LIMIT_ENV, bad)
        with pytest.raises(ValueError, match=f"\\${TIME_LIMIT_ENV}: expected a number of seconds"):
            time_limit_s()


# --- the command line: one line, exit status 2, with the local pool as with one process ---


@pytest.fixture(scope="module")
def fake_dataset(tmp_path_factory):
    from test_generate_fakes import FAKE_STAGES, FakeScenario

    from cadsim.generation.pipeline import generate_dataset

    out = tmp_path_factory.mktemp("plugins") / "ds"
    generate_dataset(FakeScenario(), out, pairs=2, workers=1, stages=FAKE_STAGES, progress=False)
    return out


def _evaluate(dataset, tmp_path, matcher: str, *extra: str) -> list[str]:
    argv = ["evaluate", str(dataset), "--no-calibration", "--matchers", matcher, "--runs", "1"]
    argv += ["--out", str(tmp_path / "r"), "--cache", str(tmp_path / "c"), "--no-progress"]
    return argv + list(extra)


def _one_error_line(capsys) -> str:
    lines = [line for line in capsys.readouterr().err.strip().splitlines() if line]
    assert lines[-1].startswith("cadsim evaluate: error: "), lines
    assert not any("Traceback" in line for line in lines), lines
    return lines[-1]


def test_cadsim_evaluate_names_a_plugin_with_nan_scores_in_one_line(fake_dataset, tmp_path, capsys):
    argv = _evaluate(fake_dataset, tmp_path, "plugin_fakes:nan_scores", "--workers", "1")
    assert main(argv) == 2
    line = _one_error_line(capsys)
    assert "matcher 'plugin_fakes:nan_scores' returned scores with 1 NaN" in line


@pytest.mark.timeout(120)
def test_cadsim_evaluate_stops_a_hanging_plugin_in_pool_workers(fake_dataset, tmp_path, capsys):
    argv = _evaluate(fake_dataset, tmp_path, "sm,plugin_fakes:sleeps_forever", "--workers", "2")
    assert main([*argv, "--plugin-time-limit", str(LIMIT)]) == 2
    line = _one_error_line(capsys)
    assert "matcher 'plugin_fakes:sleeps_forever' did not return within the time limit" in line


@pytest.mark.timeout(180)
def test_the_time_limit_holds_on_dask_worker_threads_too(fake_dataset, tmp_path):
    # a Dask worker runs tasks on its own threads (no SIGALRM there); the limit is the
    # coordinator's, carried in the task, not the worker's environment
    distributed = pytest.importorskip("distributed")
    from cadsim.dataset import Dataset
    from cadsim.generation.dask_executor import DaskExecutor

    checksum = Dataset(fake_dataset).checksum
    specs = [MatcherSpec("sm"), MatcherSpec("plugin_fakes:sleeps_forever")]
    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        DaskExecutor(cluster.scheduler_address) as executor,
    ):
        runner = Runner(
            ResultCache(tmp_path / "c"), executor, progress=False, plugin_time_limit_s=LIMIT
        )
        with pytest.raises(RunFailed) as failed:
            runner.run(requests_for([(str(fake_dataset), checksum)], specs, [0]))
    assert failed.value.user_error
    assert all(isinstance(e, PluginTimeout) for e in failed.value.errors)
    assert "plugin_fakes:sleeps_forever' did not return within the time limit of 0.5 s" in str(
        failed.value
    )


def test_plugin_time_limit_is_a_positive_number(fake_dataset, tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main([*_evaluate(fake_dataset, tmp_path, "sm"), "--plugin-time-limit", "0"])
    assert exit_info.value.code == 2
    assert "--plugin-time-limit" in capsys.readouterr().err


# --- broken entry points: left out of `all` with a warning, one line when named ---


@pytest.fixture
def broken_entry_points(tmp_path, monkeypatch):
    """An installed distribution declaring a good matcher, one whose module does not import and
    one that is not callable — and the same three fusions."""
    (tmp_path / "broken_plugin.py").write_text("raise ImportError('a dependency is missing')\n")
    dist = tmp_path / "hostile_plugins-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: hostile-plugins\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text(
        textwrap.dedent(
            f"""
            [{matchers.ENTRY_POINT_GROUP}]
            fine = plugin_fakes:good
            unimportable = broken_plugin:matcher
            not_callable = plugin_fakes:NOT_CALLABLE
            [{fusion_registry.ENTRY_POINT_GROUP}]
            fine_fusion = plugin_fakes:fusion_good
            unimportable_fusion = broken_plugin:fusion
            not_callable_fusion = plugin_fakes:NOT_CALLABLE
            """
        )
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(registry, "_registered", {})
    monkeypatch.setattr(fusion_registry, "_registered", {})
    monkeypatch.setattr(named_lookup, "_warned", set())
    registry._entry_points.cache_clear()
    fusion_registry._entry_points.cache_clear()
    yield
    registry._entry_points.cache_clear()
    fusion_registry._entry_points.cache_clear()
    sys.modules.pop("broken_plugin", None)


def test_a_broken_entry_point_is_left_out_of_all_with_a_warning(broken_entry_points, caplog):
    with caplog.at_level(logging.WARNING):
        names = [spec.name for spec in parse_matchers("all")]
    assert "fine" in names and {"sm", "maximin", "rrwhm"} <= set(names)
    assert "unimportable" not in names and "not_callable" not in names
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert any(
        "matcher 'unimportable': entry point 'broken_plugin:matcher' cannot be loaded "
        "(ImportError: a dependency is missing); left out of 'all'" in w
        for w in warnings
    ), warnings
    assert any("matcher 'not_callable'" in w and "is not callable (a int)" in w for w in warnings)
    assert "unimportable" in matchers.available()  # still listed: available() imports nothing
    with caplog.at_level(logging.WARNING):
        caplog.clear()
        parse_matchers("all")
    assert not caplog.records  # reported once per process


def test_a_broken_entry_point_asked_for_by_name_is_one_line(
    broken_entry_points, fake_dataset, tmp_path, capsys
):
    with pytest.raises(PluginError, match="entry point 'broken_plugin:matcher' cannot be loaded"):
        parse_matchers("sm,unimportable")
    with pytest.raises(PluginError, match="is not callable"):
        get("not_callable")
    argv = _evaluate(fake_dataset, tmp_path, "unimportable", "--workers", "1")
    assert main(argv) == 2
    line = _one_error_line(capsys)
    assert "matcher 'unimportable': entry point 'broken_plugin:matcher' cannot be loaded" in line


def test_a_broken_fusion_entry_point_is_left_out_and_named(broken_entry_points, caplog):
    with caplog.at_level(logging.WARNING):
        names = usable_fusions()
    assert {"independent", "spectral", "clear", "transitive", "fine_fusion"} <= set(names)
    assert "unimportable_fusion" not in names and "not_callable_fusion" not in names
    assert any("fusion 'unimportable_fusion'" in r.getMessage() for r in caplog.records)
    with pytest.raises(PluginError, match="fusion 'not_callable_fusion'.*is not callable"):
        get_fusion("not_callable_fusion")
    universe = checked_fusion("fine_fusion", time_limit_s=LIMIT)(_evidence())
    assert universe.count == 4


# --- fusions: each family through the multi-agent study's call (eval.studies.multiagent.evaluation) ---


def _evidence() -> PairwiseEvidence:
    """Three views of the same 4 objects, every pair of views matched exactly."""
    right = np.array([[0, 0], [1, 1], [2, 2], [3, 3]])
    scores = {key: np.eye(4) * 0.9 for key in ((0, 1), (0, 2), (1, 2))}
    return PairwiseEvidence((4, 4, 4), scores, dict.fromkeys(scores, right))


def _fuse(name: str):
    """What the multi-agent study runs for a plug-in fusion, on :func:`_evidence`."""
    return checked_fusion(f"plugin_fakes:{name}", time_limit_s=LIMIT)(_evidence())


@pytest.mark.parametrize(
    "name, words",
    [
        ("fusion_raises", "raised KeyError: 'no such view'"),
        ("fusion_none", "returned None, expected a matchers.fusion.Universe"),
        ("fusion_too_few_views", "expected one array per view (3 views)"),
        ("fusion_labels_of_another_shape", "labels of view 0 of shape (3,), expected (4,)"),
        ("fusion_label_outside", "returned labels in [0, 7] with count 4"),
        ("fusion_wrong_count", "returned count 7 but its labels name 4 objects"),
        ("fusion_two_in_one_view", "object 0 holding 2 detections of view 0"),
        ("fusion_pair_outside", "pairs (0, 1) with (4, 0) at row 0, outside the views' 4 x 4"),
        ("fusion_repeated_pairs", "pairs (0, 1) that match i = 0 2 times"),
        ("fusion_bad_key", "pairs keyed (1, 0) (a tuple), expected views (i, j)"),
        ("fusion_inconsistent", "3 fused pairs (0, 1) where its labels imply 4"),
        ("fusion_nan_time", "time_s nan (a float), expected a finite number ≥ 0"),
        ("fusion_negative_time", "time_s -0.5 (a float), expected a finite number ≥ 0"),
    ],
)
def test_a_plugin_fusion_that_breaks_its_contract_is_named_in_one_line(name, words):
    with pytest.raises(PluginError) as error:
        _fuse(name)
    assert f"fusion 'plugin_fakes:{name}'" in str(error.value) and words in str(error.value)
    assert "\n" not in str(error.value)


@pytest.mark.timeout(60)
def test_a_plugin_fusion_that_never_returns_meets_the_time_limit():
    with pytest.raises(PluginTimeout, match="fusion 'plugin_fakes:fusion_sleeps_forever' did not"):
        _fuse("fusion_sleeps_forever")


def test_the_study_runs_plugin_fusions_through_the_guard_and_says_where():
    from eval.core.tasks import PairOutcome
    from eval.studies.multiagent import evaluation as multiagent

    def outcome(n1, n2):
        pairs = np.stack([np.arange(min(n1, n2))] * 2, axis=1)
        scores = np.full((n1, n2), 0.1)
        scores[pairs[:, 0], pairs[:, 1]] = 0.9
        return PairOutcome(0, "e00000_s00", 0, 1, "x", n1, n2, pairs, pairs, scores, 0.0, 0)

    outcomes = {(1, 2): [outcome(3, 3)], (1, 5): [outcome(3, 3)], (2, 5): [outcome(3, 3)]}
    rows = multiagent._fused_rows(
        outcomes, (1, 2, 5), 0.5, ["transitive", "plugin_fakes:fusion_good"]
    )
    assert [r["fusion"] for r in rows] == ["transitive", "plugin_fakes:fusion_good"]
    with pytest.raises(PluginError, match=r"fusion_nan_time' returned time_s nan.*\(snapshot 0"):
        multiagent._fused_rows(outcomes, (1, 2, 5), 0.5, ["plugin_fakes:fusion_nan_time"])
    good = checked_fusion("plugin_fakes:fusion_from_labels")(_evidence())
    assert good.count == 12 and good.fused
