"""Issue 15 #5 and #6: a failed ``generate`` does not block its own ``--out``, and a second
``generate`` on the same ``--out`` stops at once, naming the run that holds it, without touching
that run's unfinished records."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
import test_generate_fakes as fakes
from test_generate_fakes import FAKE_STAGES, FakeScenario

from cadsim.dataset import Dataset, layout
from cadsim.dataset.writer_lock import DatasetBusy, exclusive_writer
from cadsim.generation.pipeline import GenerationError, generate_dataset

TESTS = Path(__file__).resolve().parent
SCENARIO = FakeScenario(sampling={"pairs_per_episode": 3, "pairs_per_snapshot": 2})


def _generate(scenario, out, **kw):
    kw = {"workers": 1, **kw}
    return generate_dataset(scenario, out, stages=FAKE_STAGES, progress=False, **kw)


def test_bad_arguments_are_refused_before_out_is_touched(tmp_path):
    out = tmp_path / "never"
    for kw, words in (({"seed": -1}, "--seed"), ({"pairs": 0}, "--pairs"), ({"workers": 0}, "--workers")):  # fmt: skip
        with pytest.raises(GenerationError, match=words):
            _generate(SCENARIO, out, **kw)
    assert not out.exists()


def test_a_run_that_wrote_no_record_does_not_block_its_folder(tmp_path, monkeypatch):
    out = tmp_path / "typo"
    monkeypatch.setattr(fakes, "FAIL_AT_TIME", 0.0)  # fails before its first record
    with pytest.raises(RuntimeError, match="injected failure"):
        _generate(SCENARIO, out, pairs=3)
    assert (out / layout.MANIFEST).is_file() and not layout.existing_records(out)
    monkeypatch.setattr(fakes, "FAIL_AT_TIME", None)
    fixed = FakeScenario(text="# the typo, fixed\n", sampling=SCENARIO.sampling)
    result = _generate(fixed, out, pairs=3, seed=5)  # another scenario and seed: accepted
    assert result.pairs == 3
    ds = Dataset(out, verify=True)
    assert ds.manifest["seeds"]["root"] == 5
    assert ds.manifest["scenario"]["text"] == fixed.text
    # Once it holds records, the folder is that dataset's: another configuration is refused.
    with pytest.raises(GenerationError, match="different"):
        _generate(SCENARIO, out, pairs=3)


def test_a_second_writer_is_refused_and_told_who_holds_the_folder(tmp_path):
    out = tmp_path / "busy"
    code = (
        "from test_generate_fakes import *; from cadsim.generation.pipeline import generate_dataset; "
        f"generate_dataset({SCENARIO!r}, {str(out)!r}, pairs=6, workers=1, stages=FAKE_STAGES, "
        "progress=False)"
    )
    env = {**os.environ, "PYTHONPATH": f"{TESTS}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    env["CADSIM_FAKE_DELAY_S"] = "0.5"
    proc = subprocess.Popen([sys.executable, "-c", code], env=env, start_new_session=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)  # fmt: skip
    try:
        deadline = time.monotonic() + 60
        while not (out / layout.MANIFEST).is_file():
            assert proc.poll() is None, proc.communicate()[1].decode()
            assert time.monotonic() < deadline, "the first run did not start within 60 s"
            time.sleep(0.02)
        marker = out / f"{layout.TEMP_PREFIX}e00000_s03-{proc.pid}-0123abcd"
        marker.mkdir()  # stands for its unfinished records
        with pytest.raises(DatasetBusy) as exc:
            _generate(SCENARIO, out, pairs=6)
        message = str(exc.value)
        assert f"pid {proc.pid} on {socket.gethostname()}, started " in message
        assert str(out) in message and "--out" in message
        assert marker.is_dir()  # the refused run deleted nothing
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    # The kernel released the dead run's lock: the same folder resumes.
    marker.rmdir()
    assert _generate(SCENARIO, out, pairs=6).pairs == 6


def test_lock_file_records_the_holder(tmp_path):
    with exclusive_writer(tmp_path):
        info = json.loads((tmp_path / layout.LOCK_FILE).read_text())
        assert info["pid"] == os.getpid() and info["host"] == socket.gethostname()
        with pytest.raises(DatasetBusy, match=f"pid {os.getpid()}"), exclusive_writer(tmp_path):
            pass
        assert (tmp_path / layout.LOCK_FILE).is_file()  # the refused writer removed nothing
    assert not (tmp_path / layout.LOCK_FILE).exists()  # the holder cleans up after itself
    with exclusive_writer(tmp_path):  # released on leaving the block
        pass


def test_a_finished_dataset_holds_no_lock_file(tmp_path):
    out = tmp_path / "done"
    assert _generate(SCENARIO, out, pairs=3).pairs == 3
    assert not (out / layout.LOCK_FILE).exists()
