"""``python -m eval.reproduce`` checks every option before it creates anything: a bad one is one
line on stderr (``python -m eval.reproduce: error: …``), exit status 2, no traceback, and the
working folder (``--out``, ``--data``, ``--cache`` included) exactly as it was."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from eval import reproduce

ROOT = Path(__file__).resolve().parents[1]
DATASET = ROOT / "eval" / "data" / "dmgm-cad" / "val-070"


def _tree(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    """A working folder holding one file; the stages must never be reached."""
    (tmp_path / "afile").write_text("mine\n")
    monkeypatch.chdir(tmp_path)

    def reached(*args, **kwargs):
        raise AssertionError("the stages started: an option was not checked first")

    monkeypatch.setattr(reproduce, "walk", reached)
    return tmp_path


CASES = [
    (["--matchers", "nope"], "--matchers: unknown ['nope']"),
    (["--matchers", "no_such_module_58:fn"], "ModuleNotFoundError"),
    (["--matchers", "json:no_such_function"], "has no 'no_such_function'"),
    (["--rates", "x"], "--rates"),
    (["--rates", "0,nan"], "--rates"),
    (["--keep", "2"], "--keep"),
    (["--localisation-sigmas", "-1"], "--localisation-sigmas"),
    (["--pairs", "0"], "--pairs: expected an integer in 1..100000, got 0"),
    (["--val-pairs", "-2"], "--val-pairs"),
    (["--workers", "0"], "--workers: expected an integer in 1..1024, got 0"),
    (["--out="], "--out: expected a folder path, got an empty one"),
    (["--out", "afile"], "afile: exists and is not a folder"),
    (["--out", str(DATASET / "inside")], "is inside the cadsim dataset"),
    (["--data", "afile"], "--data afile: exists and is not a folder"),
    (["--cache="], "--cache"),
    (["--scenarios", "missing.toml"], "--scenarios missing.toml: no such scenario file"),
    (["--scale", "1000000000"], "--scale 1000000000: a split of"),
    (["--scale", "0"], "argument --scale: expected an integer >= 1"),
    (["--runs", "0"], "--runs: expected an integer in 1..1000, got 0"),
    (["--runs", "-3"], "--runs: expected an integer in 1..1000, got -3"),
    (["--v2x-runs", "-1"], "--v2x-runs: expected an integer in 0..1000, got -1"),
    (["--sweep-runs", "0"], "--sweep-runs: expected an integer in 1..1000, got 0"),
    (["--regime-pairs", "-1"], "--regime-pairs"),
    (["--pairs", "two"], "argument --pairs: invalid int value"),
]


@pytest.mark.parametrize("argv, expected", [c for c in CASES if c[1]], ids=lambda v: str(v))
def test_a_bad_option_is_one_line_exit_2_and_creates_nothing(workdir, capsys, argv, expected):
    before = _tree(workdir)
    try:
        status = reproduce.main([*argv, "--no-progress"])
    except SystemExit as stop:  # argparse's own refusals
        status = stop.code
    assert status == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("python -m eval.reproduce: error: "), err
    assert expected in err[0], err[0]
    assert "Traceback" not in err[0]
    assert _tree(workdir) == before


def test_the_module_entry_point_gives_the_same_line(tmp_path):
    done = subprocess.run(
        [sys.executable, "-m", "eval.reproduce", "--runs", "-3", "--out", str(tmp_path / "o")],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip() == (
        "python -m eval.reproduce: error: --runs: expected an integer in 1..1000, got -3"
    )
    assert not (tmp_path / "o").exists()
