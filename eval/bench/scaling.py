"""How the matchers scale with the number of objects, and what the tensor cap costs in accuracy.

``python -m eval.bench.scaling`` times every matcher (tensor or affinity build included) and
pygmtools' RRWM on n vs n objects (n = 10 ... 100, the CoID-like problems of
:func:`eval.bench.bench_problem`), each point in a fresh process so that its peak resident memory
(``ru_maxrss``) is its own, and draws ``docs/figures/scaling.png`` (log-log: seconds and MB
against n). It is a benchmark output, not a ``make reproduce`` result.

``python -m eval.bench.scaling --cap-accuracy`` runs every hypergraph matcher with and without
the default tensor cap (``max_tensor_entries``) where the cap binds: the outlier protocol of
:mod:`eval.validation.synthetic` with 20 inliers (the published 10 give view 1 only 120
triangles, too few for the cap to bind) and 50 and 100 outliers (``--both-views``: in each view)
and the synthetic CoID
benchmark of :mod:`eval.validation.coid_synthetic` scaled to 40-60 objects per view, and prints
the markdown table kept in docs/matchers.md. Both tensors of a problem come from the same seed.

``python -m eval.bench.scaling --per-pair`` prints each matcher's CPU time per CAD-sized pair.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

SIZES = (10, 20, 40, 60, 80, 100)
MATCHERS = ("appearance", "sm", "rrwm", "mos", "tm", "hgm", "bcagm", "rrwhm", "maximin")
PYGM = "pygmtools rrwm"
FIGURE = Path("docs/figures/scaling.png")
HYPERGRAPH = ("tm", "hgm", "bcagm", "rrwhm", "mos", "maximin")


# --------------------------------------------------------------------------- one point


def _call(name: str):
    """``problem -> None`` running matcher ``name`` (tensor or affinity built inside)."""
    if name != PYGM:
        from matchers import get

        matcher = get(name)
        return lambda problem: matcher(problem, seed=0)
    import pygmtools as pygm

    from eval.bench import PYGM_RRWM_NATIVE
    from matchers.blocks.pairwise import pairwise_affinity
    from matchers.core.indexing import to_column_major

    pygm.set_backend("numpy")

    def call(problem):
        n = problem.n1
        pygm.rrwm(to_column_major(pairwise_affinity(problem), n, n), n, n, **PYGM_RRWM_NATIVE)

    return call


def measure_point(name: str, n: int) -> dict:
    """Wall time (s) of matcher ``name`` on the n vs n bench problem — the best of 3 calls, or
    one call when it takes over a second, after a warm-up call on 6 vs 6 objects — and this
    process's peak RSS (MB) afterwards."""
    from eval.bench import bench_problem

    call = _call(name)
    call(bench_problem(6))
    problem = bench_problem(n)
    best = np.inf
    for _ in range(3):
        started = time.perf_counter()
        call(problem)
        best = min(best, time.perf_counter() - started)
        if best > 1.0:
            break
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return {"matcher": name, "n": n, "time_s": best, "peak_mb": peak}


def run_point(name: str, n: int, timeout_s: float) -> dict:
    """:func:`measure_point` in a fresh interpreter; time/memory None if it failed or timed out."""
    cmd = [sys.executable, "-m", "eval.bench.scaling", "--point", name, str(n)]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout_s, check=True)
        return json.loads(done.stdout.strip().splitlines()[-1])
    except (subprocess.SubprocessError, ValueError, IndexError) as err:
        print(f"  {name} n={n}: no measurement ({type(err).__name__})", file=sys.stderr)
        return {"matcher": name, "n": n, "time_s": None, "peak_mb": None}


def draw(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for name in [*MATCHERS, PYGM]:
        pts = [r for r in rows if r["matcher"] == name and r["time_s"] is not None]
        if not pts:
            continue
        style = {"linestyle": "--", "color": "black"} if name == PYGM else {}
        ns = [r["n"] for r in pts]
        axes[0].plot(ns, [r["time_s"] for r in pts], marker="o", ms=3, label=name, **style)
        axes[1].plot(ns, [r["peak_mb"] for r in pts], marker="o", ms=3, label=name, **style)
    for ax, label in zip(axes, ("seconds per call", "peak RSS of the process, MB"), strict=True):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("objects per view (n vs n)")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
    axes[1].legend(fontsize=8, ncol=2)
    fig.suptitle("Matcher scaling (defaults: tensor cap 250,000 entries, 500 affinity partners)")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)


