"""`cadsim` command line. Each subcommand lives in its own module and is imported only when run,
so `cadsim info` works without SUMO or pyrender installed.

A subcommand module exposes ``add_arguments(parser)`` and ``run(args) -> int``.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys

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
    "evaluate": ("eval.commands.evaluate", "run matchers on datasets (cached, parallel)"),
    "sweep-noise": (
        "eval.commands.sweep_noise",
        "re-detect at several depth-noise rates and evaluate",
    ),
    "table": ("eval.commands.table", "re-render tables and figures from cached results"),
    "synthetic": ("eval.synthetic", "published synthetic benchmarks (BCAGM protocols)"),
}


def _load(name: str):
    module, _ = COMMANDS[name]
    return importlib.import_module(module)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="cadsim", description=__doc__.splitlines()[0])
    parser.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, (_, help_text) in COMMANDS.items():
        p = sub.add_parser(name, help=help_text)
        p.set_defaults(_command=name)
        p.set_defaults(_needs_args=True)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    # First pass finds the subcommand; its module then adds its own arguments.
    known, _ = parser.parse_known_args(argv)
    module = _load(known._command)
    parser = build_parser()
    sub_action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    module.add_arguments(sub_action.choices[known._command])
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.DEBUG if args.verbose else logging.INFO,
        format="%(levelname)s %(name)s: %(message)s",
    )
    return int(module.run(args) or 0)


if __name__ == "__main__":
    sys.exit(main())
