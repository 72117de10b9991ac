"""The ``hexapod`` entry point: one parser, sub-commands from the modules of this package."""

from __future__ import annotations

import argparse
import contextlib
import importlib
import logging
import os
import sys
import warnings
from collections.abc import Iterator

from .. import __version__
from ..exceptions import CompileWarning, HexapodError, SolverError
from ..kinematics.newton.first_compile import LOGGER as COMPILE_LOGGER

EXIT_CODES = {
    0: "all good",
    1: "some rows or the solve failed",
    2: "usage error or unreadable input",
    130: "interrupted (Ctrl-C)",
    141: "standard output closed early (e.g. piped into head)",
}
MODULES = (
    "core",
    "mjcf",
    "reproduce",
    "calibrate",
    "evaluate",
    "track",
    "view",
    "serve",
    "fixture",
    "statics",
    "sweep",
    "changeover_plan",
    "clearance",
)
#: the module registering each sub-command: ``hexapod fk`` imports ``core`` only, not the studies'
#: scipy, matplotlib or meshcat (tests/cli check this table against the modules)
OWNER = {"urdf": "core", "fk": "core", "ik": "core", "bench": "core", "mjcf": "mjcf", "reproduce": "reproduce"}
OWNER |= {"calibrate": "calibrate", "evaluate": "evaluate", "track": "track", "view": "view", "snapshot": "view"}
OWNER |= {"serve": "serve", "simulate-encoders": "serve", "fixture": "fixture", "statics": "statics", "sweep": "sweep"}
OWNER |= {"changeover": "changeover_plan"}
OWNER |= {"clearance": "clearance"}

DESCRIPTION = """\
Leg readings <-> platform pose for Stewart-Gough hexapods with offset-axis Cardan joints.

HEXAPOD arguments are a preset name (see `hexapod urdf --list-presets`), a URDF file, a
geometry file (.toml, .yaml, .json) or an MJCF file (.xml, `hexapod mjcf`); every sub-command
accepts the four.
"""
EPILOG = "exit codes: " + "; ".join(f"{k} {v}" for k, v in EXIT_CODES.items())


class _Formatter(argparse.RawDescriptionHelpFormatter):
    """``hexapod --help`` with one line per sub-command (argparse wraps long names otherwise)."""

    def __init__(self, prog: str):
        super().__init__(prog, max_help_position=24, width=110)

    def add_argument(self, action: argparse.Action) -> None:
        super().add_argument(action)
        if isinstance(action, argparse._SubParsersAction):
            for sub in action._get_subactions():
                self._action_max_length = max(self._action_max_length, len(sub.metavar or sub.dest) + 8)


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``hexapod`` parser: with every sub-command, or only those of the module owning ``command``."""
    parser = argparse.ArgumentParser(prog="hexapod", description=DESCRIPTION, epilog=EPILOG, formatter_class=_Formatter)
    parser.add_argument("--version", action="version", version=f"hexapod_model {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in (OWNER[command],) if command in OWNER else MODULES:
        importlib.import_module(f"{__package__}.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run ``hexapod`` with ``argv`` (default: ``sys.argv[1:]``); returns the exit code."""
    argv = sys.argv[1:] if argv is None else argv
    args = build_parser(argv[0] if argv else None).parse_args(argv)
    with _compile_notes(args.command):
        return _run(args)


@contextlib.contextmanager
def _compile_notes(command: str) -> Iterator[None]:
    """On a terminal, the solver's one line before a first compilation, as ``hexapod COMMAND: ...`` on stderr.

    The :class:`~hexapod_model.exceptions.CompileWarning` a plain script sees is not shown: this line replaces it.
    """
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=CompileWarning)
        with _compile_line(command):
            yield


@contextlib.contextmanager
def _compile_line(command: str) -> Iterator[None]:
    if not sys.stderr.isatty():
        yield
        return
    log = logging.getLogger(COMPILE_LOGGER)
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter(f"hexapod {command}: %(message)s"))
    level, propagate = log.level, log.propagate
    log.addHandler(handler)
    log.setLevel(logging.INFO)
    log.propagate = False
    try:
        yield
    finally:
        log.removeHandler(handler)
        log.setLevel(level)
        log.propagate = propagate


def _run(args: argparse.Namespace) -> int:
    """``args.func(args)``: the exit code, one line on stderr for an error."""
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
    except BrokenPipeError:  # the reader of stdout went away: stop quietly, as Unix tools do
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error when Python flushes
        return 141
