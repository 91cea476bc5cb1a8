"""Benchmarks (``make bench`` = ``python -m eval.bench``): they measure and print; nothing fails.

Sections run in order; ``--only NAME`` picks some. A section is a :class:`Section` in
:data:`SECTIONS`: a name, a one-line description and ``run(args) -> list[Target]`` that prints its
own table and returns the speed targets it checked (printed as PASS/FAIL at the end). Other parts
of the suite add theirs with :func:`register`, e.g. at the end of this module
``register(lazy_section("generation", "views/s, pairs/s", "eval.bench.generation:generation_section"))``.

Problems are random 3-D CoID-like scenes: n = m objects spread over 30 m, view 2 a rigidly moved
copy with 0.1 m noise, random non-negative features. Times are wall-clock seconds, the best of
``--repeat`` calls after one warm-up (one call when it takes longer than 2 s). The load average is
printed first: on a busy machine wall times grow with it.
"""

from __future__ import annotations

import argparse
import importlib
import os
import resource
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

SIZES = (10, 20, 40, 80)
SLOW_CALL_S = 2.0  # calls slower than this are not repeated

# pygmtools' RRWM defaults, in its own names and in ours (jump = its alpha: the weight of the
# reweighted jump). Our Sinkhorn runs to tolerance 1e-3 (cap 1000 sweeps) instead of 20 half-steps.
PYGM_RRWM_NATIVE = {"max_iter": 50, "sk_iter": 20, "alpha": 0.2, "beta": 30}
PYGM_RRWM = {"jump": 0.2, "beta": 30.0, "max_iter": 50}


@dataclass(frozen=True)
class Target:
    """A speed target: ``measured`` against ``limit`` (same unit), PASS when measured <= limit."""

    name: str
    measured: float
    limit: float
    unit: str = "s"

    @property
    def passed(self) -> bool:
        return self.measured <= self.limit

    def line(self) -> str:
        verdict = "PASS" if self.passed else "FAIL"
        return f"{verdict}  {self.name}: {self.measured:.4g} {self.unit} (target <= {self.limit:.4g} {self.unit})"


@dataclass(frozen=True)
class Section:
    name: str
    description: str
    run: Callable[[argparse.Namespace], list[Target]]


SECTIONS: list[Section] = []


def register(section: Section) -> Section:
    """Add a section (replacing one of the same name)."""
    SECTIONS[:] = [s for s in SECTIONS if s.name != section.name] + [section]
    return section


def lazy_section(name: str, description: str, target: str) -> Section:
    """A section whose ``run`` is ``"package.module:function"``, imported only when it runs (so a
    section with heavy dependencies costs nothing unless selected)."""
    module_name, _, function = target.partition(":")
    if not module_name or not function:
        raise ValueError(f"target: expected 'package.module:function', got {target!r}")

    def run(args: argparse.Namespace) -> list[Target]:
        return getattr(importlib.import_module(module_name), function)(args)

    return Section(name, description, run)


# --------------------------------------------------------------------------- helpers


def timed(fn: Callable[[], object], repeat: int) -> tuple[float, object]:
    """(best wall time in s, last result) of ``fn`` over ``repeat`` calls after a warm-up call.
    The minimum is the least disturbed by other load on the machine. A call slower than
    SLOW_CALL_S is timed once (its warm-up is the measurement)."""
    t0 = time.perf_counter()
    out = fn()
    best = time.perf_counter() - t0
    if best > SLOW_CALL_S or repeat <= 1:
        return best, out
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def bench_problem(n: int, m: int | None = None, seed: int = 0, dim: int = 3):
    """A random CoID-like :class:`matchers.Problem`: view 2 = rigid motion of view 1 + noise."""
    from scipy.spatial.transform import Rotation

    from matchers import Problem

    m = n if m is None else m
    rng = np.random.default_rng([seed, n, m, dim])
    world = rng.uniform(0.0, 30.0, (max(n, m), dim))
    p1 = world[:n]
    rot = Rotation.random(random_state=rng).as_matrix()[:dim, :dim]
    if dim == 2:
        angle = rng.uniform(0, 2 * np.pi)
        rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    p2 = world[rng.permutation(max(n, m))[:m]] @ rot.T + 0.1 * rng.standard_normal((m, dim))
    f = rng.gamma(1.0, 1.0, (max(n, m), 8))
    return Problem(p1, p2, f[:n], f[:m])


def _peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _row(cells: list[str]) -> str:
    return "| " + " | ".join(cells) + " |"


register(
    lazy_section(
        "tensor",
        "third-order tensor build time and size per n",
        "eval.bench.matchers:tensor_section",
    )
)
register(
    lazy_section("matchers", "time per matcher call per n", "eval.bench.matchers:matchers_section")
)
register(
    lazy_section(
        "targets",
        "the speed and memory targets (matchers at 20 v 20 and 100 v 100), PASS/FAIL",
        "eval.bench.matchers:targets_section",
    )
)
register(
    lazy_section(
        "scaling",
        "time and peak memory of every matcher against n (docs/figures/scaling.png)",
        "eval.bench.scaling:scaling_section",
    )
)
register(
    lazy_section(
        "pipeline",
        "render views/s and 50-pair CAD generation",
        "eval.bench.pipeline:pipeline_section",
    )
)
register(
    lazy_section(
        "generation",
        "core-seconds per camera pair, per LiDAR pair and per episode (cad-v2x, cad-v2x-lidar)",
        "eval.bench.generation:generation_section",
    )
)
register(
    lazy_section(
        "lidar",
        "LiDAR rays/s, a 64 x 1024 sweep, LiDAR pair vs camera pair",
        "eval.bench.lidar:lidar_section",
    )
)
register(
    lazy_section(
        "dair-import",
        "cadsim import dair-v2x of 10,000 generated DAIR-V2X-C frame pairs",
        "eval.bench.dair_import:dair_import_section",
    )
)
register(
    lazy_section(
        "scaleout",
        "noise sweep on the local pool vs a 2-worker Dask LocalCluster",
        "eval.bench.scaleout:scaleout_section",
    )
)


# --------------------------------------------------------------------------- CLI


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m eval.bench", description=__doc__.split("\n")[0]
    )
    parser.add_argument(
        "--only", nargs="+", metavar="NAME", help=f"sections to run: {[s.name for s in SECTIONS]}"
    )
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES), help="n = m values")
    parser.add_argument("--repeat", type=int, default=3, help="timed calls per measurement")
    parser.add_argument("--matchers", nargs="+", default=None, help="matchers (default: all)")
    args = parser.parse_args(argv)
    chosen = SECTIONS
    if args.only:
        unknown = set(args.only) - {s.name for s in SECTIONS}
        if unknown:
            parser.error(
                f"--only: unknown section(s) {sorted(unknown)}; have {[s.name for s in SECTIONS]}"
            )
        chosen = [s for s in SECTIONS if s.name in args.only]
    load = os.getloadavg()[0]
    cores = os.cpu_count() or 1
    print(
        f"load average {load:.1f} on {cores} cores"
        + (" (busy: timings inflated)" if load > cores else "")
    )
    targets: list[Target] = []
    for section in chosen:
        print(f"\n## {section.name}: {section.description}\n", flush=True)
        t0 = time.perf_counter()
        targets += section.run(args)
        print(f"\n({section.name}: {time.perf_counter() - t0:.1f} s)", flush=True)
    if targets:
        print("\n## targets\n")
        for t in targets:
            print(t.line())
    return 0
