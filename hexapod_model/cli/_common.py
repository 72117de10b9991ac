"""What every sub-command shares: the HEXAPOD argument, progress bars, output files."""

from __future__ import annotations

import argparse
import itertools
import sys
from collections.abc import Iterable, Iterator
from typing import Any, Protocol, TypeVar

from ..description.presets import DEFAULT_PRESET
from ..kinematics.hexapod import Hexapod, load_hexapod

T = TypeVar("T")
HEXAPOD_HELP = "preset name, URDF file, geometry file (.toml/.yaml/.json) or MJCF file (.xml)"


POSE_METAVAR = ("X", "Y", "Z", "ROLL", "PITCH", "YAW")


class ArgumentAdder(Protocol):
    """A parser or an argument group: what takes ``add_argument``."""

    def add_argument(self, *names: str, **options: Any) -> argparse.Action: ...  # noqa: D102


def add_pose_argument(p: ArgumentAdder, help: str) -> None:
    """``--pose X Y Z ROLL PITCH YAW``: a platform pose in metres (base frame) and degrees."""
    p.add_argument("--pose", nargs=6, type=float, metavar=POSE_METAVAR, help=help)


def add_hexapod_argument(p: argparse.ArgumentParser, optional: bool = False) -> None:
    """The positional HEXAPOD argument (dest ``hexapod``) that every command takes."""
    if optional:
        p.add_argument(
            "hexapod",
            nargs="?",
            default=DEFAULT_PRESET,
            metavar="HEXAPOD",
            help=f"{HEXAPOD_HELP} (default {DEFAULT_PRESET})",
        )
    else:
        p.add_argument("hexapod", metavar="HEXAPOD", help=HEXAPOD_HELP)
    p.add_argument(
        "--no-body-check",
        action="store_true",
        help="solve without judging the joint cones and collision bodies (docs/solver.md)",
    )


def hexapod_of(args: argparse.Namespace, compiled: bool = True) -> Hexapod:
    """The :class:`Hexapod` named by ``args.hexapod`` (preset, URDF, geometry or MJCF file).

    ``compiled=False``: solved with the NumPy kernels (no numba start-up; see :func:`compiled_for_long`).
    """
    return load_hexapod(args.hexapod, compiled=compiled, check_body=not getattr(args, "no_body_check", False))


def compiled_for_long(hexa: Hexapod, chunks: Iterator[T]) -> tuple[Hexapod, Iterator[T]]:
    """``hexa`` with the compiled kernels when ``chunks`` has more than one, and the same chunks.

    A command that streams a table loads its hexapod with ``compiled=False`` and calls this on
    the table's chunks (of ``CHUNK_ROWS`` rows): an input of one chunk is solved with the NumPy
    kernels, ~3 ms a row, with no numba import (~1 s, 130 MB) nor first compilation (~20 s once
    after installation); a longer one with the compiled kernels, ~30 us a row.
    """
    head = list(itertools.islice(chunks, 2))
    if len(head) > 1 and not hexa.compiled:
        hexa = Hexapod(hexa.closed_loop, hexa.geometry, compiled=True, check_body=hexa.check_body)
    return hexa, itertools.chain(head, chunks)


def progress(iterable: Iterable[T], total: int, desc: str, unit: str = "row") -> Iterator[T]:
    """A tqdm bar on stderr for inputs of 200 items or more; tqdm hides itself off a terminal."""
    if total < 200:
        return iter(iterable)
    from tqdm import tqdm

    return iter(tqdm(iterable, total=total, desc=desc, file=sys.stderr, unit=unit, disable=None))


def stream_bar(desc: str, unit: str = "row") -> Any:
    """A tqdm counter on stderr for a stream of unknown length: on a terminal only, after 1 s.

    Use as a context manager and call ``update(n)``.
    """
    from tqdm import tqdm

    return tqdm(desc=desc, file=sys.stderr, unit=unit, disable=None, delay=1.0)


def note(command: str, text: str) -> None:
    """One line on stderr, prefixed with the command."""
    print(f"hexapod {command}: {text}", file=sys.stderr)


def serve_until_interrupted() -> None:
    """Keep a meshcat view served until Ctrl-C (``hexapod view``, ``view --plan``)."""
    import time

    print("serving; press Ctrl-C to stop", file=sys.stderr)
    try:
        while True:
            time.sleep(1.0)
    except KeyboardInterrupt:
        pass
