"""The learned matchers: deterministic training, the model file as data, the overlap refusal, a
planted correspondence recovered after training, and one τ calibration path for every row."""

from __future__ import annotations

import json
import pickle
from pathlib import Path

import numpy as np
import pytest
from learned_fixture import model_path, synthetic_pairs

from cadsim.commands.train import save_model
from matchers import get, required_options
from matchers.learned.features import feature_names, pair_features
from matchers.learned.model import load_model
from matchers.learned.training import labels, train_model

DMGM = Path(__file__).resolve().parents[1] / "eval" / "data" / "dmgm-cad"


def test_training_gives_the_same_model_bytes_twice(tmp_path):
    examples = synthetic_pairs(1, 12)
    a = train_model(examples, {"datasets": []}, rounds=25).to_bytes()
    b = train_model(synthetic_pairs(1, 12), {"datasets": []}, rounds=25).to_bytes()
    assert a == b
    other = train_model(synthetic_pairs(2, 12), {"datasets": []}, rounds=25).to_bytes()
    assert other != a  # the bytes follow the data
    save_model(train_model(examples, {"datasets": []}, rounds=25), tmp_path / "m.json")
    assert (tmp_path / "m.json").read_bytes() == a


def test_features_are_named_rows_in_match_order():
    problem, truth = synthetic_pairs(3, 1)[0]
    plain, prior = pair_features(problem), pair_features(problem, prior=True)
    assert plain.shape == (problem.n1 * problem.n2, len(feature_names(False)))
    assert np.array_equal(prior[:, : plain.shape[1]], plain)  # the plain features come first
    y = labels(problem, truth)
    assert y.sum() == len(truth) and y[truth[0, 0] * problem.n2 + truth[0, 1]] == 1
    same = plain[:, feature_names(False).index("class_same")]
    assert np.all(same[y == 1] == 1)  # a true match has one class


@pytest.mark.parametrize("name", ["learned", "learned_pose", "maximin_learned", "rrwm_learned"])
def test_a_matcher_trained_on_similar_scenes_recovers_the_planted_correspondence(name):
    assert required_options(name) == {"model"}
    found = total = wrong = 0
    for problem, truth in synthetic_pairs(99, 6):  # other scenes than the training ones
        pairs = get(name)(problem, seed=0, threshold=0.3, model=model_path()).pairs
        got = {tuple(p) for p in pairs.tolist()}
        want = {tuple(p) for p in truth.tolist()}
        found += len(got & want)
        wrong += len(got - want)
        total += len(want)
    assert found >= 0.9 * total and wrong <= 0.1 * total, (found, wrong, total)


def test_a_learned_matcher_without_a_model_says_what_it_needs():
    problem, _ = synthetic_pairs(4, 1)[0]
    with pytest.raises(ValueError, match="model.*cadsim train"):
        get("learned")(problem)


def _bad(tmp_path, name: str, data: bytes) -> str:
    path = tmp_path / name
    path.write_bytes(data)
    with pytest.raises(ValueError) as info:
        load_model(path)
    message = str(info.value)
    assert "\n" not in message and str(path) in message
    return message


class _Payload:
    def __reduce__(self):
        return (Path.touch, (Path("/tmp/cadsim-model-payload-ran"),))


def test_a_model_file_with_unexpected_content_is_refused_in_one_line(tmp_path):
    good = json.loads(Path(model_path()).read_text())
    marker = Path("/tmp/cadsim-model-payload-ran")
    marker.unlink(missing_ok=True)
    assert "JSON" in _bad(tmp_path, "pickle.json", pickle.dumps(_Payload()))
    assert not marker.exists()  # nothing in the file ran
    assert "JSON" in _bad(tmp_path, "garbage.json", b"\x00\xff not json")
    extra = dict(good) | {"code": "__import__('os')"}
    assert "code" in _bad(tmp_path, "extra.json", json.dumps(extra).encode())
    wrong_version = dict(good) | {"features_version": 999}
    assert "retrain" in _bad(tmp_path, "version.json", json.dumps(wrong_version).encode())
    broken = json.loads(json.dumps(good))
    broken["variants"]["learned"]["booster"] = "tree\nnot a model\n"
    assert "variants.learned.booster" in _bad(tmp_path, "trees.json", json.dumps(broken).encode())
    renamed = json.loads(json.dumps(good))
    renamed["variants"]["learned"]["features"] = ["x"]
    assert "features" in _bad(tmp_path, "features.json", json.dumps(renamed).encode())
    with pytest.raises(ValueError, match="changed"):
        load_model(model_path(), sha256="0" * 64)


