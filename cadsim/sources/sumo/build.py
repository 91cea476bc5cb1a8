"""Building a scenario's network (netgenerate) at run time (its random demand:
:mod:`cadsim.sources.sumo.demand`, in process).

The network is written under a cache folder (``workdir``), in a sub-folder named by a hash of the
inputs (parameters, SUMO version), so a second run with the same inputs reuses it. A folder is built under a temporary name and renamed into place, so parallel workers
that build the same folder at once never see a half-written one. The SUMO binaries and tools are
those of the installed eclipse-sumo wheel.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import shutil
import subprocess
import tempfile
from collections.abc import Callable
from pathlib import Path

from cadsim.sources.sumo.install import binary, sumo_env, sumo_version
from cadsim.sources.sumo.options import check_netgenerate_args

log = logging.getLogger(__name__)

# Types SUMO defines without a file.
BUILTIN_TYPES = {"DEFAULT_VEHTYPE", "DEFAULT_PEDTYPE", "DEFAULT_BIKETYPE", "DEFAULT_CONTAINERTYPE"}


class ToolFailed(RuntimeError):
    """netgenerate failed (its output's last lines say why), or a demand cannot be drawn."""

    user_error = True  # a scenario's options or inputs, not a bug (cadsim.user_errors)


def build_network(params: dict, workdir: Path) -> Path:
    """Run netgenerate for a validated ``[traffic.network]`` table; return the .net.xml path."""
    args = netgenerate_args(params)
    key = content_hash({"netgenerate": args, "sumo": sumo_version()})
    folder = cached_folder(
        Path(workdir) / f"net-{key}",
        lambda tmp: _run([str(binary("netgenerate")), *args, "-o", str(tmp / "net.net.xml")], tmp),
    )
    return folder / "net.net.xml"


def netgenerate_args(params: dict) -> list[str]:
    """netgenerate options for a grid of ``junctions``² junctions with ``arm_length`` roads
    attached at the boundary (junctions = 1: a single four-arm intersection), then the
    scenario's ``extra_args`` (allowlisted: :func:`cadsim.sources.sumo.options.check_netgenerate_args`)."""
    n = params["junctions"]
    args = [
        "--grid",
        f"--grid.number={n}",
        f"--grid.length={params['block_length']}",
        f"--grid.attach-length={params['arm_length']}",
        f"--default.lanenumber={params['lanes']}",
        f"--default.speed={params['speed']}",
        "--no-turnarounds=true",
    ]
    if params["traffic_lights"]:
        inner = [f"{chr(ord('A') + i)}{j}" for i in range(n) for j in range(n)]
        args.append("--tls.set=" + ",".join(inner))
    if params["sidewalks"]:
        args += [
            "--sidewalks.guess=true",
            # Sidewalks are guessed only up to this speed (default 13.89 m/s).
            f"--sidewalks.guess.max-speed={max(params['speed'] + 1.0, 13.89)}",
            f"--default.sidewalk-width={params['sidewalk_width']}",
        ]
    if params["crossings"] and params["sidewalks"]:
        args.append("--crossings.guess=true")
    extra = list(params["extra_args"])
    check_netgenerate_args(extra)  # the scenario check refuses these first; never run them
    return args + extra


def cached_folder(target: Path, build: Callable[[Path], None]) -> Path:
    """``target`` if it exists, else build it in a temporary sibling and rename it into place."""
    if target.is_dir():
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}-"))
    try:
        build(tmp)
        try:
            os.rename(tmp, target)
            log.info("built %s", target)
        except OSError:
            if not target.is_dir():
                raise
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return target


def content_hash(obj: object) -> str:
    return hashlib.sha256(json.dumps(obj, sort_keys=True).encode()).hexdigest()[:16]


def file_hash(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _run(cmd: list[str], cwd: Path) -> None:
    """Run a SUMO tool in ``cwd`` (a folder inside the work folder); ``ToolFailed`` if it fails."""
    proc = subprocess.run(
        cmd, cwd=cwd, env=sumo_env(), capture_output=True, text=True, stdin=subprocess.DEVNULL
    )
    if proc.returncode != 0:
        raise ToolFailed(f"{Path(cmd[0]).name} failed: {_tail(proc.stdout + proc.stderr)}")


def _tail(output: str, lines: int = 3) -> str:
    """The last non-empty lines of a tool's output, on one line."""
    kept = [line.strip() for line in output.splitlines() if line.strip()][-lines:]
    return " | ".join(kept) or "(no output)"
