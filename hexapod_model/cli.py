"""The ``hexapod`` command line. ``main(argv)`` is testable: it returns the exit code.

Core commands live here (``urdf``, ``fk``, ``ik``, ``bench``); other commands are modules
listed in ``COMMAND_MODULES``, each with ``register(subparsers)`` that adds its parser and
sets ``func`` to a ``run(args) -> int``.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path


from .exceptions import HexapodError
from .geometry import load_geometry
from .hexapod import Hexapod
from .presets import DEFAULT_PRESET, PRESETS, get_preset
from .tables import LENGTH_COLUMNS, POSE_COLUMNS, SOLVER_COLUMNS, column, pose_row, poses_from_table, read_table, write_table
from .urdf import geometry_to_urdf

COMMAND_MODULES: list[str] = ["track", "evaluate", "study", "view_cli"]


def progress(iterable, total: int, desc: str):
    """tqdm progress bar on stderr, shown only on a terminal and for long inputs."""
    if total < 200 or not sys.stderr.isatty():
        return iterable
    from tqdm import tqdm

    return tqdm(iterable, total=total, desc=desc, file=sys.stderr, unit="row")


def load_hexapod(spec: str) -> Hexapod:
    """A URDF path or a preset name."""
    return Hexapod.from_urdf(spec)


def cmd_urdf(args) -> int:
    if args.list_presets:
        for name, factory in PRESETS.items():
            print(f"{name:14s}{factory().description}")
        return 0
    geom = load_geometry(args.geometry) if args.geometry else get_preset(args.preset)
    text = geometry_to_urdf(geom)
    Hexapod.from_geometry(geom)  # refuse to write a URDF that does not load and assemble
    if args.output:
        Path(args.output).write_text(text)
        print(f"wrote {args.output} ({geom.name}, {geom.joint_type} legs)", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0


def _solve_rows(args, kind: str) -> int:
    hexa = load_hexapod(args.urdf)
    if kind == "fk":
        header, data = read_table(args.input, LENGTH_COLUMNS)
        inputs = column(header, data, LENGTH_COLUMNS)
        out_header = POSE_COLUMNS + SOLVER_COLUMNS
    else:
        header, data = read_table(args.input)
        inputs = poses_from_table(header, data)
        out_header = LENGTH_COLUMNS + SOLVER_COLUMNS
    width = len(out_header) - len(SOLVER_COLUMNS)
    rows, failures, guess = [], [], None
    for k, x in enumerate(progress(inputs, len(inputs), kind)):
        try:
            sol = (hexa.forward if kind == "fk" else hexa.inverse)(x, guess=guess, check=False)
            status, it, res = sol.status, sol.iterations, sol.residual
        except HexapodError as exc:
            sol, status, it, res = None, "invalid_input", 0, float("nan")
            failures.append(f"row {k + 1}: {exc}")
        if sol is not None and sol.converged:
            guess = sol
            values = pose_row(sol.pose) if kind == "fk" else list(sol.lengths)
            rows.append([*map(float, values), "ok", it, float(res)])
        else:
            if sol is not None:
                failures.append(f"row {k + 1}: {status}: {sol.message}")
            rows.append([float("nan")] * width + [status, it, float(res)])
    write_table(args.output, out_header, rows, out=sys.stdout)
    if failures:
        print(f"hexapod {kind}: {len(failures)} of {len(rows)} rows failed; first: {failures[0]}", file=sys.stderr)
        return 1
    return 0


def cmd_fk(args) -> int:
    return _solve_rows(args, "fk")


def cmd_ik(args) -> int:
    return _solve_rows(args, "ik")


def cmd_bench(args) -> int:
    from .bench import print_report, run_benchmarks

    report = run_benchmarks(args.urdf, samples=args.samples, seed=args.seed)
    print_report(report)
    if args.json:
        import json

        Path(args.json).write_text(json.dumps(report, indent=2))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="hexapod", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("urdf", help="write the URDF of a preset or a geometry file")
    p.add_argument("-o", "--output", help="output file (default: stdout)")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--preset", default=DEFAULT_PRESET, help=f"preset name (default {DEFAULT_PRESET})")
    src.add_argument("--geometry", help="geometry file (.toml, .yaml or .json), see docs/geometry.md")
    src.add_argument("--list-presets", action="store_true", help="print 'NAME  description' per preset")
    p.set_defaults(func=cmd_urdf)

    for name, func, what, inp, out in (("fk", cmd_fk, "direct kinematics: leg readings -> poses", "LENGTHS.csv", "POSES.csv"),
                                       ("ik", cmd_ik, "inverse kinematics: poses -> leg readings", "POSES.csv", "LENGTHS.csv")):
        p = sub.add_parser(name, help=what)
        p.add_argument("urdf", metavar="URDF", help="URDF file or preset name")
        p.add_argument("input", metavar=inp)
        p.add_argument("-o", "--output", metavar=out, help="output CSV (default: stdout)")
        p.set_defaults(func=func)

    p = sub.add_parser("bench", help="timing figures of the solvers (median, p95, p99)")
    p.add_argument("urdf", nargs="?", default=DEFAULT_PRESET, metavar="URDF", help="URDF file or preset name")
    p.add_argument("--samples", type=int, default=1000, help="random poses for the cold FK and IK figures")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--json", help="also write the figures as JSON")
    p.set_defaults(func=cmd_bench)

    for mod in COMMAND_MODULES:
        importlib.import_module(f"hexapod_model.{mod}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except HexapodError as exc:
        print(f"hexapod {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
