"""`cadsim` command line. Each subcommand lives in its own module and is imported only when run,
so `cadsim info` works without SUMO or pyrender installed.

A subcommand module exposes ``add_arguments(parser)`` and ``run(args) -> int``. Errors are
reported here, once: a user error (:mod:`cadsim.user_errors`) as one line ``cadsim CMD: error:
...`` naming the file (and key), exit status 2; a bug with its traceback. ``--debug`` shows the
traceback of every error.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import sys

from cadsim.user_errors import is_user_error, one_line

DEBUG_HELP = "show the traceback of every error (user errors too)"

# name -> (module, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "generate": (
        "cadsim.commands.generate",
        "simulate, render and detect: write a frame-pair dataset",
    ),
    "info": (
        "cadsim.commands.info",
        "summarise a dataset (objects, covisibility, classes, depths)",
    ),
    "show": ("cadsim.commands.show", "draw one frame pair with boxes and ground-truth lines"),
    "schema": ("cadsim.commands.schema", "print the JSON Schema of scenario files"),
    "import": (
        "cadsim.commands.import_",
        "write external data (DMGM, V2X-Seq, OPV2V/V2XSet, V2V4Real, DAIR-V2X) as a dataset",
    ),
    "export": ("cadsim.commands.export", "write a dataset in the OPV2V layout or as KITTI labels"),
    "train": ("cadsim.commands.train", "train the learned matchers on training datasets"),
    "evaluate": ("eval.commands.evaluate", "run matchers on datasets (cached, parallel)"),
    "sweep-noise": (
        "eval.commands.sweep_noise",
        "re-detect at several depth-noise rates and evaluate",
    ),
    "sweep-regime": (
        "eval.commands.sweep_regime",
        "thin non-covisible detections level by level and evaluate",
    ),
    "sweep-localisation": (
        "eval.commands.sweep_localisation",
        "re-draw the localisation prior at several position errors and evaluate",
    ),
    "table": ("eval.commands.table", "re-render tables and figures from cached results"),
    "synthetic": ("eval.validation.synthetic", "published synthetic benchmarks (BCAGM protocols)"),
}


# name -> examples shown under `cadsim NAME --help` (kept here: the modules load only when run)
COMMAND_EXAMPLES: dict[str, tuple[str, ...]] = {
    "generate": (
        "cadsim generate scenarios/cad-intersection.toml --pairs 3 --out data/mini",
        "cadsim generate scenarios/cad-intersection.toml --pairs 50 --seed 7 --workers 2 --out data/cad",
    ),
    "info": ("cadsim info data/cad", "cadsim info data/cad --json > cad-info.json"),
    "show": (
        "cadsim show data/cad --pair 0 --out pair0.png",
        "cadsim show data/cad-v2x-seq --sequence 2 --frame 9 --out seq2-frame9.png",
        "cadsim show eval/data/dmgm-cad/val-070 --pair 5 --no-labels --out dmgm5.png",
    ),
    "schema": ("cadsim schema", "cadsim schema --out scenario.schema.json"),
    "import": (
        "cadsim import dmgm path/to/DMGM/data/cad/test --out data/dmgm --sequences 069,071",
        "cadsim import v2x-seq path/to/V2X-Seq-SPD --out data/v2x-seq",
        "cadsim import opv2v path/to/OPV2V/test --out data/opv2v-test",
        "cadsim import v2v4real path/to/V2V4Real/test --out data/v2v4real-test",
        "cadsim import dair-v2x path/to/cooperative-vehicle-infrastructure --out data/dair-v2x-c",
    ),
    "export": (
        "cadsim export opv2v data/cad-v2x --out export/cad-v2x-opv2v",
        "cadsim export kitti data/cad-v2x --out export/cad-v2x-kitti",
    ),
    "train": (
        "cadsim train data/cad-train data/cad-v2x-train --out my-model.json",
        "cadsim train eval/data/dmgm-cad/val-070 --variants learned --out dmgm070.json",
    ),
    "evaluate": (
        "cadsim evaluate data/cad --val data/cad-val --matchers sm,maximin --runs 1 --out my-run",
        "cadsim evaluate data/cad --matchers learned,maximin_learned --model my-model.json --out l",
        "cadsim evaluate data/cad data/mrc --val data/cad-val data/mrc-val --tune --out my-tuned",
        "cadsim evaluate data/cad --no-calibration --matchers my_pkg.matcher:match --out mine",
        "cadsim evaluate data/cad --matchers pose,maximin_pose --localisation gnss-urban --out urban",
    ),
    "sweep-noise": (
        "cadsim sweep-noise data/cad --rates 0,0.002,0.005 --matchers sm,maximin --out noise",
    ),
    "sweep-regime": ("cadsim sweep-regime data/cad-dense --keep 1,0.5,0 --out regime",),
    "sweep-localisation": (
        "cadsim sweep-localisation data/cad --sigmas 0,1.2,2.5,5 --matchers pose,maximin_pose "
        "--out localisation",
        "cadsim sweep-localisation data/cad-v2x --preset gnss-urban --scales 0,1,3 "
        "--latencies 0,300 --out localisation",
    ),
    "table": (
        "cadsim table results",
        "cadsim table my-run --paper-table eval/data/paper-table1.csv",
    ),
    "synthetic": (
        "cadsim synthetic --protocol deformation --matchers tm,rrwhm,maximin",
        "cadsim synthetic --protocol house --house-n1 20 --workers 2 --out house",
    ),
}


def command_epilog(name: str) -> str | None:
    """The "examples:" block under ``cadsim NAME --help`` (None for a command without any)."""
    if name not in COMMAND_EXAMPLES:
        return None
    lines = "\n".join(f"  {line}" for line in COMMAND_EXAMPLES[name])
    return f"examples:\n{lines}"


def int_in(low: int, high: int):
    """An argparse ``type``: an integer in [low, high]; anything else is a usage error naming the
    option (``argument --workers: expected an integer in 1..1024, got 0``)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected an integer in {low}..{high}, got {value}")
        return value

    parse.__name__ = "integer"
    return parse


