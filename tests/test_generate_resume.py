"""Generation orchestration with fake stages: determinism across workers and seeds, resume after
an injected failure and after killing the process group, refusal to mix configurations."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import test_generate_fakes as fakes
from test_generate_fakes import FAKE_STAGES, FakeScenario

from cadsim.dataset import Dataset, layout
from cadsim.generation.pipeline import GenerationError, generate_dataset

TESTS = Path(__file__).resolve().parent
# Two candidate pairs can be kept per snapshot, so resumes also start in the middle of one.
SCENARIO = FakeScenario(sampling={"pairs_per_episode": 3, "pairs_per_snapshot": 2})


def _tree(out: Path) -> dict[str, bytes]:
    """Every file of the dataset's records plus the manifest's record list, for comparison."""
    files = {
        f"{p.parent.name}/{p.name}": p.read_bytes() for p in sorted((out / "pairs").glob("*/*"))
    }
    files["records"] = repr(Dataset(out).manifest["records"]).encode()
    return files


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("ref") / "ds"
    result = generate_dataset(SCENARIO, out, pairs=7, workers=1, stages=FAKE_STAGES, progress=False)
    assert result.pairs == 7 and result.new_records == 7
    return out


def test_records_follow_episode_slot_order(reference):
    ds = Dataset(reference, verify=True)
    idents = [(p.episode, p.slot) for p in ds]
    assert idents == [(0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (1, 2), (2, 0)]
    for pair in ds:
        assert len(pair.gt_pairs) >= 3
        assert len(pair.view1) > len(pair.gt_pairs) and len(pair.view2) > len(pair.gt_pairs)
    # pairs_per_snapshot = 2: the second record of an episode comes from the same snapshot.
    assert ds[0].time == ds[1].time and ds[1].time < ds[2].time
    assert ds.manifest["seeds"]["root"] == 11 and ds.manifest["complete"]
    assert sorted(ds.manifest["seeds"]["episodes"]) == ["0", "1", "2"]
    assert ds.manifest["scenario"]["text"] == SCENARIO.text


def test_worker_count_does_not_change_the_dataset(reference, tmp_path):
    out = tmp_path / "w2"
    generate_dataset(SCENARIO, out, pairs=7, workers=2, stages=FAKE_STAGES, progress=False)
    assert _tree(out) == _tree(reference)
    assert Dataset(out).checksum == Dataset(reference).checksum
    strip = ("git", "versions")  # the rest of the manifest is identical too
    m1, m2 = Dataset(out).manifest, Dataset(reference).manifest
    assert {k: v for k, v in m1.items() if k not in strip} == {
        k: v for k, v in m2.items() if k not in strip
    }


def test_same_seed_same_records_other_seed_other_records(reference, tmp_path):
    same = tmp_path / "same"
    generate_dataset(SCENARIO, same, pairs=3, workers=1, stages=FAKE_STAGES, progress=False)
    ref = _tree(reference)
    assert all(ref[k] == v for k, v in _tree(same).items() if k != "records")
    other = tmp_path / "other"
    generate_dataset(
        SCENARIO, other, pairs=3, seed=12, workers=1, stages=FAKE_STAGES, progress=False
    )
    assert Dataset(other).manifest["seeds"]["root_from"] == "--seed"
    assert Dataset(other).checksum != Dataset(same).checksum


def test_resume_after_injected_failure(reference, tmp_path, monkeypatch):
    out = tmp_path / "crash"
    monkeypatch.setattr(fakes, "FAIL_AT_TIME", 2.0)  # episode 0 dies after its first snapshot
    with pytest.raises(RuntimeError, match="injected failure"):
        generate_dataset(SCENARIO, out, pairs=7, workers=1, stages=FAKE_STAGES, progress=False)
    written = sorted(layout.existing_records(out))
    assert written == [(0, 0), (0, 1)]  # the snapshot's two pairs, complete
    with pytest.raises(ValueError, match="generation did not finish"):
        Dataset(out)
    monkeypatch.setattr(fakes, "FAIL_AT_TIME", None)
    result = generate_dataset(SCENARIO, out, pairs=7, workers=1, stages=FAKE_STAGES, progress=False)
    assert result.new_records == 5
    assert _tree(out) == _tree(reference)


def test_resume_after_killing_generate(reference, tmp_path):
    out = tmp_path / "killed"
    slow = "FakeScenario(sampling={'pairs_per_episode': 3, 'pairs_per_snapshot': 2})"
    code = (
        "from test_generate_fakes import *; from cadsim.generation.pipeline import generate_dataset; "
        f"generate_dataset({slow}, {str(out)!r}, pairs=7, workers=2, stages=FAKE_STAGES, progress=False)"
    )
    path = f"{TESTS}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"
    env = {**os.environ, "PYTHONPATH": path, "CADSIM_FAKE_DELAY_S": "0.15"}
    proc = subprocess.Popen([sys.executable, "-c", code], env=env, start_new_session=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)  # fmt: skip
    try:
        deadline = time.monotonic() + 60
        while len(layout.existing_records(out)) < 2:
            assert proc.poll() is None, proc.communicate()[1].decode()
            assert time.monotonic() < deadline, "no records after 60 s"
            time.sleep(0.02)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # main process and its workers, mid-way
        proc.wait()
    partial = layout.existing_records(out)
    assert 2 <= len(partial) < 7
    for path in partial.values():  # whatever exists is complete
        assert sorted(p.name for p in path.iterdir()) == sorted(layout.RECORD_FILES)
    generate_dataset(SCENARIO, out, pairs=7, workers=2, stages=FAKE_STAGES, progress=False)
    assert not [p for p in out.iterdir() if p.name.startswith(layout.TEMP_PREFIX)]
    assert _tree(out) == _tree(reference)
    Dataset(out, verify=True)


def test_growing_and_shrinking_a_dataset(reference, tmp_path):
    out = tmp_path / "grow"
    generate_dataset(SCENARIO, out, pairs=2, workers=1, stages=FAKE_STAGES, progress=False)
    result = generate_dataset(SCENARIO, out, pairs=7, workers=1, stages=FAKE_STAGES, progress=False)
    assert result.new_records == 5 and _tree(out) == _tree(reference)
    generate_dataset(SCENARIO, out, pairs=4, workers=1, stages=FAKE_STAGES, progress=False)
    assert len(Dataset(out)) == 4 and len(layout.existing_records(out)) == 4


def test_refuses_to_mix_configurations(reference, tmp_path):
    out = tmp_path / "mix"
    generate_dataset(SCENARIO, out, pairs=1, workers=1, stages=FAKE_STAGES, progress=False)
    with pytest.raises(GenerationError, match="different seed"):
        generate_dataset(
            SCENARIO, out, pairs=1, seed=99, workers=1, stages=FAKE_STAGES, progress=False
        )
    other = FakeScenario(text="# changed\n", sampling=SCENARIO.sampling)
    with pytest.raises(GenerationError, match="different scenario_sha256"):
        generate_dataset(other, out, pairs=1, workers=1, stages=FAKE_STAGES, progress=False)


def test_too_few_acceptable_pairs_is_an_error(tmp_path):
    short = FakeScenario(traffic={"source": "fake", "snapshots": 1})
    with pytest.raises(GenerationError, match="only 2 of 5 acceptable pairs in 2 episodes"):
        generate_dataset(short, tmp_path / "x", pairs=5, workers=1, stages=FAKE_STAGES,
                         progress=False, max_episodes=2)  # fmt: skip
