"""``python -m eval.studies.<study>``: every study has one, with --help; a study that reads
another study's results says which to run first, in one line, exit 2, before anything runs."""

from __future__ import annotations

import subprocess
import sys

import pytest

from eval.run_study import run_study
from eval.studies import STUDIES, study


@pytest.mark.parametrize("name", STUDIES)
def test_every_study_runs_alone_with_help(name, capsys):
    with pytest.raises(SystemExit) as stopped:
        run_study(name, ["--help"])
    assert stopped.value.code == 0
    text = " ".join(capsys.readouterr().out.split())  # argparse wraps the description
    assert f"python -m eval.studies.{name}" in text and study(name).label in text
    assert "--out" in text and "--cache" in text
    for first in study(name).needs:
        assert f"python -m eval.studies.{first}" in text


@pytest.mark.parametrize("name", [n for n in STUDIES if any(study(n).needs.values())])
def test_a_study_without_what_it_reads_names_the_study_to_run_first(name, tmp_path, capsys):
    code = run_study(name, ["--out", str(tmp_path / "out"), "--data", str(tmp_path / "data")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err
    assert "tuning.csv missing" in err and "run `python -m eval.studies.table1" in err
    assert not (tmp_path / "data").exists()  # nothing generated


def test_the_module_entry_point_works():
    out = subprocess.run(
        [sys.executable, "-m", "eval.studies.v2x", "--help"], capture_output=True, text=True
    )
    text = " ".join(out.stdout.split())
    assert out.returncode == 0 and "run that first" in text, out.stderr[-2000:]
