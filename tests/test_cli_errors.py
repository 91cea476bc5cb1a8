"""Issue 15 #3, #4, #9: every user error ends in one line naming the file (and key) with exit
status 2; a bug keeps its traceback; ``--debug`` shows the traceback of any error."""

from __future__ import annotations

import json
import shutil
import types
from pathlib import Path

import pytest
from test_generate_fakes import FAKE_STAGES, FakeScenario

from cadsim import cli
from cadsim.cli import main
from cadsim.generation.pipeline import generate_dataset


@pytest.fixture(scope="module")
def pristine(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("clierr") / "ds"
    generate_dataset(FakeScenario(), out, pairs=2, workers=1, stages=FAKE_STAGES, progress=False)
    return out


@pytest.fixture
def dataset(pristine, tmp_path) -> Path:
    copy = tmp_path / "ds"
    shutil.copytree(pristine, copy)
    return copy


def _one_error_line(capsys, command: str) -> str:
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines and lines[-1].startswith(f"cadsim {command}: error: "), lines
    assert len(lines) == 1, lines  # nothing but the line: no traceback
    return lines[-1]


def _set(manifest: dict, dotted: str, value) -> None:
    keys = dotted.replace("[", ".").replace("]", "").split(".")
    target = manifest
    for key in keys[:-1]:
        target = target[int(key) if key.isdigit() else key]
    target[int(keys[-1]) if keys[-1].isdigit() else keys[-1]] = value


@pytest.mark.parametrize(
    "key, value",
    [
        ("records", 5),
        ("records[0]", "e00000_s00"),
        ("records[0].episode", "0"),
        ("records[0].name", "../../../etc"),
        ("records[1].checksum", None),
        ("complete", "yes"),
        ("checksum", 12),
        ("scenario", []),
        ("seeds.root", -1),
        ("generation.noise.noise_rate", "lots"),
        ("generation.noise", [0.1]),
    ],
)
def test_manifest_fields_of_the_wrong_type_name_file_and_key(dataset, capsys, key, value):
    path = dataset / "manifest.json"
    manifest = json.loads(path.read_text())
    _set(manifest, key, value)
    path.write_text(json.dumps(manifest))
    assert main(["info", str(dataset)]) == 2
    line = _one_error_line(capsys, "info")
    assert str(path) in line and f"{key}: expected" in line


def test_noise_rate_lots_is_named_in_evaluate_too(dataset, tmp_path, capsys):
    path = dataset / "manifest.json"
    manifest = json.loads(path.read_text())
    manifest["generation"]["noise"]["noise_rate"] = "lots"
    path.write_text(json.dumps(manifest))
    argv = ["evaluate", str(dataset), "--no-calibration", "--matchers", "sm", "--runs", "1"]
    argv += ["--workers", "1", "--out", str(tmp_path / "r"), "--cache", str(tmp_path / "c")]
    assert main(argv) == 2
    line = _one_error_line(capsys, "evaluate")
    assert str(path) in line and "generation.noise.noise_rate" in line


@pytest.mark.parametrize(
    "argv, words",
    [
        (["--pairs", "0"], "argument --pairs: expected an integer in 1..100000, got 0"),
        (["--rates", "inf"], "--rates: expected one or more rates in [0, 1]"),
        (["--rates", "0,nan"], "--rates: expected one or more rates in [0, 1]"),
        (["--workers", "0"], "argument --workers: expected an integer in 1..1024, got 0"),
        (["--runs", "-1"], "argument --runs: expected an integer in 1..1000, got -1"),
    ],
)
def test_bad_sweep_options_are_refused_in_one_line(dataset, tmp_path, capsys, argv, words):
    base = ["sweep-noise", str(dataset), "--matchers", "sm", "--out", str(tmp_path / "o")]
    try:
        assert main([*base, "--cache", str(tmp_path / "c"), *argv]) == 2
    except SystemExit as exc:  # argparse's usage errors: status 2, the last line says why
        assert exc.code == 2
    assert words in capsys.readouterr().err.strip().splitlines()[-1]
    assert not (tmp_path / "o").exists()


def test_generate_refuses_workers_0_and_a_negative_seed(tmp_path, capsys):
    scenario = Path(__file__).resolve().parents[1] / "scenarios" / "mrc-arena.toml"
    for argv in (["--workers", "0"], ["--seed", "-3"]):
        with pytest.raises(SystemExit) as exc:
            main(["generate", str(scenario), "--out", str(tmp_path / "o"), *argv])
        assert exc.value.code == 2
        assert argv[0] in capsys.readouterr().err.strip().splitlines()[-1]
    assert not (tmp_path / "o").exists()


def _fake_command(monkeypatch, exc: BaseException) -> None:
    module = types.SimpleNamespace(add_arguments=lambda parser: None)

    def run(args):
        raise exc

    module.run = run
    monkeypatch.setitem(cli.COMMANDS, "boom", ("fake", "raises"))
    monkeypatch.setattr(cli, "_load", lambda name: module)


def test_a_bug_keeps_its_traceback(monkeypatch):
    _fake_command(monkeypatch, TypeError("internal slip"))
    with pytest.raises(TypeError, match="internal slip"):
        main(["boom"])


def test_debug_shows_the_traceback_of_a_user_error(monkeypatch, capsys):
    _fake_command(monkeypatch, ValueError("x.toml: camera.width: is 0\nsecond line"))
    assert main(["boom"]) == 2
    assert _one_error_line(capsys, "boom").endswith("camera.width: is 0 | second line")
    for argv in (["--debug", "boom"], ["boom", "--debug"]):
        with pytest.raises(ValueError, match="camera.width"):
            main(argv)


def test_show_prints_the_file_it_writes(dataset, tmp_path, capsys):
    folder = tmp_path / "figures"
    folder.mkdir()
    assert main(["show", str(dataset), "--pair", "1", "--out", str(folder)]) == 0
    written = Path(capsys.readouterr().out.split(":")[0])
    assert written == folder / "e00000_s01.png" and written.is_file()
    assert main(["show", str(dataset), "--out", str(tmp_path / "noext")]) == 0
    written = Path(capsys.readouterr().out.split(":")[0])
    assert written == tmp_path / "noext.png" and written.is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ds", "figures", "noext.png"]


# --- issue 22 #7-#9: more hostile inputs, one line each; info/show verify; atomic result files ---


def _edit_manifest(dataset: Path, **fields) -> None:
    path = dataset / "manifest.json"
    manifest = json.loads(path.read_text())
    path.write_text(json.dumps(manifest | fields))


@pytest.mark.parametrize(
    "fields, words",
    [
        ({"record_files": 5}, "record_files: expected a list of file names"),
        ({"records": []}, "records: a finished dataset with no record"),
    ],
)
@pytest.mark.parametrize("command", ["info", "show"])
def test_manifest_shapes_that_break_the_reader_are_one_line(
    dataset, capsys, fields, words, command
):
    _edit_manifest(dataset, **fields)
    assert (
        main([command, str(dataset), *(["--out", str(dataset.parent)] * (command == "show"))]) == 2
    )
    line = _one_error_line(capsys, command)
    assert str(dataset / "manifest.json") in line and words in line


@pytest.mark.parametrize("command", ["info", "show"])
def test_one_flipped_byte_is_caught_by_verification(dataset, capsys, command):
    npz = dataset / "pairs" / "e00000_s00" / "detections.npz"
    data = bytearray(npz.read_bytes())
    data[len(data) // 2] ^= 0xFF
    npz.write_bytes(bytes(data))
    assert (
        main([command, str(dataset), *(["--out", str(dataset.parent)] * (command == "show"))]) == 2
    )
    line = _one_error_line(capsys, command)
    assert "e00000_s00" in line and "checksum mismatch" in line


def test_info_and_show_say_that_they_verified(dataset, capsys, tmp_path):
    assert main(["info", str(dataset)]) == 0
    assert "every record verified" in capsys.readouterr().out
    assert main(["info", str(dataset), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["verified"] is True
    assert main(["show", str(dataset), "--out", str(tmp_path)]) == 0
    assert "(record checksum verified)" in capsys.readouterr().out


def test_a_corrupt_npz_is_named_even_unverified(dataset):
    from cadsim.dataset.encoding import load_npz

    npz = dataset / "pairs" / "e00000_s00" / "detections.npz"
    data = bytearray(npz.read_bytes())
    data[len(data) // 2] ^= 0xFF
    with pytest.raises(ValueError, match="detections.npz: not a readable .npz"):
        load_npz(bytes(data), str(npz))  # zlib's own error would not be a user error


def test_a_deeply_nested_scenario_is_one_line(tmp_path, capsys):
    path = tmp_path / "deep.toml"
    path.write_text("a = " + "[" * 5000 + "]" * 5000 + "\n")
    assert main(["generate", str(path), "--out", str(tmp_path / "o")]) == 2
    line = _one_error_line(capsys, "generate")
    assert str(path) in line and "nested too deeply" in line
    assert not (tmp_path / "o").exists()


def test_a_huge_message_is_cut_to_a_readable_line(monkeypatch, capsys):
    _fake_command(monkeypatch, ValueError("bad value " + "x" * 900_000 + " end"))
    assert main(["boom"]) == 2
    line = _one_error_line(capsys, "boom")
    assert len(line) < 1200 and "characters cut" in line and line.endswith(" end")


def test_a_full_disk_names_the_file_and_leaves_the_previous_result(tmp_path, monkeypatch):
    import errno
    import os

    import pandas as pd

    from cadsim.dataset import atomic_writer
    from eval.core.result_files import write_csv, write_text

    table = tmp_path / "table1.md"
    write_text(table, "the previous table\n")

    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(atomic_writer.os, "fsync", full)
    with pytest.raises(OSError) as err:
        write_text(table, "a new table\n")
    assert str(table) in str(err.value) and "No space left" in str(err.value)
    assert table.read_text() == "the previous table\n"  # never a 0-byte or half file
    with pytest.raises(OSError, match="results.csv"):
        write_csv(pd.DataFrame({"a": [1]}), tmp_path / "results.csv")
    assert not (tmp_path / "results.csv").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table1.md"]  # no temp file left


def test_a_full_disk_during_generate_is_one_line_naming_the_file(tmp_path, monkeypatch, capsys):
    import errno
    import os

    from cadsim.dataset import atomic_writer

    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(atomic_writer.os, "fsync", full)
    out = tmp_path / "ds"
    with pytest.raises(OSError) as err:
        generate_dataset(
            FakeScenario(), out, pairs=1, workers=1, stages=FAKE_STAGES, progress=False
        )
    assert str(out) in str(err.value) and "No space left" in str(err.value)


@pytest.mark.parametrize(
    "command", ["evaluate", "sweep-noise", "sweep-regime", "sweep-localisation"]
)
def test_commands_that_write_results_need_an_explicit_out(
    dataset, tmp_path, capsys, monkeypatch, command
):
    # Run from a folder holding a results/ of its own: nothing in it may change.
    monkeypatch.chdir(tmp_path)
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / "table1.md").write_text("committed\n")
    with pytest.raises(SystemExit) as exit_info:
        main([command, str(dataset), "--matchers", "sm", "--runs", "1"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "--out" in err[-1] and "required" in err[-1]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ds", "results"]  # no cache/ either
    assert (tmp_path / "results" / "table1.md").read_text() == "committed\n"


def test_the_result_cache_defaults_to_the_users_cache_not_the_current_folder(monkeypatch, tmp_path):
    import argparse

    from eval.commands.evaluate import add_runner_arguments

    monkeypatch.setenv("CADSIM_CACHE_DIR", str(tmp_path / "mine"))
    parser = argparse.ArgumentParser()
    add_runner_arguments(parser)
    args = parser.parse_args(["--out", "x"])
    assert args.cache == str(tmp_path / "mine" / "runs")