def scaling(sizes: tuple[int, ...], matchers: list[str], out: Path, timeout_s: float) -> list:
    rows = []
    print("| matcher | " + " | ".join(f"n={n}" for n in sizes) + " |")
    print("|---|" + "---|" * len(sizes))
    for name in matchers:
        cells = []
        for n in sizes:
            row = run_point(name, n, timeout_s)
            rows.append(row)
            cells.append(
                "—" if row["time_s"] is None else f"{row['time_s']:.3g} s, {row['peak_mb']:.0f} MB"
            )
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)
    draw(rows, out)
    print(f"\nwrote {out}")
    return rows


def scaling_section(args) -> list:
    """``make bench`` section "scaling": every matcher's time and peak memory against n, and the
    figure; it checks no target (the targets are in the "targets" section)."""
    scaling(tuple(SIZES), [*MATCHERS, PYGM], FIGURE, 600.0)
    return []


# --------------------------------------------------------------------------- cap accuracy


def _outlier_problems(inliers: int, outliers: int, both: bool, trials: int, seed: int):
    """The outlier protocol of :mod:`eval.validation.synthetic` (sigma 0.03, scale 1.5) with
    ``inliers`` inliers (published: 10, where view 1's 120 triangles times k stay under the cap
    even at 200 outliers) and ``outliers`` in view 2, or in each view when ``both``. Inliers are
    view 1's first rows; ``truth`` gives their partners."""
    from eval.validation.point_sets import make_point_sets
    from matchers import Problem

    for t in range(trials):
        rng = np.random.default_rng([seed, 5021, inliers, outliers, int(both), t])
        ps = make_point_sets(rng, inliers, outliers, sigma=0.03, scale=1.5)
        extra = rng.standard_normal((outliers if both else 0, 2))
        points1 = np.concatenate([ps.points1, extra])
        yield Problem(points1, ps.points2), ps.truth, int(rng.integers(2**31))


def _coid_problems(frames: int, seed: int):
    from eval.validation.coid_synthetic import SceneConfig, make_frame_pair
    from matchers import Problem

    cfg = SceneConfig(covisible=(20, 30), distractors=(20, 30))  # 40-60 objects per view
    for k in range(frames):
        fp = make_frame_pair(np.random.default_rng([seed, 4711, k]), cfg)
        yield Problem(fp.points1, fp.points2, fp.features1, fp.features2), fp.truth, k


def _score(kind: str, pairs: np.ndarray, truth: np.ndarray, n1: int, n2: int) -> float:
    if kind == "outliers":
        from eval.validation.synthetic import accuracy

        return accuracy(pairs, truth)
    from eval.protocol.metrics import pair_metrics

    return float(pair_metrics(pairs, truth, n1, n2).f1)


def cap_accuracy(
    inliers: int,
    outliers: list[int],
    both: bool,
    trials: int,
    frames: int,
    seed: int,
    caps: list[int | None],
) -> None:
    """Accuracy (F1 for CoID, full Hungarian assignment, no threshold) of every hypergraph
    matcher on the same problems with each tensor cap in ``caps`` (None: uncapped)."""
    from matchers import build_tensor, get

    suites = [
        *[
            (
                "outliers",
                f"{inliers} inliers + {k} outliers" + (" in each view" if both else ""),
                "duchenne",
                list(_outlier_problems(inliers, k, both, trials, seed)),
            )
            for k in outliers
        ],
        *(
            [("coid", "CoID 40-60 objects", "paper", list(_coid_problems(frames, seed)))]
            * (frames > 0)
        ),
    ]
    names = " / ".join("uncapped" if c is None else f"{c:,}" for c in caps)
    print("| problems | " + " | ".join(HYPERGRAPH) + f" | entries ({names}) |")
    print("|---|" + "---|" * (len(HYPERGRAPH) + 1))
    for kind, label, recipe, problems in suites:
        scores = {(name, cap): [] for name in HYPERGRAPH for cap in caps}
        sizes = {cap: [] for cap in caps}
        for problem, truth, mseed in problems:
            for cap in caps:
                tensor = build_tensor(
                    problem, recipe, np.random.default_rng(mseed), max_entries=cap
                )
                sizes[cap].append(tensor.nnz)
                for name in HYPERGRAPH:
                    m = get(name)(problem, seed=mseed, tensor=tensor)
                    scores[name, cap].append(_score(kind, m.pairs, truth, problem.n1, problem.n2))
        cells = [" / ".join(f"{np.mean(scores[name, c]):.3f}" for c in caps) for name in HYPERGRAPH]
        size = " / ".join(f"{np.mean(sizes[c]):,.0f}" for c in caps)
        print(f"| {label} ({len(problems)}) | " + " | ".join(cells) + f" | {size} |", flush=True)
    print(f"\ncells: {names} (mean over the problems in brackets)")


