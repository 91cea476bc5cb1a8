"""`make bench` section "pipeline": rendering speed and cold-start dataset generation (issue 3).

Renders run in a child process: the GL platform is fixed per process at the first OpenGL import,
and generation spawns its own worker processes anyway.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp

from eval.bench import Target

GENERATION_PAIRS = 50
GENERATION_LIMIT_S = 120.0  # issue 3: 50 CAD pairs in <= 2 minutes from a cold start
RENDER_TARGET_VIEWS_PER_S = 14.0  # stack notes: colour + depth + instance ids at 640x480


def _render_measure(_: object = None) -> dict:
    from eval.bench.render import measure

    return measure()


def pipeline_section(args: argparse.Namespace) -> list[Target]:
    """Views/s of render (+ noise + detection) at 640×480 and the wall time of generating 50 CAD
    pairs from cold with one worker per core."""
    from eval.bench.generation import format_report, measure_generation

    with mp.get_context("spawn").Pool(1) as pool:
        r = pool.apply(_render_measure)
    print(
        f"render ({r['backend']}, {r['objects']} objects, 640x480): "
        f"{r['render_views_per_s']:.1f} views/s render only, "
        f"{r['pipeline_views_per_s']:.1f} views/s with noise + detection, "
        f"{r['render_cpu_ms_per_view']:.0f} ms CPU per rendered view"
    )
    g = measure_generation(pairs=GENERATION_PAIRS)
    print(format_report(g))
    return [
        Target(
            "render views/s (colour + depth + ids, 640x480), as time per view",
            1.0 / r["render_views_per_s"],
            1.0 / RENDER_TARGET_VIEWS_PER_S,
        ),
        Target(
            f"generate {GENERATION_PAIRS} CAD pairs from cold", g["seconds"], GENERATION_LIMIT_S
        ),
    ]
