"""`cadsim info`, `cadsim show` and `cadsim generate`'s error handling, through the CLI entry point."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from test_generate_fakes import FAKE_STAGES, FakeScenario

from cadsim.cli import main
from cadsim.dataset import Dataset
from cadsim.generation.pipeline import generate_dataset
from cadsim.pair_drawing import CORRECT, MISSED, WRONG, pair_figure, save_figure


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("cli") / "ds"
    generate_dataset(FakeScenario(), out, pairs=3, workers=1, stages=FAKE_STAGES, progress=False)
    return out


def test_info_json_structure(dataset, capsys):
    assert main(["info", str(dataset), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    ds = Dataset(dataset)
    assert info["n_pairs"] == 3 and info["checksum"] == ds.checksum and info["scenario"] == "fake"
    assert [p["index"] for p in info["pairs"]] == [0, 1, 2]
    for p, pair in zip(info["pairs"], ds, strict=True):
        assert (p["n1"], p["n2"], p["covisible"]) == (
            len(pair.view1),
            len(pair.view2),
            len(pair.gt_pairs),
        )
        assert p["non_covisible1"] == p["n1"] - p["covisible"] >= 1
        assert sum(p["classes1"].values()) == p["n1"]
        z = pair.view2.positions[:, 2]
        assert p["depth2"] == [pytest.approx(z.min()), pytest.approx(z.max())]
    assert sum(info["class_mix"].values()) == sum(p["n1"] + p["n2"] for p in info["pairs"])
    cov = [p["covisible"] for p in info["pairs"]]
    assert info["covisible"] == {
        "mean": pytest.approx(np.mean(cov)),
        "min": min(cov),
        "max": max(cov),
    }
    assert info["depth"]["min"] <= info["depth"]["median"] <= info["depth"]["max"]


def test_info_text_and_errors(dataset, tmp_path, capsys):
    assert main(["info", str(dataset)]) == 0
    text = capsys.readouterr().out
    assert "3 pairs" in text and "covisible per pair" in text and "e00000_s00" in text
    assert main(["info", str(tmp_path)]) == 2
    assert "no manifest" in capsys.readouterr().err


def test_show_writes_png(dataset, tmp_path, capsys):
    import cv2

    out = tmp_path / "fig" / "pair1.png"
    assert main(["show", str(dataset), "--pair", "1", "--out", str(out)]) == 0
    assert "pair 1" in capsys.readouterr().out
    img = cv2.imread(str(out))
    assert img is not None and img.shape[1] >= 2 * 160  # both views side by side
    assert main(["show", str(dataset), "--pair", "9", "--out", str(out)]) == 2
    assert "out of range" in capsys.readouterr().err


def test_pair_figure_draws_given_lines(tmp_path):
    """The drawing function the evaluation's Fig. 3 reuses: per-pair line colours."""
    c1 = np.zeros((40, 50, 3), np.uint8)
    c2 = np.full((40, 60, 3), 255, np.uint8)
    boxes1 = np.array([[1, 1, 10, 10], [20, 20, 30, 30]], float)
    boxes2 = np.array([[5, 5, 15, 15], [40, 10, 50, 20], [0, 30, 8, 39]], float)
    fig = pair_figure(
        c1, c2, boxes1, boxes2, [[0, 1], [1, 0], [1, 2]], line_colors=[CORRECT, WRONG, MISSED]
    )
    ax = fig.axes[0]
    lines = [c for c in ax.collections if c.__class__.__name__ == "LineCollection"][0]
    segs = lines.get_segments()
    np.testing.assert_allclose(
        segs[0], [[5.5, 5.5], [50 + 16 + 45, 15]]
    )  # view 2 shifted by W1+gap
    assert len(segs) == 3
    assert save_figure(fig, tmp_path / "f.png").stat().st_size > 0
    with pytest.raises(ValueError, match="line_colors: 1 colours for 3 pairs"):
        pair_figure(c1, c2, boxes1, boxes2, [[0, 1], [1, 0], [1, 2]], line_colors=["red"])
    with pytest.raises(ValueError, match="pairs: index out of range"):
        pair_figure(c1, c2, boxes1, boxes2, [[2, 0]])


