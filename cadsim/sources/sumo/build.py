"""Building a scenario's network (netgenerate) and random demand (randomTrips) at run time.

Everything is written under a cache folder (``workdir``), in a sub-folder named by a hash of the
inputs (parameters, input file contents, seed, SUMO version), so a second run with the same inputs
reuses it. A folder is built under a temporary name and renamed into place, so parallel workers
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
import sys
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cadsim.sources.sumo.install import binary, sumo_env, sumo_home, sumo_version
from cadsim.sources.sumo.options import check_netgenerate_args
from cadsim.sources.sumo.xml_files import parse_xml

log = logging.getLogger(__name__)

# Types SUMO defines without a file.
BUILTIN_TYPES = {"DEFAULT_VEHTYPE", "DEFAULT_PEDTYPE", "DEFAULT_BIKETYPE", "DEFAULT_CONTAINERTYPE"}


class ToolFailed(RuntimeError):
    """netgenerate or randomTrips exited with an error (its output's last lines say why)."""

    user_error = True  # a scenario's options or inputs, not a bug (cadsim.user_errors)


@dataclass(frozen=True)
class Demand:
    """Files of generated demand: route files for sumo ``-r`` and additional files (vTypes that
    route files refer to but do not contain) for sumo ``-a``."""

    routes: list[Path]
    additional: list[Path]


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


def build_demand(net: Path, demand: dict, seed: int, workdir: Path) -> Demand:
    """Random trips for motor vehicles, bicycles and pedestrians (randomTrips, seeded), routed
    with duarouter; pedestrians walk from/to edges routed by sumo at departure."""
    vtypes = Path(demand["vtypes"])
    key = content_hash(
        {
            "net": file_hash(net),
            "vtypes": file_hash(vtypes),
            "demand": {k: v for k, v in demand.items() if k != "vtypes"},
            "seed": seed,
            "sumo": sumo_version(),
        }
    )
    seeds = [int(s) % 2**31 for s in np.random.SeedSequence(seed).generate_state(3)]
    common = ["-n", str(net), "-e", str(demand["end"]), "--fringe-factor", "max"]
    jobs: dict[str, list[str]] = {
        "vehicles": [
            *common,
            *["-p", str(demand["vehicle_period"]), "--seed", str(seeds[0]), "--prefix", "veh"],
            *["--validate", "--additional-files", str(vtypes)],
            "--trip-attributes",
            f'type="{demand["vehicle_type"]}" departLane="best" departSpeed="max"',
        ],
    }
    if demand["bicycle_period"] > 0:
        jobs["bicycles"] = [
            *common,
            *["-p", str(demand["bicycle_period"]), "--seed", str(seeds[1]), "--prefix", "bike"],
            *["--validate", "--vclass", "bicycle", "--additional-files", str(vtypes)],
            "--trip-attributes",
            f'type="{demand["bicycle_type"]}" departLane="best"',
        ]
    if demand["person_period"] > 0:
        jobs["persons"] = [
            *common,
            *["-p", str(demand["person_period"]), "--seed", str(seeds[2]), "--prefix", "ped"],
            "--pedestrians",
            "--trip-attributes",
            f'type="{demand["person_type"]}"',
        ]

    def build(tmp: Path) -> None:
        tool = sumo_home() / "tools" / "randomTrips.py"
        procs = {}
        for name, args in jobs.items():
            out = ["-o", str(tmp / f"{name}.trips.xml")]
            if name != "persons":
                out += ["-r", str(tmp / f"{name}.rou.xml")]
            procs[name] = subprocess.Popen(
                [sys.executable, str(tool), *args, *out],
                cwd=tmp,
                env=sumo_env(),
                stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT,
                text=True,
            )
        for name, proc in procs.items():
            output, _ = proc.communicate()
            if proc.returncode != 0:
                raise ToolFailed(f"randomTrips ({name}) failed: {_tail(output)}")
        write_person_types(vtypes, tmp / "persons.add.xml")

    folder = cached_folder(Path(workdir) / f"demand-{key}", build)
    routes = [folder / f"{n}.rou.xml" for n in ("vehicles", "bicycles") if n in jobs]
    if "persons" in jobs:
        routes.append(folder / "persons.trips.xml")
    return Demand(routes=routes, additional=[folder / "persons.add.xml"])


def write_person_types(vtypes: Path, out: Path) -> None:
    """Copy the pedestrian vTypes and vTypeDistributions of ``vtypes`` into ``out``.

    duarouter copies only the vTypes that routed vehicles use into its route files; pedestrian
    trips are left to sumo, so their types must be loaded separately (and loading the vehicle
    types twice is an error in sumo)."""
    root = parse_xml(vtypes).getroot()
    types = {e.get("id"): e for e in root if e.tag == "vType"}
    pedestrian = {i for i, e in types.items() if e.get("vClass") == "pedestrian"}
    keep = [e for i, e in types.items() if i in pedestrian]
    for dist in (e for e in root if e.tag == "vTypeDistribution"):
        members = [c for c in dist if c.tag == "vType"]
        refs = (dist.get("vTypes") or "").split()
        if (
            (members or refs)
            and all(c.get("vClass") == "pedestrian" for c in members)
            and all(r in pedestrian for r in refs)
        ):
            keep.append(dist)
    out_root = ET.Element("additional")
    out_root.extend(keep)
    ET.ElementTree(out_root).write(out, encoding="unicode")


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
