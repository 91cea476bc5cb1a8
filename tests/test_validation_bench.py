"""The benchmark runner's plumbing (sections, targets); timings themselves are not tested."""

from __future__ import annotations

import pytest

from eval import bench


def test_registered_section_runs_alone_and_reports_targets(capsys):
    calls = []

    def section(args):
        calls.append(args.sizes)
        return [bench.Target("fast thing", 0.5, 1.0), bench.Target("slow thing", 2.0, 1.0)]

    bench.register(bench.Section("probe", "a test section", section))
    try:
        assert bench.main(["--only", "probe", "--sizes", "10"]) == 0
    finally:
        bench.SECTIONS[:] = [s for s in bench.SECTIONS if s.name != "probe"]
    out = capsys.readouterr().out
    assert calls == [[10]]
    assert "## probe: a test section" in out and "## tensor" not in out
    assert "PASS  fast thing: 0.5 s (target <= 1 s)" in out
    assert "FAIL  slow thing: 2 s (target <= 1 s)" in out


def test_lazy_section_imports_on_run():
    section = bench.lazy_section("house", "loader", "eval.validation.house:load_house_landmarks")
    with pytest.raises(TypeError):  # imported and called with the args namespace
        section.run(object())
    with pytest.raises(ValueError, match="package.module:function"):
        bench.lazy_section("x", "y", "no_colon")


def test_unknown_section_is_named(capsys):
    with pytest.raises(SystemExit):
        bench.main(["--only", "nope"])
    assert "nope" in capsys.readouterr().err


def test_default_sections_cover_the_issue():
    assert [s.name for s in bench.SECTIONS][:3] == ["tensor", "matchers", "targets"]
    problem = bench.bench_problem(12, 9)
    assert (problem.n1, problem.n2, problem.dim) == (12, 9, 3)