# --------------------------------------------------------------------------- CAD-sized pairs


def per_pair(matchers: list[str], pairs: int, passes: int) -> None:
    """CPU milliseconds per CAD-sized frame pair of every matcher (the minimum over ``passes``
    passes over ``pairs`` synthetic CoID pairs with 3-6 covisible objects and 10-13 distractors
    per view, 14-19 objects per view as in the CAD dataset). CPU time, not wall time: on a
    shared machine it is the steadier measure. The ``matchers`` package imported is whichever
    comes first on sys.path, so a ``PYTHONPATH`` holding another ``matchers/`` times that one."""
    import matchers as package
    from eval.validation.coid_synthetic import SceneConfig, make_frame_pair
    from matchers import Problem, get

    cfg = SceneConfig(covisible=(3, 6), distractors=(10, 13))
    frames = [make_frame_pair(np.random.default_rng([5, k]), cfg) for k in range(pairs)]
    problems = [Problem(f.points1, f.points2, f.features1, f.features2) for f in frames]
    cells = []
    for name in matchers:
        best = np.inf
        for _ in range(passes):
            started = time.process_time()
            for problem in problems:
                get(name)(problem, seed=0)
            best = min(best, (time.process_time() - started) / len(problems))
        cells.append(f"{name} {best * 1e3:.1f}")
    print(f"{Path(package.__file__).parent}: CPU ms per pair: " + " | ".join(cells))


# --------------------------------------------------------------------------- CLI


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m eval.bench.scaling", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES), help="n values")
    parser.add_argument("--matchers", nargs="+", default=[*MATCHERS, PYGM], help="what to time")
    parser.add_argument("--out", type=Path, default=FIGURE, help="figure path")
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds per point")
    parser.add_argument("--point", nargs=2, metavar=("MATCHER", "N"), help=argparse.SUPPRESS)
    parser.add_argument("--cap-accuracy", action="store_true", help="the cap's accuracy table")
    parser.add_argument("--per-pair", action="store_true", help="CPU ms per CAD-sized pair")
    parser.add_argument("--pairs", type=int, default=12, help="pairs for --per-pair")
    parser.add_argument("--inliers", type=int, default=20, help="outlier protocol inliers")
    parser.add_argument("--outliers", type=int, nargs="*", default=[50, 100], help="outliers")
    parser.add_argument(
        "--caps", nargs="+", help="tensor caps to compare (default: the default cap and none)"
    )
    parser.add_argument("--both-views", action="store_true", help="outliers in each view")
    parser.add_argument("--trials", type=int, default=3, help="outlier trials per setting")
    parser.add_argument("--frames", type=int, default=3, help="CoID frame pairs")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    if args.point:
        print(json.dumps(measure_point(args.point[0], int(args.point[1]))))
    elif args.per_pair:
        names = [m for m in args.matchers if m != PYGM]
        per_pair(names, args.pairs, 3)
    elif args.cap_accuracy:
        from matchers.hypergraph.tensor_build import MAX_ENTRIES

        caps = [None if c == "none" else int(c) for c in args.caps or [MAX_ENTRIES, "none"]]
        cap_accuracy(
            args.inliers, args.outliers, args.both_views, args.trials, args.frames, args.seed, caps
        )
    else:
        scaling(tuple(args.sizes), args.matchers, args.out, args.timeout)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
