"""`make bench` sections "tensor", "matchers" and "targets": matcher speed on random CoID-like
problems (see :func:`eval.bench.bench_problem`)."""

from __future__ import annotations

import argparse

from eval.bench import (
    PYGM_RRWM,
    PYGM_RRWM_NATIVE,
    Target,
    _peak_rss_mb,
    _row,
    bench_problem,
    timed,
)


def tensor_section(args: argparse.Namespace) -> list[Target]:
    from matchers.hypergraph.tensor_build import build_tensor

    print(_row(["n = m", "recipe", "entries", "MB stored", "build s", "peak RSS MB"]))
    print("|---|---|---|---|---|---|")
    for n in args.sizes:
        problem = bench_problem(n)
        for recipe in ("paper", "duchenne"):
            secs, tensor = timed(lambda p=problem, r=recipe: build_tensor(p, r, 0), args.repeat)
            mb = (tensor.indices.nbytes + tensor.values.nbytes) / 2**20
            print(
                _row(
                    [
                        str(n),
                        recipe,
                        f"{tensor.nnz:,}",
                        f"{mb:.1f}",
                        f"{secs:.4f}",
                        f"{_peak_rss_mb():.0f}",
                    ]
                ),
                flush=True,
            )
    return []


def matchers_section(args: argparse.Namespace) -> list[Target]:
    from eval.validation.matcher_options import HYPERGRAPH_MATCHERS
    from matchers import get, usable
    from matchers.hypergraph.tensor_build import build_tensor

    names = args.matchers or usable()
    print(_row(["n = m", "tensor build s", *[f"{name} s" for name in names]]))
    print("|" + "---|" * (2 + len(names)))
    for n in args.sizes:
        problem = bench_problem(n)
        build_s, tensor = timed(lambda p=problem: build_tensor(p, "paper", 0), 1)
        cells = [str(n), f"{build_s:.4f}"]
        for name in names:
            opts = {"tensor": tensor} if name in HYPERGRAPH_MATCHERS else {}
            matcher = get(name)
            secs, _ = timed(lambda f=matcher, p=problem, o=opts: f(p, seed=0, **o), args.repeat)
            cells.append(f"{secs:.4f}")
        print(_row(cells), flush=True)
        del tensor
    print("\n(hypergraph matchers timed on the prebuilt 'paper' tensor; add the build column)")
    return []


def targets_section(args: argparse.Namespace) -> list[Target]:
    """The speed and memory targets (20 vs 20 build + maximin: 10 ms and 0.15 x pygmtools' RRWM;
    our RRWM against pygmtools'; 100 vs 100: 1.5 s and 600 MB), PASS/FAIL. The 100 vs
    100 points run each in a fresh process (:func:`eval.bench.scaling.run_point`), so that
    their peak RSS is their own."""
    import pygmtools as pygm

    from eval.bench.scaling import run_point
    from matchers import get
    from matchers.blocks.pairwise import pairwise_affinity
    from matchers.core.indexing import to_column_major

    pygm.set_backend("numpy")
    targets = []
    problem = bench_problem(20)
    maximin_s, _ = timed(lambda: get("maximin")(problem, seed=0), max(args.repeat, 5))
    targets.append(Target("tensor build + maximin, 20 vs 20 (paper tensor)", maximin_s, 0.010))
    for n in (20, 40):
        p = bench_problem(n)
        k_ours = pairwise_affinity(p)
        k_pygm = to_column_major(k_ours, n, n)
        ours_s, _ = timed(
            lambda k=k_ours, p=p: get("rrwm")(p, seed=0, affinity=k, **PYGM_RRWM), args.repeat
        )
        pygm_s, _ = timed(lambda k=k_pygm, n=n: pygm.rrwm(k, n, n, **PYGM_RRWM_NATIVE), args.repeat)
        if n == 20:
            targets.append(
                Target(
                    "tensor build + maximin / pygmtools rrwm, 20 vs 20",
                    maximin_s / pygm_s,
                    0.15,
                    "x",
                )
            )
        targets.append(
            Target(
                f"our rrwm / pygmtools rrwm, same {n}x{n} matrix and settings",
                ours_s / pygm_s,
                1.0,
                "x",
            )
        )
        print(f"rrwm {n} vs {n}: ours {ours_s * 1e3:.1f} ms, pygmtools {pygm_s * 1e3:.1f} ms")
    for name in ("maximin", "rrwhm", "sm", "rrwm", "mos"):
        point = run_point(name, 100, timeout_s=120)
        if name in ("maximin", "rrwhm"):
            secs = point["time_s"] if point["time_s"] is not None else float("inf")
            targets.append(Target(f"{name}, 100 vs 100, tensor build included", secs, 1.5))
        peak = point["peak_mb"] if point["peak_mb"] is not None else float("inf")
        targets.append(Target(f"{name}, 100 vs 100, peak RSS of its process", peak, 600, "MB"))
    return targets
