"""Issue 15 #9: worker processes of the local pool exit when their parent is killed with SIGKILL
(no chance to clean up), instead of running on as orphans."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

TESTS = Path(__file__).resolve().parent


def write_pid_and_sleep(path: str) -> None:
    """The task: record this worker's pid, then sleep far longer than the test waits."""
    Path(path).write_text(str(os.getpid()))
    time.sleep(600)


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return False
    return state != "Z"  # a zombie has exited


def test_pool_workers_exit_when_their_parent_is_sigkilled(tmp_path):
    pid_file = tmp_path / "worker.pid"
    code = (
        "import os, signal, time\n"
        "from cadsim.generation.local_executor import LocalProcessExecutor\n"
        "from test_worker_orphans import write_pid_and_sleep\n"
        "executor = LocalProcessExecutor(1)\n"
        f"executor.submit(write_pid_and_sleep, {str(pid_file)!r})\n"
        f"while not os.path.exists({str(pid_file)!r}): time.sleep(0.02)\n"
        "os.kill(os.getpid(), signal.SIGKILL)\n"
    )
    env = {**os.environ, "PYTHONPATH": f"{TESTS}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    parent = subprocess.run([sys.executable, "-c", code], env=env, timeout=120, cwd=TESTS.parent)
    assert parent.returncode == -signal.SIGKILL
    worker = int(pid_file.read_text())
    try:
        deadline = time.monotonic() + 60  # liveness bound, not a timing claim
        while _alive(worker) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not _alive(worker), "the worker outlived its SIGKILLed parent"
    finally:
        if _alive(worker):
            os.kill(worker, signal.SIGKILL)
