"""``hexapod mjcf``: the hexapod as MJCF, loop closures included (MuJoCo, Pinocchio's MJCF parser)."""

from __future__ import annotations

import argparse
import sys

from ..description.mjcf import geometry_to_mjcf, urdf_to_mjcf
from ..description.mjcf_loader import MJCF_SUFFIXES, load_mjcf_text
from ..exceptions import InputError
from ..files import atomic_write_text, check_output_path
from ._common import add_hexapod_argument, hexapod_of, note


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``mjcf``."""
    p = sub.add_parser(
        "mjcf",
        help="write the MJCF (MuJoCo) file of a hexapod, loop closures included",
        description=(
            "Write the MJCF of a preset, URDF or geometry file: the URDF tree (same joint names, axes, limits; "
            "the platform on a free joint), the six loop closures as weld/connect equalities, the visuals, and "
            "with --actuated one position actuator per leg reading. MuJoCo reads it, so does Pinocchio's MJCF "
            "parser and every hexapod sub-command (see docs/mjcf.md)."
        ),
    )
    add_hexapod_argument(p)
    p.add_argument("-o", "--output", metavar="FILE.xml", help="output file (default: standard output)")
    p.add_argument(
        "--actuated", action="store_true", help="add a position actuator on each measured joint (ctrl = reading, m)"
    )
    p.set_defaults(func=cmd_mjcf)


def cmd_mjcf(args: argparse.Namespace) -> int:
    """``hexapod mjcf``."""
    if args.output:
        if not args.output.lower().endswith(MJCF_SUFFIXES):
            raise InputError("output", args.output, f"name an MJCF file ending in {' or '.join(MJCF_SUFFIXES)}")
        check_output_path(args.output, args.hexapod)
    hexa = hexapod_of(args)
    urdf_xml = hexa.closed_loop.urdf_xml
    if urdf_xml is None:
        raise InputError("HEXAPOD", args.hexapod, "is an MJCF file already; give a preset, URDF or geometry file")
    if hexa.geometry is not None:  # a preset or geometry file: its cones and min_clearance go in the file too
        text = geometry_to_mjcf(hexa.geometry, actuated=args.actuated)
    else:
        text = urdf_to_mjcf(urdf_xml, actuated=args.actuated, source=str(args.hexapod))
    load_mjcf_text(text, "the generated MJCF")  # refuse to write a file that does not load and assemble
    if args.output:
        atomic_write_text(args.output, text)
        what = ", with position actuators" if args.actuated else ""
        note("mjcf", f"wrote {args.output} ({hexa.closed_loop.kind} closures{what})")
    else:
        sys.stdout.write(text)
    return 0
