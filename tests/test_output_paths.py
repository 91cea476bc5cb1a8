"""Issue 40: one output-path rule for every ``--out`` of every command
(``cadsim.dataset.output_folder``). Never over an existing dataset, result folder or file the
command did not write, never into a dataset, never through a symbolic link; atomic (a new
temporary name in the same folder opened with ``O_EXCL``, renamed at the end, removed on
failure). Each refusal is one line and exit status 2, and changes no file of the user's."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import uuid
from pathlib import Path

import pytest
from learned_fixture import model_path

from cadsim.cli import main
from cadsim.dataset import atomic_writer
from cadsim.dataset.atomic_writer import OutputPathError, write_file_atomic
from cadsim.dataset.output_folder import (
    check_cache_folder,
    check_output_file,
    check_result_folder,
    file_holds,
)

REPO = Path(__file__).resolve().parents[1]
DMGM = REPO / "eval" / "data" / "dmgm-cad"


def _tree_state(folder: Path) -> dict[str, str | None]:
    """Every path under ``folder`` (links not followed) with its sha256 (None: folder/link)."""
    state = {}
    for path in sorted(folder.rglob("*")):
        plain = path.is_file() and not path.is_symlink()
        digest = hashlib.sha256(path.read_bytes()).hexdigest() if plain else None
        state[str(path.relative_to(folder))] = digest
    return state


@pytest.fixture
def other(tmp_path) -> Path:
    """Another dataset of the user's (a copy of the shipped DMGM validation split)."""
    copy = tmp_path / "other"
    shutil.copytree(DMGM / "val-070", copy)
    return copy


def _one_line(capsys, command: str) -> str:
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"cadsim {command}: error: "), lines
    return lines[0]


def _train(out: Path | str) -> int:
    args = ["train", str(DMGM / "test-069-071"), "--variants", "learned", "--rounds", "2"]
    return main([*args, "--no-progress", "--out", str(out)])


def test_train_never_overwrites_another_datasets_manifest(other, tmp_path, capsys):
    before = _tree_state(other)
    assert _train(other / "manifest.json") == 2
    line = _one_line(capsys, "train")
    assert str(other / "manifest.json") in line and "inside the cadsim dataset" in line
    assert _tree_state(other) == before  # the manifest byte for byte, nothing added
    assert _train(other / "model.json") == 2  # a new name inside a dataset neither
    assert "inside the cadsim dataset" in _one_line(capsys, "train")
    assert _train(other / "pairs" / "model.json") == 2
    assert _tree_state(other) == before


def test_train_into_a_folder_leaves_nothing_behind(tmp_path, capsys):
    folder = tmp_path / "models"
    folder.mkdir()
    assert _train(folder) == 2
    assert "is a folder" in _one_line(capsys, "train")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["models"] and not any(folder.iterdir())


def test_train_never_writes_through_or_over_a_users_file(tmp_path, capsys):
    victim = tmp_path / "thesis.tex"
    victim.write_text("precious")
    link = tmp_path / "model.json"
    link.symlink_to(victim)
    assert _train(link) == 2
    assert "symbolic link" in _one_line(capsys, "train")
    assert link.is_symlink() and victim.read_text() == "precious"
    assert _train(victim) == 2
    assert "not a cadsim model file" in _one_line(capsys, "train")
    assert victim.read_text() == "precious"
    assert _train("") == 2 and "--out" in _one_line(capsys, "train")


def test_a_link_at_the_temporary_name_is_never_opened(tmp_path, monkeypatch):
    """The old ``MODEL.partial`` name was predictable; a link planted at the temporary name must
    not be written through. The random part is forced to collide once."""
    victim = tmp_path / "victim"
    victim.write_text("precious")
    target = tmp_path / "m.json"
    names = iter([uuid.UUID(int=0xABCDEF01 << 96), uuid.UUID(int=0x12345678 << 96)])
    monkeypatch.setattr(atomic_writer.uuid, "uuid4", lambda: next(names))
    planted = tmp_path / f".tmp-m.json-{os.getpid()}-abcdef01"
    planted.symlink_to(victim)
    write_file_atomic(target, b"model bytes")
    assert target.read_bytes() == b"model bytes" and victim.read_text() == "precious"
    assert planted.is_symlink()  # left as it was: not ours
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([planted.name, "m.json", "victim"])


