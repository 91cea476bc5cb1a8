"""The command line a newcomer meets: a version, a top-level help with a purpose and examples,
matcher names as the tables print them, one summary line per generation, plain wording for
imported data."""

from __future__ import annotations

import pytest

from cadsim.cli import main
from eval.engine.matcher_list import parse_matchers


def test_version_and_help(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["--version"])
    assert exit_info.value.code == 0
    assert capsys.readouterr().out.startswith("cadsim ")
    with pytest.raises(SystemExit):
        main(["--help"])
    text = capsys.readouterr().out
    assert "score the\nmatchers" in text and "examples:" in text and "cadsim generate" in text
    assert "imported only when run" not in text  # no developer sentence


def test_matcher_names_are_case_insensitive_and_misspellings_get_a_suggestion():
    assert [m.name for m in parse_matchers("SM, Maximin,rrwm")] == ["sm", "maximin", "rrwm"]
    with pytest.raises(ValueError, match="did you mean maximin"):
        parse_matchers("maximn")


def test_generate_reports_once(tmp_path, capsys):
    from pathlib import Path

    scenario = Path(__file__).resolve().parents[1] / "scenarios" / "mrc-arena.toml"
    assert main(["generate", str(scenario), "--pairs", "1", "--no-progress", "--workers", "1",
                 "--out", str(tmp_path / "d")]) == 0  # fmt: skip
    captured = capsys.readouterr()
    assert (captured.out + captured.err).count("checksum") == 1


def test_info_on_imported_data_says_so(capsys):
    from pathlib import Path

    data = Path(__file__).resolve().parents[1] / "eval" / "data" / "dmgm-cad" / "test-069-071"
    assert main(["info", str(data)]) == 0
    out = capsys.readouterr().out
    assert "imported (no seed)" in out and "seed None" not in out and "- m" not in out


def test_every_matcher_has_its_own_colour_and_marker():
    from eval.report.palette import BUILTIN, styles
    from matchers import available

    found = styles([*available(), "my_matcher", "another"])
    assert set(available()) <= set(BUILTIN)
    assert len({s.color for s in found.values()}) == len(found)  # no two share a colour
    assert len({s.marker for s in BUILTIN.values()}) == len(BUILTIN)


def test_a_users_scenario_keeps_its_name_and_gets_no_paper_columns():
    import pandas as pd

    from eval.engine.splits import dataset_label
    from eval.report.tables import to_markdown

    assert dataset_label("my-busy-3lane") == "my-busy-3lane"
    assert (dataset_label("cad-intersection"), dataset_label("mrc-arena")) == ("CAD", "MRC")
    assert dataset_label("dmgm-cad") == "DMGM"
    from pathlib import Path

    table = pd.read_csv(Path(__file__).resolve().parents[1] / "results" / "table1.csv")
    cad = table[table["dataset"] == "CAD"]
    assert "Accuracy (paper)" in to_markdown(cad)
    mine = cad.assign(dataset="my-busy-3lane", runs=1)
    text = to_markdown(mine)
    assert "(paper)" not in text and "× 1 run;" in text and "**my-busy-3lane**" in text


def _parsers() -> dict:
    import argparse

    from cadsim import cli

    parser = cli.build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name in cli.COMMANDS:
        cli._load(name).add_arguments(sub.choices[name])
    return sub.choices


def _every_parser() -> dict:
    """Every subcommand's parser, nested ones (``import dmgm``) included, by "cmd sub" name."""
    import argparse

    found = {}

    def walk(name, parser):
        found[name] = parser
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for sub_name, sub in action.choices.items():
                    walk(f"{name} {sub_name}", sub)

    for name, parser in _parsers().items():
        walk(name, parser)
    return found


def test_every_help_has_a_purpose_and_examples_that_parse():
    import shlex

    parsers = _every_parser()
    for name, parser in parsers.items():
        if name == "import":  # a group: its formats carry the examples
            continue
        assert parser.description and parser.description.strip(), name
        assert parser.epilog and parser.epilog.startswith("examples:"), name
        for line in parser.epilog.splitlines()[1:]:
            argv = shlex.split(line.split(" > ")[0].strip())  # a shell redirection is no argument
            assert argv[0] == "cadsim", line
            words = argv[1:]
            depth = len(name.split())
            assert " ".join(words[:depth]) == name, line
            parser.parse_args(words[depth:])  # SystemExit (usage error) fails the test


def test_the_same_flag_means_the_same_on_every_subcommand():
    for name, parser in _every_parser().items():
        strings = {o for a in parser._actions for o in a.option_strings}
        primary = {a.option_strings[0] for a in parser._actions if a.option_strings}
        assert "--jobs" not in primary, name  # workers are --workers everywhere
        assert "--quiet" not in strings, name  # --no-progress is the one spelling
        if "--matchers" in strings or "--runs" in strings and name != "synthetic":
            assert "--workers" in strings, name
        if name in ("evaluate", "sweep-noise", "sweep-regime", "sweep-localisation"):
            assert {"--out", "--cache", "--workers", "--no-progress", "--val"} <= strings, name
            out = next(a for a in parser._actions if "--out" in a.option_strings)
            assert out.required, name  # never a default that overwrites results/


def test_synthetic_takes_matchers_comma_separated_too():
    from eval.validation import synthetic

    parser = _parsers()["synthetic"]
    args = parser.parse_args(["--matchers", "TM,rrwhm", "bcagm", "--workers", "1"])
    assert args.jobs == 1
    assert synthetic.matcher_names(args.matchers) == ["tm", "rrwhm", "bcagm"]
