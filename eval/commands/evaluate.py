"""``cadsim evaluate DATASET_DIR... --matchers all --runs 4 --out DIR``: calibrate τ on each
dataset's validation dataset, run every matcher on the test dataset with several seeds (cached,
parallel), and write per-pair metrics, AP, PR curves, Table I and the qualitative-figure input.

Each test dataset DIR is paired with a validation dataset from other simulation seeds: ``--val``
(same order), else ``DIR-val`` when it exists. ``--tune`` first picks each matcher's parameters
from its declared grid on the validation dataset (:mod:`eval.protocol.tuning`); Table I is then the tuned
one and the untuned one is written beside it (``table1_untuned``). ``--protocol paper`` runs the
matchers as the paper describes them instead (image-space pairwise terms, full Hungarian
assignment, no τ, no tuning; ``table1_paper_protocol``, :mod:`eval.protocol.variants`).
``--protocol equal_cues`` hands every one of the paper's matchers the same cues (metric geometry
and appearance, :mod:`eval.protocol.cues`; ``table1_equal_cues``).
``--no-calibration`` reports the full Hungarian assignment (τ = none) under the calibrated
protocol's matcher options.
"""

from __future__ import annotations

import argparse

from cadsim.cli import int_in
from cadsim.limits import MAX_RUNS, MAX_WORKERS
from eval.core.cache import ResultCache
from eval.core.executor import add_scheduler_argument, make_executor
from eval.core.result_files import check_outputs
from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec
from eval.engine.matcher_list import parse_matchers
from eval.engine.protocol_run import evaluate
from eval.engine.splits import open_entry, val_dirs
from eval.protocol.model_options import with_model
from eval.protocol.variants import PROTOCOLS
from eval.report.tables import PAPER_CSV, write_tables
from matchers.core.jit import cache_root
from matchers.core.plugin_guard import DEFAULT_TIME_LIMIT_S, TIME_LIMIT_ENV, parse_time_limit

# the learned matchers that `--matchers all` gains with --model (the prior one must be named)
LEARNED_PLAIN = ("learned", "maximin_learned", "rrwm_learned")


def add_runner_arguments(parser: argparse.ArgumentParser) -> None:
    """Options every cached, parallel command shares."""
    parser.add_argument("--matchers", default="all", help="'all' or a comma list (default: all)")
    parser.add_argument(
        "--runs",
        type=int_in(1, MAX_RUNS),
        default=4,
        help=f"runs with seeds 0..RUNS-1, RUNS in 1..{MAX_RUNS} (default 4)",
    )
    parser.add_argument(
        "--out",
        required=True,
        help="output directory (required: no command writes results where you did not say; "
        "the committed results/ are make reproduce's)",
    )
    parser.add_argument(
        "--cache",
        default=str(cache_root() / "runs"),
        help="result cache (default: $CADSIM_CACHE_DIR/runs, else ~/.cache/cadsim/runs)",
    )
    parser.add_argument(
        "--workers",
        type=int_in(1, MAX_WORKERS),
        default=None,
        help=f"processes, 1..{MAX_WORKERS} (default: one per core)",
    )
    parser.add_argument(
        "--no-progress", action="store_true", help="no progress bar (none when not a terminal)"
    )
    parser.add_argument(
        "--plugin-time-limit",
        type=_seconds,
        default=None,
        metavar="SECONDS",
        help="seconds a plug-in matcher or fusion (not a built-in) may take on one problem "
        f"before the run stops naming it (default: ${TIME_LIMIT_ENV}, else "
        f"{DEFAULT_TIME_LIMIT_S:g})",
    )
    add_scheduler_argument(parser)


def _seconds(text: str) -> float:
    """argparse type of ``--plugin-time-limit``: a positive number of seconds."""
    try:
        return parse_time_limit(text, "--plugin-time-limit")
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc).split(": ", 1)[1]) from None


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("datasets", nargs="+", metavar="DATASET_DIR", help="test datasets")
    parser.add_argument(
        "--val",
        nargs="+",
        metavar="DIR",
        help="validation datasets, same order (default: each DATASET_DIR-val, when it exists)",
    )
    parser.add_argument(
        "--no-calibration", action="store_true", help="report full assignments (no τ)"
    )
    parser.add_argument(
        "--tune",
        action="store_true",
        help="pick each matcher's parameters from its grid on the validation datasets first",
    )
    parser.add_argument(
        "--protocol",
        choices=PROTOCOLS,
        default="calibrated",
        help="calibrated (default: τ from validation, each matcher with its published cues), "
        "equal_cues (every paper matcher handed metric geometry and appearance; "
        "table1_equal_cues) or paper (image-space pairwise terms, full assignment, no tuning)",
    )
    parser.add_argument(
        "--paper-table", default=str(PAPER_CSV), help="the paper's Table I (CSV) shown beside ours"
    )
    parser.add_argument(
        "--label",
        nargs="+",
        metavar="NAME",
        help="a title per dataset, same order (default: from its scenario's name)",
    )
    parser.add_argument(
        "--model",
        metavar="MODEL",
        help="model file of the learned matchers (cadsim train); refused when it was trained on "
        "a record of a test dataset. With --matchers all, the learned matchers join",
    )
    parser.add_argument(
        "--reference",
        default=None,
        metavar="NAME",
        help="the matcher every other is compared with in paired_differences.csv (NAME − each "
        "other, with its 95 %% interval over episodes); one of --matchers (default: maximin, "
        "when evaluated)",
    )
    parser.add_argument(
        "--pose-metrics",
        choices=("cadsim", "v2x-reg"),
        default="cadsim",
        help="cadsim (default: Table I's pose columns, success@(1 m, 2°) and (2 m, 5°), median "
        "RTE/RRE) or v2x-reg: also V2X-Reg++'s registration table (registration.csv/.md): "
        "success@1/2/3 m (RTE < λ m and RRE < λ°, over all frames, a frame without a pose a "
        "failure), mRTE/mRRE over the frames successful at λ, seconds per frame",
    )
    parser.add_argument(
        "--frames",
        metavar="JSON",
        default=None,
        help="with --pose-metrics v2x-reg: only the frame pairs of a V2X-Reg++ frame list (their "
        "JSON: cooperative data_info entries, e.g. data_info_top3000.json)",
    )
    parser.add_argument(
        "--top-k",
        type=int_in(1, 1000),
        default=None,
        metavar="K",
        help="with --pose-metrics v2x-reg: the v2x_reg matcher keeps each view's top K boxes as "
        "V2X-Reg++ selects them (bus, truck, car first, then by volume; within 120 m)",
    )
    add_localisation_argument(parser)
    add_runner_arguments(parser)


