"""The sumo command line for a validated ``[traffic]`` table, confined to the run folder.

SUMO is never given a configuration file to read on its own: a ``.sumocfg``'s options are sorted
(:mod:`cadsim.sources.sumo.options`) and only allowlisted ones are passed, on the command line,
as ``--name=value`` with values checked against their types, its inputs resolved to absolute
paths. Every file SUMO loads — network, route and additional files — is loaded through the run
folder (:mod:`cadsim.sources.sumo.confinement`): outputs they declare are rewritten into
``run_dir/outputs``. Inputs stay where they are and are only read.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

from cadsim.sources.sumo.build import build_network
from cadsim.sources.sumo.config import read_sumocfg
from cadsim.sources.sumo.confinement import confined_files
from cadsim.sources.sumo.demand import write_demand
from cadsim.sources.sumo.options import sumo_time, sumocfg_options

log = logging.getLogger(__name__)

DEFAULT_STEP_LENGTH = 0.1  # seconds, for networks without a sumocfg


@dataclass(frozen=True)
class SumoRun:
    """The sumo arguments (without the binary name) and the network they simulate."""

    args: list[str]
    net: Path


def sumo_run(traffic: dict, seed: int, workdir: Path, run_dir: Path, end: float | None) -> SumoRun:
    """Build the net (cached in ``workdir``) and draw the demand (into ``run_dir``) if the scenario
    generates them, and assemble
    the arguments. ``run_dir``: this simulation's private folder for confined inputs and
    outputs. Raises ``OptionError``/``ConfinementError`` (ValueErrors) for a sumocfg option or an
    XML file that cannot be run confined (the scenario check refuses those first)."""
    run_dir.mkdir(parents=True, exist_ok=True)
    routes = [Path(p) for p in traffic["routes"]]
    additional = [Path(p) for p in traffic["additional"]]
    passed: dict[str, str] = {}
    own: dict[str, str] = {}
    if traffic["sumocfg"] is not None:
        cfg = read_sumocfg(traffic["sumocfg"])
        sorted_out = sumocfg_options(cfg.options)
        passed, own = sorted_out.passed, sorted_out.own
        if sorted_out.dropped:
            log.debug("%s: not passed to sumo: %s", cfg.path, ", ".join(sorted_out.dropped))
        net = cfg.net
        routes = [*cfg.routes, *routes]
        additional = [*cfg.additional, *additional]
    else:
        net = Path(traffic["net"]) if traffic["net"] else build_network(traffic["network"], workdir)
        if traffic["demand"] is not None:
            demand = write_demand(net, traffic["demand"], seed, run_dir)
            routes = [*demand.routes, *routes]
            additional = [*demand.additional, *additional]
    # Every file SUMO loads goes through the run folder, the network too: an actuated traffic
    # light's <param key="file"> or a detector in the net declares outputs like an additional.
    (confined_net,) = confined_files([Path(net)], run_dir, "net")
    args = ["-n", str(confined_net)]
    if routes:
        args += ["--route-files", ",".join(map(str, confined_files(routes, run_dir, "routes")))]
    if additional:
        linked = confined_files(additional, run_dir, "additional")
        args += ["--additional-files", ",".join(map(str, linked))]
    for name, value in passed.items():  # one argument each: a value can never become an option
        args.append(f"--{name}={value}")
    step = traffic["step_length"]
    if step is None and traffic["sumocfg"] is None:
        step = DEFAULT_STEP_LENGTH
    if step is not None:
        args += ["--step-length", f"{step:g}"]
    elif "step-length" in own:
        args.append(f"--step-length={own['step-length']}")
    if end is not None:  # the scenario's max_time counts from the config's begin (SUMO time)
        args += ["--end", f"{sumo_time(passed.get('begin', '0')) + end:.10g}"]
    elif "end" in own:
        args.append(f"--end={own['end']}")
    args += [
        *["--seed", str(int(seed) % 2**31), "--random", "false"],
        *["--no-step-log", "true", "--no-warnings", "true", "--verbose", "false"],
        *["--duration-log.disable", "true", "--duration-log.statistics", "false"],
        *["--ignore-route-errors", "true", "--xml-validation", "never"],
    ]
    return SumoRun(args=args, net=Path(net))
