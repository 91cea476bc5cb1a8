"""`cadsim import FORMAT SRC --out DIR`: external data written as a frame-pair dataset.

Formats (docs/external-data.md): ``dmgm`` (the DMGM CAD test pairs, ``proc_s/<id>/data.pt`` +
``proc_t/<id>/data.pt``), ``v2x-seq`` (V2X-Seq-SPD's cooperative frames), ``dair-v2x``
(DAIR-V2X-C's cooperative frame pairs), ``opv2v`` (the OPV2V family's
``scenario/<agent>/<frame>.yaml``), ``v2v4real`` (the same layout as V2V4Real encodes it) and
``tumtraf-v2x`` (TUMTraf-V2X's OpenLABEL labels), all but ``dmgm`` as box-only records. A
malformed input file is one error line naming the file (and key), exit status 2.
"""

from __future__ import annotations

import argparse
import sys


def _sequences(text: str) -> list[str]:
    items = [s.strip() for s in text.split(",") if s.strip()]
    if not items or not all(s.isdigit() for s in items):
        raise argparse.ArgumentTypeError(f"expected comma-separated sequence numbers, got {text!r}")
    return items


def _agents(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if not 2 <= value <= 12:
        raise argparse.ArgumentTypeError(f"expected an integer in 2..12, got {value}")
    return value


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
    seq = formats.add_parser(
        "v2x-seq",
        help="V2X-Seq-SPD cooperative frames (vehicle + roadside boxes, as sequences)",
        description="Write V2X-Seq-SPD's cooperative frames as box-only frame pairs.",
        epilog="examples:\n  cadsim import v2x-seq path/to/V2X-Seq-SPD --out data/v2x-seq\n"
        "  cadsim import v2x-seq path/to/V2X-Seq-SPD --out data/v2x-seq-0010 --sequences 0010",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    seq.add_argument("src", metavar="SRC", help="folder holding cooperative/, vehicle-side/, ...")
    seq.add_argument("--out", required=True, help="new (or empty) dataset folder")
    seq.add_argument(
        "--sequences",
        type=_sequences,
        default=None,
        help="only these cooperative sequences, e.g. 0010,0011 (default: all)",
    )
    seq.add_argument(
        "--offset-convention",
        choices=("roadside", "vehicle"),
        default="roadside",
        help="where system_error_offset applies: added to the roadside LiDAR -> world "
        "translation (default; DAIR-V2X's calib_i2v.py, OpenCOOD, CoAlign, HEAL) or in the "
        "vehicle LiDAR frame (label_i2v.py, UniV2X, CoopTrack)",
    )
    opv2v = formats.add_parser(
        "opv2v",
        help="OPV2V / V2XSet labels (scenario/<agent>/<frame>.yaml)",
        description="Write OPV2V-layout labels as box-only records (every frame's agents).",
        epilog="examples:\n  cadsim import opv2v path/to/OPV2V/test --out data/opv2v-test\n"
        "  cadsim import opv2v path/to/V2XSet/test --out data/v2xset-3 --agents 3",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _opv2v_arguments(opv2v)
    v2v4real = formats.add_parser(
        "v2v4real",
        help="V2V4Real labels as recorded (numpy-tagged yaml, ass_id links, right-handed poses)",
        description="Write V2V4Real's labels as box-only records: the OPV2V layout, yaml written "
        "by PyYAML from numpy values, objects linked across vehicles by ass_id.",
        epilog="examples:\n  cadsim import v2v4real path/to/V2V4Real/test --out data/v2v4real\n"
        "  cadsim import v2v4real path/to/V2V4Real/test --out data/v2v4real-noprior --no-prior",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _opv2v_arguments(v2v4real)
    _dair_arguments(formats)
    _tumtraf_arguments(formats)


def _tumtraf_arguments(formats) -> None:
    tum = formats.add_parser(
        "tumtraf-v2x",
        help="TUMTraf-V2X cooperative labels (ASAM OpenLABEL JSON; vehicle + infrastructure)",
        description="Write TUMTraf-V2X's OpenLABEL labels as box-only frame pairs: the vehicle's "
        "and the infrastructure's LiDAR boxes, linked by the object uids both sides share.",
        epilog="examples:\n  cadsim import tumtraf-v2x path/to/TUMTraf-V2X/test --out data/tumtraf\n"
        "  cadsim import tumtraf-v2x labels --out data/tumtraf --infrastructure-cs "
        "s110_lidar_ouster_north",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    tum.add_argument("src", metavar="SRC", help="folder holding the OpenLABEL .json files")
    tum.add_argument("--out", required=True, help="new (or empty) dataset folder")
    tum.add_argument(
        "--vehicle-cs",
        default="vehicle_lidar_robosense",
        help="the vehicle LiDAR's coordinate system (default: vehicle_lidar_robosense)",
    )
    tum.add_argument(
        "--infrastructure-cs",
        default="s110_lidar_ouster_south",
        help="the infrastructure LiDAR's coordinate system (default: s110_lidar_ouster_south)",
    )


def _opv2v_arguments(opv2v: argparse.ArgumentParser) -> None:
    opv2v.add_argument("src", metavar="SRC", help="a split folder or one scenario folder")
    opv2v.add_argument("--out", required=True, help="new (or empty) dataset folder")
    opv2v.add_argument(
        "--agents",
        type=_agents,
        default=None,
        help="views per record (default: the fewest agents of any frame)",
    )
    opv2v.add_argument(
        "--no-prior",
        action="store_true",
        help="ignore predicted_ego_pos (no stored prior; localisation presets draw one)",
    )
    opv2v.add_argument(
        "--prior-sigma",
        type=float,
        default=None,
        help="stated uncertainty of the stored prior, metres: overrides data_protocol.yaml's "
        "prior_sigma_m, with a warning (default: the file's, else 1.0)",
    )


def run(args: argparse.Namespace) -> int:
    if args.format in ("v2x-seq", "opv2v", "v2v4real", "dair-v2x", "tumtraf-v2x"):
        try:
            return _run_boxes(args)
        except KeyboardInterrupt:
            print(
                f"cadsim import: interrupted; no dataset was written to {args.out} (its partial "
                "records are removed). Run the same command again.",
                file=sys.stderr,
            )
            return 130
    from cadsim.importers.dmgm_dataset import import_dmgm

    result = import_dmgm(
        args.src, args.out, args.sequences, compact=args.compact, progress=not args.no_progress
    )
    per_sequence = ", ".join(f"{s}: {n}" for s, n in result.sequences.items())
    print(f"{result.out}: {result.pairs} pairs ({per_sequence}), checksum {result.checksum[:16]}")
    return 0


def _run_boxes(args: argparse.Namespace) -> int:
    if args.format == "v2x-seq":
        from cadsim.importers.v2x_seq import import_v2x_seq

        result = import_v2x_seq(args.src, args.out, args.sequences, args.offset_convention)
    elif args.format == "dair-v2x":
        from cadsim.importers.dair_v2x import import_dair_v2x

        result = import_dair_v2x(args.src, args.out, args.link_gate)
    elif args.format == "tumtraf-v2x":
        from cadsim.importers.tumtraf_v2x import import_tumtraf_v2x

        result = import_tumtraf_v2x(args.src, args.out, args.vehicle_cs, args.infrastructure_cs)
    else:
        from cadsim.importers.opv2v import import_opv2v

        result = import_opv2v(
            args.src, args.out, args.agents, not args.no_prior, args.prior_sigma,
            v2v4real=args.format == "v2v4real",
        )  # fmt: skip
    kind = "frame pairs" if result.views == 2 else f"{result.views}-view snapshots"
    print(
        f"{result.out}: {result.records} {kind} in {len(result.episodes)} episodes, box-only, "
        f"checksum {result.checksum[:16]}"
    )
    return 0


def _gate(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of metres, got {text!r}") from None
    if not 0 < value <= 10:
        raise argparse.ArgumentTypeError(f"expected metres in (0, 10], got {value}")
    return value


def _default_link_gate() -> float:
    """DAIR-V2X's default link gate, metres (read from its importer for the help text)."""
    from cadsim.importers.dair_v2x import LINK_GATE_M

    return float(LINK_GATE_M)


def _dair_arguments(formats) -> None:
    dair = formats.add_parser(
        "dair-v2x",
        help="DAIR-V2X-C cooperative frame pairs (vehicle + roadside labels, calibration)",
        description="Write DAIR-V2X-C's cooperative frames as box-only frame pairs; ground truth "
        "from the cooperative world boxes, else from the calibrated side boxes.",
        epilog="examples:\n  cadsim import dair-v2x path/to/cooperative-vehicle-infrastructure "
        "--out data/dair-v2x-c\n  cadsim import dair-v2x path/to/cooperative-vehicle-infrastructure "
        "--out data/dair-v2x-c-strict --link-gate 0.5",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    dair.add_argument("src", metavar="SRC", help="folder holding cooperative/, vehicle-side/, ...")
    dair.add_argument("--out", required=True, help="new (or empty) dataset folder")
    dair.add_argument(
        "--link-gate",
        type=_gate,
        default=None,
        help="largest centre distance (metres) of two boxes linked as one object "
        f"(default: {_default_link_gate():.1f} m)",
    )
