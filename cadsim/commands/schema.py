"""`cadsim schema [--out FILE]`: the JSON Schema of scenario files (for editors: completion and
checking while writing a scenario), generated from the validator's own declarations."""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", help="write it to this file (default: print it)")


def run(args: argparse.Namespace) -> int:
    from cadsim.scenario_schema import scenario_json_schema

    text = json.dumps(scenario_json_schema(), indent=1, sort_keys=False) + "\n"
    if args.out:
        Path(args.out).write_text(text, encoding="utf-8")
        print(args.out)
    else:
        print(text, end="")
    return 0
