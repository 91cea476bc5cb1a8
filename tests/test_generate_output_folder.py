"""``generate`` writes only into a new, empty or cadsim dataset folder: a user's folder is refused
in one line and nothing in it is deleted or changed; symbolic links are refused, never followed."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from cadsim.cli import main
from cadsim.dataset.output_folder import OutputFolderError, check_output_folder

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = str(ROOT / "scenarios" / "mrc-arena.toml")


def _snapshot(folder: Path) -> dict[str, bytes | None]:
    """Every path under `folder` (links not followed) with its bytes (None for folders/links)."""
    out = {}
    for path in sorted(folder.rglob("*")):
        rel = str(path.relative_to(folder))
        out[rel] = path.read_bytes() if path.is_file() and not path.is_symlink() else None
    return out


def _users_folder(tmp_path: Path) -> Path:
    """The issue's folder: cadsim's names, but not cadsim's content."""
    v = tmp_path / "v"
    (v / ".work").mkdir(parents=True)
    (v / ".work" / "x").write_text("my notes")
    (v / "episodes").mkdir()
    (v / "manifest.json").write_text("{}")
    (v / ".tmp-notes").write_text("keep me")
    return v


def test_generate_refuses_a_folder_that_is_not_a_dataset_and_deletes_nothing(tmp_path, capsys):
    v = _users_folder(tmp_path)
    before = _snapshot(v)
    assert main(["generate", SCENARIO, "--pairs", "1", "--out", str(v)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and str(v) in err
    assert _snapshot(v) == before


@pytest.mark.parametrize("out", ["", "   "])
def test_an_empty_out_is_refused(out, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["generate", SCENARIO, "--pairs", "1", "--out", out]) == 2
    assert "--out" in capsys.readouterr().err and not list(tmp_path.iterdir())


def test_what_is_refused_is_named(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "thesis.tex").write_text("x")
    with pytest.raises(OutputFolderError, match="thesis.tex"):
        check_output_folder(tmp_path / "a")
    (tmp_path / "f").write_text("x")
    with pytest.raises(OutputFolderError, match="not a folder"):
        check_output_folder(tmp_path / "f")
    (tmp_path / "b" / "pairs" / "e00000_s00").mkdir(parents=True)
    (tmp_path / "b" / "pairs" / "holiday.jpg").write_text("x")
    with pytest.raises(OutputFolderError, match="holiday.jpg"):
        check_output_folder(tmp_path / "b")
    (tmp_path / "c").mkdir()
    (tmp_path / "c" / "manifest.json").write_text(json.dumps({"format": "other"}))
    with pytest.raises(OutputFolderError, match="not a cadsim manifest"):
        check_output_folder(tmp_path / "c")


@pytest.mark.parametrize("link", ["pairs", "episodes", ".work", "pairs/e00000_s00"])
def test_symbolic_links_inside_out_are_refused_not_followed(tmp_path, link):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "precious.txt").write_text("x")
    out = tmp_path / "out"
    (out / Path(link).parent).mkdir(parents=True, exist_ok=True)
    os.symlink(elsewhere, out / link)
    with pytest.raises(OutputFolderError, match="symbolic link"):
        check_output_folder(out)
    assert main(["generate", SCENARIO, "--pairs", "1", "--out", str(out)]) == 2
    assert (elsewhere / "precious.txt").read_text() == "x" and len(list(elsewhere.iterdir())) == 1


def test_out_itself_a_link_is_refused(tmp_path):
    (tmp_path / "real").mkdir()
    os.symlink(tmp_path / "real", tmp_path / "link")
    with pytest.raises(OutputFolderError, match="symbolic link"):
        check_output_folder(tmp_path / "link")


def test_new_empty_and_dataset_folders_are_accepted(tmp_path):
    assert check_output_folder(tmp_path / "new") == tmp_path / "new"
    (tmp_path / "empty").mkdir()
    assert check_output_folder(tmp_path / "empty") == tmp_path / "empty"
    out = tmp_path / "data"
    assert main(["generate", SCENARIO, "--pairs", "1", "--out", str(out), "--workers", "1"]) == 0
    (out / ".tmp-e00000_s05-123-0123abcd").mkdir()  # a record an interrupted run left behind
    assert check_output_folder(out) == out  # a dataset, resumable
