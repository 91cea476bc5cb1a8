"""The box-only V2X table: camera splits exported and imported back as boxes, every matcher
that needs no pixels run with the full table's protocol, a report part read off its files."""

from __future__ import annotations

import pandas as pd
import pytest
from test_generate_fakes import FAKE_STAGES, FakeScenario

from cadsim.dataset import Dataset
from cadsim.generation.executors import make_executor
from cadsim.generation.pipeline import generate_dataset
from eval.core.cache import ResultCache
from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec
from eval.studies.v2x.boxes import as_boxes, box_matchers, evaluate_boxes, readme_part


def test_pixel_matchers_are_left_out():
    specs = [MatcherSpec("maximin"), MatcherSpec.of("sm", pairwise="image"), MatcherSpec("pose")]
    assert [s.name for s in box_matchers(specs)] == ["maximin", "pose"]


def test_a_folder_it_did_not_write_is_never_replaced(tmp_path):
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep")
    with pytest.raises(ValueError, match="not a box dataset this stage wrote"):
        as_boxes(tmp_path / "nothing", tmp_path / "mine")
    assert (tmp_path / "mine" / "notes.txt").read_text() == "keep"


@pytest.mark.slow
def test_stage_writes_the_box_table_and_its_report_part(tmp_path):
    data = tmp_path / "data"
    for name, seed in (("cad-v2x", None), ("cad-v2x-val", 99)):
        generate_dataset(
            FakeScenario(), data / name, pairs=3, seed=seed, workers=1, stages=FAKE_STAGES,
            progress=False,
        )  # fmt: skip
    out = tmp_path / "results"
    specs = [MatcherSpec("maximin"), MatcherSpec("pose")]
    with make_executor(1) as executor:
        runner = Runner(ResultCache(tmp_path / "cache"), executor, progress=False)
        table, record = evaluate_boxes(
            data / "cad-v2x", data / "cad-v2x-val", data, specs, [0], runner, out, tune=False
        )
        again, _ = evaluate_boxes(
            data / "cad-v2x", data / "cad-v2x-val", data, specs, [0], runner, out, tune=False
        )
    assert Dataset(record["test_dir"]).manifest["generation"]["cues"] == "boxes"
    assert {"maximin", "pose", "oracle", "prior"} <= set(table["matcher"])
    pd.testing.assert_frame_equal(table, again)  # rebuilt boxes, same records: same table
    assert (out / "table_v2x_boxes.md").is_file() and (out / "v2x_boxes" / "denied").is_dir()
    part = readme_part(out, ".")
    assert part[0] == "### The V2X task with boxes only" and any(
        "with boxes only" in p for p in part
    )


@pytest.mark.slow
def test_the_box_folder_is_reused_until_its_source_or_manifest_changes(tmp_path, monkeypatch):
    import json

    import cadsim.exporters.opv2v as opv2v

    monkeypatch.setenv("CADSIM_CACHE_DIR", str(tmp_path / "cadsim-cache"))
    camera, boxes = tmp_path / "data" / "cad-v2x", tmp_path / "data" / "cad-v2x-boxes"

    def generate(pairs):
        generate_dataset(
            FakeScenario(), camera, pairs=pairs, workers=1, stages=FAKE_STAGES, progress=False
        )

    generate(2)
    exports = []
    real = opv2v.export_opv2v
    monkeypatch.setattr(opv2v, "export_opv2v", lambda *a, **k: exports.append(a) or real(*a, **k))
    as_boxes(camera, boxes)
    built = (boxes / "manifest.json").stat().st_mtime_ns
    as_boxes(camera, boxes)
    assert len(exports) == 1 and (boxes / "manifest.json").stat().st_mtime_ns == built  # reused
    generate(3)  # the source split gains a pair: another checksum
    as_boxes(camera, boxes)
    assert len(exports) == 2 and len(Dataset(boxes)) == 3
    manifest = json.loads((boxes / "manifest.json").read_text())
    (boxes / "manifest.json").write_text(json.dumps(manifest | {"checksum": "0" * 64}))
    as_boxes(camera, boxes)  # not the manifest it built: rebuilt
    assert len(exports) == 3 and Dataset(boxes).checksum == manifest["checksum"]