def _load(name: str):
    module, _ = COMMANDS[name]
    return importlib.import_module(module)


DESCRIPTION = """\
cadsim: simulate observers of one scene, detect the objects each sees, and score the
matchers that decide which object in one view is which in the other."""
EXAMPLES = """examples:
  cadsim generate scenarios/cad-intersection.toml --pairs 3 --out data/cad
  cadsim info data/cad
  cadsim evaluate data/cad --val data/cad-val --matchers sm,maximin --runs 1 --out my-run
  cadsim show data/cad --pair 0 --out pair0.png

`cadsim COMMAND --help` describes each command; docs/README.md indexes the documentation."""


def version() -> str:
    """The installed cadsim's version (the project's, from its metadata)."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as package_version

    try:
        return package_version("cadsim")
    except PackageNotFoundError:  # run from a source tree that was never installed
        return "unknown (not installed)"


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="cadsim",
        description=DESCRIPTION,
        epilog=EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"cadsim {version()}")
    parser.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    parser.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, (_, help_text) in COMMANDS.items():
        p = sub.add_parser(
            name,
            help=help_text,
            description=help_text[0].upper() + help_text[1:] + ".",
            epilog=command_epilog(name),
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        p.set_defaults(_command=name)
        # Also after the command; SUPPRESS keeps a `--debug` given before it.
        p.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=DEBUG_HELP)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    # The subcommand's module adds its own arguments before parsing, so `cadsim X --help` lists them.
    name = next((a for a in argv if not a.startswith("-")), None)
    if name in COMMANDS:
        sub_action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        _load(name).add_arguments(sub_action.choices[name])
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.DEBUG if args.verbose else logging.INFO,
        format="%(levelname)s %(name)s: %(message)s",
    )
    try:
        return int(_load(args._command).run(args) or 0)
    except BrokenPipeError:  # output piped into `head` and the like
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - keep Python's exit flush quiet
        return 0
    except Exception as exc:
        if args.debug or not is_user_error(exc):
            raise  # a bug (or --debug): the traceback is what a report needs
        print(f"cadsim {args._command}: error: {one_line(exc)}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
