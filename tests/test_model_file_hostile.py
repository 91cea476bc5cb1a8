"""Issue 40: a model file is hostile data. Every case of the hostile-input run — a split feature
past the feature count (SIGSEGV), a child cycle or an out-of-range child (a hang), thousands of
trees, NaN / Infinity leaves and thresholds (silently other scores), ``/dev/zero`` (2.4 GB read),
a FIFO (blocks for ever), deeply nested JSON and wrong types in ``training.datasets``
(tracebacks), LightGBM's own ``[Fatal]`` line — ends in one line naming the file and the key,
exit status 2, in bounded time, with nothing written to ``--out``. The crash and hang cases run
``cadsim evaluate`` in a fresh process with a timeout: it must exit, not die of a signal."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from learned_fixture import model_path

from matchers.learned import booster, trees
from matchers.learned.features import feature_names
from matchers.learned.model import MAX_FILE_BYTES, ModelFileError, load_model

REPO = Path(__file__).resolve().parents[1]
DMGM = REPO / "eval" / "data" / "dmgm-cad"
NAMES = feature_names(False)

# a three-leaf tree: node 0 splits to node 1 (left) and leaf 1; node 1 to leaves 0 and 2
TREE3 = {
    "num_leaves": "3",
    "num_cat": "0",
    "split_feature": "0 1",
    "split_gain": "1 1",
    "threshold": "0.5 0.5",
    "decision_type": "2 2",
    "left_child": "1 -1",
    "right_child": "-2 -3",
    "leaf_value": "0.1 0.2 0.3",
    "leaf_weight": "1 1 1",
    "leaf_count": "1 1 1",
    "internal_value": "0 0",
    "internal_weight": "1 1",
    "internal_count": "2 1",
    "is_linear": "0",
    "shrinkage": "1",
}


def _good() -> dict:
    return json.loads(Path(model_path()).read_text())


def _booster_text(tree0: dict | None = None, copies: int = 1) -> str:
    """The fixture model's plain booster, its first tree replaced by ``tree0`` (no
    ``tree_sizes``, so that LightGBM itself would read the edited text too), its first tree
    repeated ``copies`` times instead when ``copies > 1``."""
    text = re.sub(r"tree_sizes=[^\n]*\n", "", _good()["variants"]["learned"]["booster"])
    head, rest = text.split("Tree=0\n", 1)
    first, others = rest.split("\n\n\n", 1)
    if tree0 is not None:
        first = "\n".join(f"{k}={v}" for k, v in tree0.items())
    if copies > 1:
        body = "".join(f"Tree={i}\n{first}\n\n\n" for i in range(copies))
        return head + body + "end of trees" + others.split("end of trees", 1)[1]
    return head + "Tree=0\n" + first + "\n\n\n" + others


def _with_booster(text: str) -> dict:
    document = _good()
    document["variants"]["learned"]["booster"] = text
    return document


def _tree(**changes) -> dict:
    return TREE3 | changes


def _write(tmp_path: Path, name: str, document=None, raw: bytes | None = None) -> Path:
    path = tmp_path / name
    path.write_bytes(raw if raw is not None else json.dumps(document).encode())
    return path


def _evaluate(model: Path | str, tmp_path: Path) -> subprocess.CompletedProcess:
    args = [sys.executable, "-m", "cadsim", "evaluate", str(DMGM / "test-069-071")]
    args += ["--val", str(DMGM / "val-070"), "--matchers", "learned", "--model", str(model)]
    args += ["--out", str(tmp_path / "out"), "--cache", str(tmp_path / "cache")]
    args += ["--runs", "1", "--workers", "1", "--no-progress"]
    env = dict(os.environ, PYTHONPATH=str(REPO))
    return subprocess.run(args, capture_output=True, text=True, cwd=REPO, env=env, timeout=90)


# (file, expected words): the families that crashed, hung or blocked the interpreter
PROCESS_CASES = {
    "split-feature": (_tree(split_feature=f"0 {2**30}"), "split_feature[1]: feature 1073741824"),
    "child-cycle": (_tree(right_child="-2 0"), "right_child[1]: node 0 reached twice"),
    "child-out-of-range": (_tree(left_child="7 -1"), "left_child[0]: node 7 out of range"),
}


@pytest.mark.parametrize("case", [*PROCESS_CASES, "fifo", "dev-zero"])
def test_crash_and_hang_models_end_in_one_line_in_a_fresh_process(case, tmp_path):
    if case == "fifo":
        model, words = tmp_path / "model.json", "is a FIFO"
        os.mkfifo(model)
    elif case == "dev-zero":
        model, words = Path("/dev/zero"), "is a character device"
    else:
        tree, words = PROCESS_CASES[case]
        model = _write(tmp_path, "model.json", _with_booster(_booster_text(tree)))
    started = time.perf_counter()
    done = _evaluate(model, tmp_path)
    assert done.returncode == 2, (done.returncode, done.stderr[-2000:])  # not -11, not a hang
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("cadsim evaluate: error: "), lines
    assert str(model) in lines[0] and words in lines[0], lines[0]
    if case in PROCESS_CASES:
        assert "variants.learned.booster: Tree=0:" in lines[0]
    assert "[LightGBM]" not in done.stdout + done.stderr
    assert not (tmp_path / "out").exists()
    assert time.perf_counter() - started < 60


def _refused(path: Path, work: Path, capfd) -> str:
    """The one line ``cadsim evaluate`` prints for the model at ``path`` (in this process; fd
    capture, so LightGBM's own output would show); its --out and --cache in ``work``."""
    from cadsim.cli import main

    out = work / "out"
    args = ["evaluate", str(DMGM / "test-069-071"), "--val", str(DMGM / "val-070")]
    args += ["--matchers", "learned", "--model", str(path), "--out", str(out), "--runs", "1"]
    args += ["--cache", str(work / "cache"), "--workers", "1", "--no-progress"]
    started = time.perf_counter()
    assert main(args) == 2
    assert time.perf_counter() - started < 20
    captured = capfd.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("cadsim evaluate: error: "), lines
    assert str(path) in lines[0]
    assert "[LightGBM]" not in captured.out + captured.err and "Fatal" not in captured.err
    assert not out.exists()
    return lines[0]


def _rounds(word: str) -> bytes:
    return json.dumps(_good()).replace('"rounds": 40', f'"rounds": {word}').encode()


def _datasets(value) -> dict:
    document = _good()
    document["training"]["datasets"] = value
    return document


def _first_tree(**changes):
    return lambda: _with_booster(_booster_text(_tree(**changes)))


ENTRY = {"name": "a", "checksum": "b" * 64, "pairs": 1, "records": ["c" * 64]}
# (the file's content, built when the test runs; the words its line must hold)
DATA_CASES = {
    "thousands-of-trees": (lambda: _with_booster(_booster_text(copies=6000)), "more than 5000"),
    "nan-leaf": (_first_tree(leaf_value="nan 0.2 0.3"), "Tree=0: leaf_value[0]"),
    "inf-threshold": (_first_tree(threshold="inf 0.5"), "Tree=0: threshold[0]"),
    "huge-leaf": (_first_tree(leaf_value="1e999 0 0"), "1e999 is not finite"),
    "json-nan": (lambda: _rounds("NaN"), "NaN in the JSON"),
    "json-infinity": (lambda: _rounds("-Infinity"), "-Infinity in the JSON"),
    "json-huge-number": (lambda: _rounds("1e400"), "1e400 in the JSON"),
    "deep-json": (lambda: b"[" * 200_000 + b"]" * 200_000, "nested 200000 deep"),
    "datasets-a-string": (lambda: _datasets("abc"), "training.datasets: expected a list"),
    "datasets-item-a-number": (lambda: _datasets([1]), "training.datasets[0]: expected an object"),
    "dataset-name-a-number": (lambda: _datasets([ENTRY | {"name": 1}]), "datasets[0].name"),
    "dataset-pairs-a-word": (lambda: _datasets([ENTRY | {"pairs": "x"}]), "datasets[0].pairs"),
    "dataset-records-a-number": (lambda: _datasets([ENTRY | {"records": 5}]), ".records: expected"),
    "dataset-record-a-list": (lambda: _datasets([ENTRY | {"records": [[]]}]), ".records[0]"),
    "dataset-extra-key": (lambda: _datasets([ENTRY | {"code": "x"}]), "datasets[0].code"),
    "lightgbm-fatal": (lambda: _with_booster("tree\nversion=v4\n"), "num_class missing"),
}


@pytest.mark.parametrize("case", DATA_CASES)
def test_hostile_model_data_is_one_line_naming_the_key(case, tmp_path, capfd):
    build, words = DATA_CASES[case]
    content = build()
    if isinstance(content, bytes):
        path = _write(tmp_path, "model.json", raw=content)
    else:
        path = _write(tmp_path, "model.json", content)
    line = _refused(path, tmp_path, capfd)
    assert words in line, line


def test_folders_and_oversized_files_are_refused_before_reading(tmp_path, capfd):
    folder = tmp_path / "models"
    folder.mkdir()
    assert "is a folder" in _refused(folder, tmp_path, capfd)
    big = tmp_path / "big.json"
    with open(big, "wb") as f:  # sparse: nothing is written, nothing may be read
        f.truncate(MAX_FILE_BYTES + 1)
    assert "larger than 64 MiB" in _refused(big, tmp_path, capfd)


def test_a_valid_model_scores_exactly_as_lightgbm_reads_it():
    import lightgbm

    model = load_model(model_path())
    rng = np.random.default_rng(3)
    for variant, text in model.boosters.items():
        width = len(feature_names(variant == "learned_pose"))
        x = rng.uniform(0, 2, (500, width))
        x[::5, NAMES.index("class_same")] = np.nan  # the missing-value branches too
        own = lightgbm.Booster(model_str=text, params={"num_threads": 1})
        assert np.array_equal(model.predict(variant, x), own.predict(x, num_threads=1))


TREE_CASES = {
    "unreached leaf": (_tree(left_child="1 -1", right_child="-2 -1"), "leaf 0 reached twice"),
    "root as a child": (_tree(left_child="0 -1"), "node 0 reached twice"),
    "leaf out of range": (_tree(right_child="-2 -9"), "leaf 8 out of range"),
    "categorical split": (_tree(decision_type="3 2"), "decision_type[0]"),
    "categorical tree": (_tree(num_cat="1"), "num_cat"),
    "linear tree": (_tree(is_linear="1"), "is_linear"),
    "short array": (_tree(threshold="0.5"), "threshold: 1 values, expected 2"),
    "too many leaves": (_tree(num_leaves=str(trees.MAX_LEAVES + 1)), "num_leaves"),
    "negative count": (_tree(leaf_count="1 -1 1"), "leaf_count: -1"),
    "hex number": (_tree(leaf_value="0x1p3 0 0"), "leaf_value[0]"),
}


@pytest.mark.parametrize("case", TREE_CASES)
def test_trees_are_checked_as_data(case):
    tree, words = TREE_CASES[case]
    with pytest.raises(trees.TreeError, match=re.escape(words)):
        trees.check_trees(_booster_text(tree), NAMES)


@pytest.mark.parametrize(
    ("edit", "words"),
    [
        (lambda t: t.replace("num_cat=0\n", "num_cat=0\nnum_cat=0\n", 1), "num_cat given twice"),
        (lambda t: t.replace("is_linear=0\n", "is_linear\n", 1), "is not key=value"),
        (lambda t: t.replace("is_linear=0\n", "leaf_const=0\n", 1), "unexpected key"),
        (lambda t: t.replace("max_feature_idx=17", "max_feature_idx=99"), "max_feature_idx"),
        (lambda t: t.replace("binary sigmoid:1", "binary sigmoid:0"), "objective"),
        (lambda t: t.replace("version=v4", "version=v4\nmonotone_constraints=1"), "unexpected"),
        (lambda t: t.replace("end of trees", "the end"), "got 'the end'"),
        (lambda t: t.replace("Tree=0", "Tree=0 é"), "printable ASCII"),
    ],
)
def test_the_text_layout_is_lightgbms_own(edit, words):
    with pytest.raises(trees.TreeError, match=re.escape(words)):
        trees.check_trees(edit(_booster_text()), NAMES)


def test_the_total_leaf_cap_bounds_prediction_work(monkeypatch):
    monkeypatch.setattr(trees, "MAX_TOTAL_LEAVES", 10)
    with pytest.raises(trees.TreeError, match="more than 10 leaves in all"):
        trees.check_trees(_booster_text(copies=6), NAMES)


def test_lightgbms_own_output_never_reaches_the_terminal(capfd):
    with pytest.raises(ValueError, match="number of classes"):
        booster.parse_booster("tree\nversion=v4\n")  # unchecked text, straight to LightGBM
    captured = capfd.readouterr()
    assert "[LightGBM]" not in captured.out + captured.err
    print("after")  # the descriptors are back
    assert capfd.readouterr().out == "after\n"


def test_refusals_are_model_file_errors_naming_the_file(tmp_path):
    path = _write(tmp_path, "m.json", _datasets("abc"))
    with pytest.raises(ModelFileError) as info:
        load_model(path)
    assert str(info.value).startswith(f"{path}: training.datasets")
    assert isinstance(info.value, ValueError)  # the CLI's one-line, exit-2 kind