def reference_matcher(text: str, matchers) -> str:
    """``--reference``: the row label (``MatcherSpec.label``; `matchers`: specs or {label: spec})
    of the one of `matchers` named by
    `text` (its name or label, case-insensitive, as --matchers reads names); ValueError naming
    the option otherwise."""
    named = dict(matchers) if isinstance(matchers, dict) else {m.label: m for m in matchers}
    names = list(named)
    by_lower = {m.name.lower(): label for label, m in named.items()}
    by_lower |= {n.lower(): n for n in names}
    name = by_lower.get(text.strip().lower())
    if name is None:
        raise ValueError(
            f"--reference: {text!r} is not one of the matchers evaluated ({', '.join(names)}); "
            "add it to --matchers"
        )
    return name


def add_localisation_argument(parser: argparse.ArgumentParser) -> None:
    """``--localisation PRESET``: every record's prior re-drawn by a GNSS-like preset (a preset
    spec: a name, optionally ``*SCALE`` and ``+LATENCYms``)."""
    from cadsim.sensing.gnss_error import PRESETS

    parser.add_argument(
        "--localisation",
        type=_preset_spec,
        default=None,
        metavar="PRESET",
        help="re-draw every record's localisation prior with a GNSS-like preset: "
        + ", ".join(PRESETS)
        + " (denied: no prior), optionally scaled and with another message latency, e.g. "
        "gnss-urban*2+300ms (docs/localisation.md). Default: the records' own",
    )


def _preset_spec(text: str) -> str:
    """argparse type of ``--localisation``: the spec itself, once it parses."""
    from cadsim.sensing.gnss_error import parse_spec

    try:
        parse_spec(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def run(args: argparse.Namespace) -> int:
    registration = getattr(args, "pose_metrics", "cadsim") == "v2x-reg"
    if not registration and (args.frames is not None or args.top_k is not None):
        raise ValueError("--frames and --top-k: expected with --pose-metrics v2x-reg")
    if args.frames is not None:
        from eval.core.registration_metrics import read_frame_list

        read_frame_list(args.frames)  # refused before anything runs
    check_outputs(args.out, args.cache)
    paper = args.protocol == "paper"
    no_val = (args.no_calibration or paper) and not args.tune
    vals = [None] * len(args.datasets) if no_val else val_dirs(args.datasets, args.val)
    labels = args.label or [None] * len(args.datasets)
    if len(labels) != len(args.datasets):
        raise ValueError(f"--label: {len(labels)} names for {len(args.datasets)} datasets")
    entries = [
        open_entry(d, v, name, args.localisation)
        for d, v, name in zip(args.datasets, vals, labels, strict=True)
    ]
    matchers = parse_matchers(args.matchers)
    if args.model and args.matchers.strip() == "all":
        matchers += [MatcherSpec(n) for n in LEARNED_PLAIN]
    matchers = with_model(matchers, args.model, [e.test_dir for e in entries])
    if args.top_k is not None:
        matchers = [
            MatcherSpec.of(m.name, **dict(m.options), top_k=args.top_k)
            if m.name == "v2x_reg"
            else m
            for m in matchers
        ]
    reference = None if args.reference is None else reference_matcher(args.reference, matchers)
    with make_executor(args.workers, args.scheduler) as executor:
        runner = Runner(
            ResultCache(args.cache),
            executor,
            progress=not args.no_progress,
            plugin_time_limit_s=args.plugin_time_limit,
        )
        evaluate(
            entries,
            matchers,
            range(args.runs),
            runner,
            args.out,
            calibrate=not args.no_calibration,
            tune=args.tune,
            protocol=args.protocol,
        )
    markdown = write_tables(args.out, args.paper_table, reference)
    from eval.report.figures import render_all

    render_all(args.out)
    print(markdown)
    if registration:
        from eval.report.registration_table import write_registration

        tests = {e.label: e.test_dir for e in entries}
        print(write_registration(args.out, tests, args.frames))
    return 0
