"""`cadsim export FORMAT DATASET --out DIR`: a cadsim dataset in the field's layouts.

Formats (docs/external-data.md): ``opv2v`` (``scenario/<agent>/<frame>.yaml`` with poses and
boxes, images beside them; ``cadsim import opv2v`` reads it back) and ``kitti`` (15-column
object labels per view, camera coordinates). The output folder must be new or empty.
"""

from __future__ import annotations

import argparse


def add_arguments(parser: argparse.ArgumentParser) -> None:
    formats = parser.add_subparsers(dest="format", required=True, metavar="FORMAT")
    for name, what, example in (
        ("opv2v", "the OPV2V layout (yaml per agent per frame, images beside it)", "cad-v2x-opv2v"),
        ("kitti", "KITTI object labels per view (15 columns, camera coordinates)", "cad-v2x-kitti"),
    ):
        sub = formats.add_parser(
            name,
            help=what,
            description=f"Write a dataset as {what}.",
            epilog=f"examples:\n  cadsim export {name} data/cad-v2x --out export/{example}",
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        sub.add_argument("dataset", metavar="DATASET", help="a cadsim dataset folder")
        sub.add_argument("--out", required=True, help="new (or empty) output folder")


def run(args: argparse.Namespace) -> int:
    if args.format == "opv2v":
        from cadsim.exporters.opv2v import export_opv2v as export
    else:
        from cadsim.exporters.kitti import export_kitti as export
    result = export(args.dataset, args.out)
    print(
        f"{result.out}: {result.scenarios} {'scenarios' if args.format == 'opv2v' else 'records'}, {result.files} files"
    )
    return 0