@pytest.fixture(scope="module")
def dmgm_model(tmp_path_factory) -> Path:
    from cadsim.commands.train import train_datasets

    path = tmp_path_factory.mktemp("model") / "dmgm070.json"
    train_datasets([str(DMGM / "val-070")], path, variants="learned", rounds=20)
    return path


def test_a_model_is_refused_on_data_it_was_trained_on(dmgm_model, tmp_path):
    from eval.core.tasks import MatcherSpec
    from eval.protocol.model_options import with_model

    model = load_model(dmgm_model)
    assert len(model.training_records()) == 201
    assert model.training["datasets"][0]["name"] == "val-070"
    specs = [MatcherSpec("learned"), MatcherSpec("sm")]
    with pytest.raises(ValueError, match="trained on 201 record"):
        with_model(specs, dmgm_model, [DMGM / "val-070"])
    named = with_model(specs, dmgm_model, [DMGM / "test-069-071"])
    assert dict(named["learned"].options)["model_sha256"] == model.sha256
    assert named["sm"] == MatcherSpec("sm")
    with pytest.raises(ValueError, match="--model"):
        with_model(specs, None, [DMGM / "test-069-071"])

    from cadsim.cli import main

    args = ["evaluate", str(DMGM / "val-070"), "--val", str(DMGM / "test-069-071")]
    args += ["--matchers", "learned", "--model", str(dmgm_model), "--out", str(tmp_path / "o")]
    assert main(args) == 2  # the one-line user error, before anything runs
    assert not (tmp_path / "o").exists()


def test_none_appearance_and_learned_rows_share_one_calibration_path(
    dmgm_model, tmp_path, monkeypatch
):
    from eval.core.cache import ResultCache
    from eval.core.executor import make_executor
    from eval.core.runner import Runner
    from eval.core.tasks import MatcherSpec
    from eval.engine.protocol_run import evaluate
    from eval.engine.splits import open_entry
    from eval.protocol import calibration
    from eval.protocol.model_options import with_model

    calibrated = []
    real = calibration.calibrate

    def spy(runs):
        calibrated.append({r.spec.matcher.name for r in runs})
        return real(runs)

    monkeypatch.setattr(calibration, "calibrate", spy)
    entry = open_entry(DMGM / "test-069-071", DMGM / "val-070")
    specs = [MatcherSpec("none"), MatcherSpec("appearance"), MatcherSpec("learned")]
    named = with_model(specs, dmgm_model, [entry.test_dir])
    with make_executor(1) as executor:
        runner = Runner(ResultCache(tmp_path / "cache"), executor, progress=False)
        taus = evaluate([entry], named, [0], runner, tmp_path / "out", untuned=False)
    assert sorted(map(sorted, calibrated)) == [["appearance"], ["learned"], ["none"]]
    assert set(taus[entry.label]) == {"none", "appearance", "learned"}
    assert taus[entry.label]["learned"] is not None


def test_cadsim_train_writes_a_model_and_refuses_bad_variants(tmp_path, capsys):
    from cadsim.cli import main

    out = tmp_path / "m.json"
    args = ["train", str(DMGM / "test-069-071"), "--rounds", "5", "--no-progress"]
    assert main([*args, "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "learned, learned_pose trained on 109 frame pairs" in printed
    assert sorted(load_model(out).boosters) == ["learned", "learned_pose"]
    assert main([*args, "--variants", "learned,bogus", "--out", str(tmp_path / "x.json")]) == 2
    assert "--variants" in capsys.readouterr().err and not (tmp_path / "x.json").exists()


def test_no_pickle_outside_the_restricted_reader():
    import re

    root = Path(__file__).resolve().parents[1]
    allowed = root / "cadsim" / "importers" / "restricted_pickle.py"
    pattern = re.compile(r"^\s*(import|from)\s+(pickle|cPickle|dill|cloudpickle|joblib)\b", re.M)
    found = [
        str(path.relative_to(root))
        for folder in ("cadsim", "matchers", "eval")
        for path in (root / folder).rglob("*.py")
        if path != allowed and pattern.search(path.read_text())
    ]
    assert not found, found