def test_a_failed_rename_removes_the_temporary_file(tmp_path, monkeypatch):
    def refuse(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(atomic_writer.os, "replace", refuse)
    with pytest.raises(OSError):
        write_file_atomic(tmp_path / "a.json", b"x")
    assert not list(tmp_path.iterdir())


def test_the_final_name_is_never_a_link_or_a_folder(tmp_path):
    (tmp_path / "real").write_text("keep")
    (tmp_path / "link").symlink_to(tmp_path / "real")
    with pytest.raises(OutputPathError, match="symbolic link"):
        write_file_atomic(tmp_path / "link", b"x")
    (tmp_path / "dir").mkdir()
    with pytest.raises(OutputPathError, match="a folder"):
        write_file_atomic(tmp_path / "dir", b"x")
    assert (tmp_path / "real").read_text() == "keep" and (tmp_path / "link").is_symlink()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dir", "link", "real"]


def test_a_model_file_written_before_is_replaced(tmp_path):
    from cadsim.commands.train import save_model
    from matchers.learned.model import load_model

    model = load_model(model_path())
    out = tmp_path / "m.json"
    first = save_model(model, out)
    assert save_model(model, out) == first == hashlib.sha256(out.read_bytes()).hexdigest()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.json"]


@pytest.mark.parametrize(
    "command", ["evaluate", "sweep-noise", "sweep-regime", "sweep-localisation"]
)
def test_results_never_go_into_a_dataset_or_a_users_folder(command, other, tmp_path, capsys):
    test = DMGM / "test-069-071"
    common = ["--matchers", "sm", "--runs", "1", "--workers", "1", "--no-progress"]
    common += ["--cache", str(tmp_path / "cache")]
    val = ["--val", str(DMGM / "val-070")]
    before = _tree_state(other)
    assert main([command, str(test), *val, *common, "--out", str(other)]) == 2
    assert "is a cadsim dataset" in _one_line(capsys, command)
    assert main([command, str(test), *val, *common, "--out", str(other / "results")]) == 2
    assert "inside the cadsim dataset" in _one_line(capsys, command)
    assert _tree_state(other) == before
    mine = tmp_path / "thesis"
    mine.mkdir()
    (mine / "chapter1.tex").write_text("precious")
    assert main([command, str(test), *val, *common, "--out", str(mine)]) == 2
    assert "not a cadsim result folder" in _one_line(capsys, command)
    (tmp_path / "link").symlink_to(mine)
    assert main([command, str(test), *val, *common, "--out", str(tmp_path / "link")]) == 2
    assert "symbolic link" in _one_line(capsys, command)
    assert (
        main([command, str(test), *val, *common[:-1], str(other), "--out", str(tmp_path / "x")])
        == 2
    )
    assert "the result cache goes elsewhere" in _one_line(capsys, command)
    assert _tree_state(mine) == {"chapter1.tex": hashlib.sha256(b"precious").hexdigest()}
    assert not (tmp_path / "cache").exists() and _tree_state(other) == before


def test_what_a_result_folder_is(tmp_path):
    assert check_result_folder(tmp_path / "new") == tmp_path / "new"
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "thresholds.csv").write_text("matcher,tau\n")
    (tmp_path / "run" / "my-notes.txt").write_text("mine")  # beside results: allowed
    assert check_result_folder(tmp_path / "run") == tmp_path / "run"
    (tmp_path / "run" / "fig").symlink_to(tmp_path)
    with pytest.raises(OutputPathError, match="symbolic links"):
        check_result_folder(tmp_path / "run")
    (tmp_path / "file").write_text("x")
    with pytest.raises(OutputPathError, match="not a folder"):
        check_result_folder(tmp_path / "file")
    with pytest.raises(OutputPathError, match="not a folder"):
        check_cache_folder(tmp_path / "file")
    with pytest.raises(OutputPathError, match="--out"):
        check_result_folder(" ")


def test_a_link_into_a_dataset_is_still_inside_it(other, tmp_path):
    (tmp_path / "way-in").symlink_to(other / "pairs")
    with pytest.raises(OutputPathError, match="inside the cadsim dataset"):
        check_output_file(tmp_path / "way-in" / "x.json", "a file", lambda p: True)


def test_a_fifo_beside_the_output_is_never_read(tmp_path):
    fifo = tmp_path / "out.png"
    os.mkfifo(fifo)
    with pytest.raises(OutputPathError, match="not a regular file"):
        check_output_file(fifo, "a figure", file_holds(b"matplotlib"))
    (tmp_path / "d").mkdir()
    os.mkfifo(tmp_path / "d" / "manifest.json")  # a dataset check must not block on it either
    assert check_output_file(tmp_path / "d" / "x.png", "a figure", lambda p: True)


def test_schema_and_show_keep_a_users_file(other, tmp_path, capsys):
    mine = tmp_path / "notes.json"
    mine.write_text('{"mine": true}')
    assert main(["schema", "--out", str(mine)]) == 2
    assert "not a scenario schema" in _one_line(capsys, "schema")
    assert mine.read_text() == '{"mine": true}'
    schema = tmp_path / "scenario.schema.json"
    assert main(["schema", "--out", str(schema)]) == 0
    assert main(["schema", "--out", str(schema)]) == 0  # its own file: replaced
    json.loads(schema.read_text())
    capsys.readouterr()
    photo = tmp_path / "holiday.png"
    photo.write_bytes(b"\x89PNG\r\n\x1a\n my camera's picture")
    assert main(["show", str(other), "--pair", "0", "--out", str(photo)]) == 2
    assert "not a figure cadsim drew" in _one_line(capsys, "show")
    assert photo.read_bytes().endswith(b"my camera's picture")
    before = _tree_state(other)
    assert main(["show", str(other), "--pair", "0", "--out", str(other)]) == 2
    assert "inside the cadsim dataset" in _one_line(capsys, "show")
    assert _tree_state(other) == before
    drawn = tmp_path / "pair.png"
    assert main(["show", str(other), "--pair", "0", "--out", str(drawn)]) == 0
    assert main(["show", str(other), "--pair", "1", "--out", str(drawn)]) == 0  # its own: replaced


def test_import_refuses_a_link_and_a_folder_inside_a_dataset(other, tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "empty")
    src = str(tmp_path / "no-such-source")
    assert main(["import", "dmgm", src, "--out", str(tmp_path / "link")]) == 2
    assert "symbolic link" in _one_line(capsys, "import")
    assert main(["import", "dmgm", src, "--out", str(other / "pairs" / "new")]) == 2
    assert "inside the cadsim dataset" in _one_line(capsys, "import")
    assert not any((tmp_path / "empty").iterdir())


def test_table_never_writes_into_a_dataset_or_through_a_link(other, tmp_path, capsys):
    before = _tree_state(other)
    assert main(["table", str(other)]) == 2
    assert "is a cadsim dataset" in _one_line(capsys, "table")
    (tmp_path / "link").symlink_to(other)
    assert main(["table", str(tmp_path / "link")]) == 2
    assert "symbolic link" in _one_line(capsys, "table")
    assert _tree_state(other) == before
