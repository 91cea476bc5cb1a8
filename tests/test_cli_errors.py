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
