"""The sumo command line for a validated ``[traffic]`` table.

Inputs stay where they are. Outputs never land in the scenario's folder: output options of a
sumocfg are redirected into the run folder, and additional files are passed through symbolic
links in the run folder, because SUMO resolves an additional file's relative output paths (e.g.
``<edgeData file="...">``) against the folder the additional file was loaded from.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from cadsim.sources.sumo.build import build_demand, build_network
from cadsim.sources.sumo.config import read_sumocfg

DEFAULT_STEP_LENGTH = 0.1  # seconds, for networks without a sumocfg


@dataclass(frozen=True)
class SumoRun:
    """The sumo arguments (without the binary name) and the network they simulate."""

    args: list[str]
    net: Path


def sumo_run(traffic: dict, seed: int, workdir: Path, run_dir: Path, end: float | None) -> SumoRun:
    """Build the net/demand if the scenario generates them (cached in ``workdir``) and assemble
    the arguments. ``run_dir``: this simulation's private folder for links and outputs."""
    run_dir.mkdir(parents=True, exist_ok=True)
    args: list[str] = []
    routes = [Path(p) for p in traffic["routes"]]
    additional = [Path(p) for p in traffic["additional"]]
    if traffic["sumocfg"] is not None:
        cfg = read_sumocfg(traffic["sumocfg"])
        net = cfg.net
        args += ["-c", str(cfg.path)]
        if routes:
            routes = [*cfg.routes, *routes]
        additional = [*cfg.additional, *additional]
        out_dir = run_dir / "outputs"
        out_dir.mkdir(exist_ok=True)
        for name, value in sorted(cfg.outputs.items()):
            args += [f"--{name}", str(out_dir / Path(value).name)]
    else:
        net = Path(traffic["net"]) if traffic["net"] else build_network(traffic["network"], workdir)
        args += ["-n", str(net)]
        if traffic["demand"] is not None:
            demand = build_demand(net, traffic["demand"], seed, workdir)
            routes = [*demand.routes, *routes]
            additional = [*demand.additional, *additional]
    if routes:
        args += ["--route-files", ",".join(str(p) for p in routes)]
    if additional:
        args += ["--additional-files", ",".join(str(p) for p in _linked(additional, run_dir))]
    step = traffic["step_length"]
    if step is None and traffic["sumocfg"] is None:
        step = DEFAULT_STEP_LENGTH
    if step is not None:
        args += ["--step-length", f"{step:g}"]
    if end is not None:
        args += ["--end", f"{end:g}"]
    args += [
        *["--seed", str(int(seed) % 2**31), "--random", "false"],
        *["--no-step-log", "true", "--no-warnings", "true", "--verbose", "false"],
        *["--duration-log.disable", "true", "--duration-log.statistics", "false"],
        *["--ignore-route-errors", "true", "--xml-validation", "never"],
    ]
    return SumoRun(args=args, net=Path(net))


def _linked(files: list[Path], run_dir: Path) -> list[Path]:
    """A symbolic link per file, each in its own sub-folder of ``run_dir``/additional."""
    out = []
    for k, target in enumerate(files):
        folder = run_dir / "additional" / str(k)
        folder.mkdir(parents=True, exist_ok=True)
        link = folder / target.name
        if link.is_symlink() or link.exists():
            link.unlink()
        link.symlink_to(target.resolve())
        out.append(link)
    return out