def test_generate_reports_bad_input(tmp_path, capsys):
    missing = tmp_path / "nope.toml"
    assert main(["generate", str(missing), "--out", str(tmp_path / "o"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "nope.toml" in err and "does not exist" in err
    bad = tmp_path / "bad.toml"
    bad.write_text('pairz = 2\n[traffic]\nsource = "sumo"\n')
    assert main(["generate", str(bad), "--out", str(tmp_path / "o"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "bad.toml" in err and "pairz" in err and "unknown key" in err


def test_birdseye_draws_observers_objects_and_match_lines_at_true_positions(dataset):
    from matplotlib.figure import Figure

    from cadsim.pair_drawing import detection_world_positions, draw_birdseye

    pair = Dataset(dataset)[1]
    w1, w2 = detection_world_positions(pair)
    centres = {o.id: o.center[:2] for o in pair.objects}
    for view, world in ((pair.view1, w1), (pair.view2, w2)):
        assert np.allclose(world, [centres[i] for i in view.object_ids])
    gt = pair.gt_pairs
    assert np.allclose(w1[gt[:, 0]], w2[gt[:, 1]])  # a true match: one object, one position
    wrong = np.array([[gt[0, 0], gt[1, 1]]])  # two different objects: a visible line
    ax = Figure().subplots()
    draw_birdseye(ax, pair, [(gt, CORRECT, "-"), (wrong, WRONG, "-")])
    drawn = [line for line in ax.get_lines() if line.get_color() == WRONG]
    assert len(drawn) == 1 and np.allclose(
        np.column_stack(drawn[0].get_data()), [w1[gt[0, 0]], w2[gt[1, 1]]]
    )
    assert len(ax.patches) == 2  # both observers' view frusta
    labels = {t.get_text() for t in ax.get_legend().get_texts()}
    assert {"observer 1", "observer 2", "seen by 1", "seen by 2"} <= labels


@pytest.fixture(scope="module")
def sequences(tmp_path_factory) -> Path:
    from test_sequences import _generate, _scenario

    out = tmp_path_factory.mktemp("cli-seq") / "ds"
    _generate(out, _scenario(frames=4, interval_s=0.25), pairs=3)
    return out


def test_info_states_sequences_frames_and_interval(sequences, dataset, capsys):
    assert main(["info", str(sequences), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    ds = Dataset(sequences)
    q = info["sequence"]
    assert q["sequences"] == ds.sequences == 3 and q["frames_planned"] == 4
    assert q["frames"] == {"mean": 4.0, "min": 4.0, "max": 4.0}
    assert q["interval_s"] == pytest.approx(0.25)
    assert q["odometry_model"]["scale_sigma"] == pytest.approx(0.01)
    for k in range(ds.sequences):
        for pair in ds.sequence(k):
            entry = info["pairs"][pair.index]
            assert (entry["sequence"], entry["frame"]) == (k, pair.frame)
    assert main(["info", str(sequences)]) == 0
    text = capsys.readouterr().out
    assert "sequences               3 of 4 frames (planned 4), 0.25 s apart" in text
    assert "seq frame" in text
    # a dataset without sequences says nothing about them
    assert main(["info", str(dataset), "--json"]) == 0
    plain = json.loads(capsys.readouterr().out)
    assert "sequence" not in plain and "sequence" not in plain["pairs"][0]


def test_show_draws_frame_t_of_sequence_k(sequences, dataset, tmp_path, capsys):
    import cv2

    ds = Dataset(sequences)
    target = ds.sequence(1)[2]
    out = tmp_path / "seq1-frame2.png"
    assert main(["show", str(sequences), "--sequence", "1", "--frame", "2", "--out", str(out)]) == 0
    said = capsys.readouterr().out
    assert f"pair {target.index} ({target.name}), sequence 1 frame 2" in said
    # the same drawing as the record named by its pair index
    again = tmp_path / "by-pair.png"
    assert main(["show", str(sequences), "--pair", str(target.index), "--out", str(again)]) == 0
    capsys.readouterr()
    assert np.array_equal(cv2.imread(str(out)), cv2.imread(str(again)))
    assert main(["show", str(sequences), "--sequence", "2", "--out", str(tmp_path / "f0")]) == 0
    assert f"({ds.sequence(2)[0].name}), sequence 2 frame 0" in capsys.readouterr().out
    cases = [
        (["--sequence", "3"], "--sequence: 3 is out of range; expected 0..2"),
        (["--sequence", "0", "--frame", "4"], "--frame: 4 is out of range"),
        (["--frame", "1"], "--frame: needs --sequence"),
        (["--pair", "0", "--sequence", "0"], "not both"),
    ]
    for extra, words in cases:
        assert main(["show", str(sequences), *extra, "--out", str(tmp_path / "x.png")]) == 2
        assert words in capsys.readouterr().err, extra
    assert main(["show", str(dataset), "--sequence", "0", "--out", str(tmp_path / "y.png")]) == 2
    assert "not a sequence dataset" in capsys.readouterr().err


def test_the_record_figure_numbers_each_true_pair_alike_in_both_views_and_from_above(dataset):
    from cadsim.pair_drawing import draw_pair_from_record

    pair = Dataset(dataset)[1]
    fig = draw_pair_from_record(pair)
    images, above = fig.axes[0], fig.axes[1]
    width1 = pair.color1.shape[1]
    on_image = {1: {}, 2: {}}
    for text in images.texts:
        number = text.get_text().split(" ")[0]
        if number.isdigit():
            on_image[1 if text.get_position()[0] < width1 else 2][int(number)] = text
    expected = set(range(1, len(pair.gt_pairs) + 1))
    assert set(on_image[1]) == set(on_image[2]) == expected  # one number per true pair, each view
    offset = images.get_xlim()[1] - pair.color2.shape[1]  # view 2's left edge on the canvas
    for k, (i, j) in enumerate(pair.gt_pairs, start=1):  # number k above box i and box j
        assert on_image[1][k].get_position()[0] == pytest.approx(pair.view1.boxes[i][0])
        assert on_image[2][k].get_position()[0] == pytest.approx(pair.view2.boxes[j][0] + offset)
    numbers_above = {int(t.get_text()) for t in above.texts if t.get_text().isdigit()}
    assert numbers_above == expected
