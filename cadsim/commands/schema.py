"""`cadsim schema [--out FILE]`: the JSON Schema of scenario files (for editors: completion and
checking while writing a scenario), generated from the validator's own declarations."""

from __future__ import annotations

import argparse
import json

SCHEMA_MARKER = b'"title": "cadsim scenario file"'  # near the start of every schema written


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", help="write it to this file (default: print it)")


def run(args: argparse.Namespace) -> int:
    from cadsim.scenario_schema import scenario_json_schema

    text = json.dumps(scenario_json_schema(), indent=1, sort_keys=False) + "\n"
    if args.out:
        from cadsim.dataset.atomic_writer import write_file_atomic
        from cadsim.dataset.output_folder import check_output_file, file_holds

        # the output-path rule: a new file or a schema written before, never a user's file
        own = file_holds(SCHEMA_MARKER, 4096)
        path = check_output_file(args.out, "a scenario schema cadsim wrote", own)
        write_file_atomic(path, text.encode("utf-8"))
        print(args.out)
    else:
        print(text, end="")
    return 0
