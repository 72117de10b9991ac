"""The ``hexapod`` entry point: one parser, sub-commands from the modules of this package."""

from __future__ import annotations

import argparse
import sys

from .. import __version__
from ..exceptions import HexapodError, SolverError
from . import core, evaluate, fixture, reproduce, serve, track, view

EXIT_CODES = {0: "all good", 1: "some rows or the solve failed", 2: "usage error or unreadable input"}
COMMANDS = (core, reproduce, evaluate, track, view, serve, fixture)

DESCRIPTION = """\
Leg readings <-> platform pose for Stewart-Gough hexapods with offset-axis Cardan joints.

HEXAPOD arguments are a preset name (see `hexapod urdf --list-presets`), a URDF file or a
geometry file (.toml, .yaml, .json); every sub-command accepts the three.
"""
EPILOG = "exit codes: " + "; ".join(f"{k} {v}" for k, v in EXIT_CODES.items())


def build_parser() -> argparse.ArgumentParser:
    """The ``hexapod`` parser with every sub-command."""
    parser = argparse.ArgumentParser(
        prog="hexapod", description=DESCRIPTION, epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--version", action="version", version=f"hexapod_model {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in COMMANDS:
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run ``hexapod`` with ``argv`` (default: ``sys.argv[1:]``); returns the exit code."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except SolverError as exc:
        print(f"hexapod {args.command}: error: {exc}", file=sys.stderr)
        return 1
    except HexapodError as exc:
        print(f"hexapod {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"hexapod {args.command}: interrupted", file=sys.stderr)
        return 130
