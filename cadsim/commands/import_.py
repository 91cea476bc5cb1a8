"""`cadsim import FORMAT SRC --out DIR`: external data written as a frame-pair dataset.

Formats: ``dmgm`` (the DMGM CAD test pairs, ``proc_s/<id>/data.pt`` + ``proc_t/<id>/data.pt``;
docs/external-data.md). A malformed input file is one error line naming the file.
"""

from __future__ import annotations

import argparse


def _sequences(text: str) -> list[str]:
    items = [s.strip() for s in text.split(",") if s.strip()]
    if not items or not all(s.isdigit() for s in items):
        raise argparse.ArgumentTypeError(f"expected comma-separated sequence numbers, got {text!r}")
    return items


def add_arguments(parser: argparse.ArgumentParser) -> None:
    formats = parser.add_subparsers(dest="format", required=True, metavar="FORMAT")
    dmgm = formats.add_parser(
        "dmgm",
        help="DMGM CAD test pairs (proc_s/ + proc_t/ of data.pt)",
        description="Write the DMGM CAD test pairs (proc_s/ + proc_t/ of data.pt) as a dataset.",
        epilog="examples:\n  cadsim import dmgm path/to/DMGM/data/cad/test --out data/dmgm\n"
        "  cadsim import dmgm path/to/DMGM/data/cad/test --out data/dmgm-069 --sequences 069",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    dmgm.add_argument("src", metavar="SRC", help="folder holding proc_s/ and proc_t/")
    dmgm.add_argument("--out", required=True, help="new (or empty) dataset folder")
    dmgm.add_argument(
        "--sequences",
        type=_sequences,
        default=None,
        help="only these driving sequences, e.g. 069,071 (default: all)",
    )
    dmgm.add_argument(
        "--compact",
        action="store_true",
        help="store features as uint8 with a per-view scale (about 4x smaller)",
    )
    dmgm.add_argument("--no-progress", action="store_true", help="no progress bar")


def run(args: argparse.Namespace) -> int:
    from cadsim.importers.dmgm_dataset import import_dmgm

    result = import_dmgm(
        args.src, args.out, args.sequences, compact=args.compact, progress=not args.no_progress
    )
    per_sequence = ", ".join(f"{s}: {n}" for s, n in result.sequences.items())
    print(f"{result.out}: {result.pairs} pairs ({per_sequence}), checksum {result.checksum[:16]}")
    return 0
