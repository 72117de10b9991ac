"""``hexapod urdf``, ``fk``, ``ik`` and ``bench``."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Iterator
from contextlib import nullcontext
from typing import IO, Any

import numpy as np

from ..description.geometry import GEOMETRY_SUFFIXES, HexapodGeometry, load_geometry
from ..description.mjcf_loader import MJCF_SUFFIXES
from ..description.plausibility import position_problem
from ..description.presets import DEFAULT_PRESET, PRESETS, get_preset
from ..description.urdf import geometry_to_urdf, validate_urdf
from ..exceptions import InputError
from ..files import atomic_write_text, atomic_writer, check_output_path
from ..io.tables import (
    LENGTH_COLUMNS,
    POSE_COLUMNS,
    SOLVER_COLUMNS,
    Rows,
    TableWriter,
    open_table,
    pose_columns,
    pose_input_columns,
    poses_from_table,
)
from ..kinematics.batch import BatchResult
from ..kinematics.hexapod import Hexapod
from ._common import add_hexapod_argument, compiled_for_long, hexapod_of, note, stream_bar


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``urdf``, ``fk``, ``ik`` and ``bench``."""
    p = sub.add_parser(
        "urdf",
        help="write the URDF of a preset or a geometry file",
        description="Write the URDF (with its <loop_closure> elements) of a preset or geometry file.",
    )
    p.add_argument(
        "hexapod",
        nargs="?",
        metavar="HEXAPOD",
        help=f"preset name or geometry file (.toml/.yaml/.json), see docs/geometry.md (default {DEFAULT_PRESET})",
    )
    p.add_argument("-o", "--output", help="output file (default: stdout)")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--preset", help="the same as HEXAPOD, for a preset name")
    src.add_argument("--geometry", help="the same as HEXAPOD, for a geometry file (.toml, .yaml or .json)")
    src.add_argument("--list-presets", action="store_true", help="print 'NAME  description' per preset")
    p.add_argument(
        "--yourdfpy",
        action="store_true",
        help="also check the file with yourdfpy, a second independent parser (imports trimesh and SciPy: ~1 s)",
    )
    p.set_defaults(func=cmd_urdf)

    for name, func, what, inp, out in (
        ("fk", cmd_fk, "direct kinematics: leg readings -> poses", "LENGTHS.csv", "POSES.csv"),
        ("ik", cmd_ik, "inverse kinematics: poses -> leg readings", "POSES.csv", "LENGTHS.csv"),
    ):
        p = sub.add_parser(
            name, help=what, description=f"{what[0].upper()}{what[1:]} (CSV in, CSV out; '-' = stdin/stdout)."
        )
        add_hexapod_argument(p)
        p.add_argument("input", metavar=inp, help="input CSV, or - for standard input")
        p.add_argument("-o", "--output", metavar=out, help="output CSV (default, or -: standard output)")
        if name == "fk":
            p.add_argument(
                "--prove",
                action="store_true",
                help="prove each row's step from the row before (Krawczyk; up to a 2 mm step): a row not proven "
                "is uncertified. Loads the proof's compiled kernels (after installation they compile once: ~1 min)",
            )
        p.set_defaults(func=func)

    p = sub.add_parser(
        "bench",
        help="timing figures of the solvers (median, p95, p99)",
        description="Time warm FK along trajectory A at 1 kHz, cold FK and IK over random box poses.",
    )
    add_hexapod_argument(p, optional=True)
    p.add_argument("--samples", type=int, default=1000, help="random poses for the cold FK and IK figures")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--json", help="also write the figures as JSON")
    p.set_defaults(func=cmd_bench)


def cmd_urdf(args: argparse.Namespace) -> int:
    """``hexapod urdf``."""
    if args.list_presets:
        width = max(map(len, PRESETS)) + 2
        for name, factory in PRESETS.items():
            print(f"{name:{width}s}{factory().description}")
        return 0
    geom = _urdf_source(args)
    if args.output:
        check_output_path(args.output, args.geometry or args.hexapod)
    text = geometry_to_urdf(geom)
    # urdfdom (Pinocchio's parser) reads it, it assembles, no numba needed; a rejection is
    # explained by yourdfpy's finding, which is imported only then or when asked for
    Hexapod.from_geometry(geom, compiled=False)
    if args.yourdfpy:
        validate_urdf(text, geom.name)
    if args.output:
        atomic_write_text(args.output, text)
        note("urdf", f"wrote {args.output} ({geom.name}, {geom.joint_type} legs)")
    else:
        sys.stdout.write(text)
    return 0


def _urdf_source(args: argparse.Namespace) -> HexapodGeometry:
    """The geometry ``hexapod urdf`` writes: HEXAPOD, ``--preset`` or ``--geometry`` (one of them)."""
    given = args.preset or args.geometry
    if args.hexapod is not None and given is not None:
        option = "--preset" if args.preset else "--geometry"
        raise InputError("HEXAPOD", args.hexapod, f"given with {option} {given}: name the hexapod once")
    if args.geometry:
        return load_geometry(args.geometry)
    spec = args.hexapod or args.preset or DEFAULT_PRESET
    if spec.lower().endswith(GEOMETRY_SUFFIXES):
        return load_geometry(spec)
    if spec.lower().endswith((".urdf", *MJCF_SUFFIXES)):
        raise InputError("HEXAPOD", spec, "hexapod urdf writes the URDF of a preset or a geometry file")
    return get_preset(spec)


def _solve_rows(args: argparse.Namespace, kind: str) -> int:
    """Stream the rows of ``args.input`` through FK or IK into the output, a chunk at a time."""
    out_path = None if args.output in (None, "-") else check_output_path(args.output, args.input, args.hexapod)
    hexa = hexapod_of(args, compiled=False)  # compiled below if the input is long
    source: Any = getattr(sys.stdin, "buffer", sys.stdin) if args.input == "-" else args.input
    with open_table(source, LENGTH_COLUMNS if kind == "fk" else (), "<stdin>" if args.input == "-" else None) as table:
        columns = LENGTH_COLUMNS if kind == "fk" else pose_input_columns(table.header)
        out_header = (POSE_COLUMNS if kind == "fk" else LENGTH_COLUMNS) + SOLVER_COLUMNS
        with atomic_writer(out_path) if out_path is not None else nullcontext(sys.stdout) as out:
            hexa, chunks = compiled_for_long(hexa, table.chunks(columns))
            prove = bool(getattr(args, "prove", False))
            total, failed, first = _stream(hexa, chunks, columns, kind, out, out_header, prove)
    if failed:
        note(kind, f"{failed} of {total} rows failed; first: {first}")
        return 1
    return 0


def _stream(
    hexa: Hexapod,
    chunks: Iterator[Rows],
    columns: list[str],
    kind: str,
    out: IO[str],
    out_header: list[str],
    prove: bool = False,
) -> tuple[int, int, str]:
    """Solve and write every row, each from the previous good solution, a chunk at a time.

    Each chunk goes through ``forward_batch`` / ``inverse_batch`` with ``warm=True``, from the
    last good solution of the chunks before: per row what ``forward`` / ``inverse`` with the
    previous good row's solution as guess gives; ``prove``: each fk row with the Krawczyk proof
    of its step (``forward_batch(prove=True)``), else with the certificate's checks (and the
    proof of a row near a singularity). Returns (rows, failed rows, the first failure as one line).
    """
    writer = TableWriter(out, out_header)
    width = len(out_header) - len(SOLVER_COLUMNS)
    total, failed, first, guess = 0, 0, "", None
    with stream_bar(kind) as bar:
        for rows in chunks:
            res, errors = _solve_chunk(hexa, kind, columns, rows, guess, prove)
            bad = np.array([bool(e) for e in errors], dtype=bool)
            status = np.where(bad, "invalid_input", res.status)
            good = status == "converged"
            table_values = np.full((len(rows), width), np.nan)
            if good.any():  # fk: pose -> quaternion and angles for the whole chunk in one call
                table_values[good] = pose_columns(res.poses[good]) if kind == "fk" else res.lengths[good]
                guess = res.solution(int(np.flatnonzero(good)[-1]))  # the next chunk's first guess
            iterations = np.where(bad, 0, res.iterations)
            residuals = np.where(bad, np.nan, res.residual)
            for k in range(len(rows)):
                flags = ";".join(res.flags[k]) if good[k] else ""  # a valid pose, but not ok (near_singular)
                label = (flags or "ok") if good[k] else str(status[k])
                why = ""
                if label != "ok":
                    failed += 1
                    why = errors[k] or res.messages[k]
                    first = first or f"row {total + k + 1} (line {rows.lines[k]}): {label}: {why}"
                writer.write([*map(float, table_values[k]), label, int(iterations[k]), float(residuals[k]), why])
            total += len(rows)
            bar.update(len(rows))
            out.flush()
    return total, failed, first


def _solve_chunk(
    hexa: Hexapod, kind: str, columns: list[str], rows: Rows, guess, prove: bool = False
) -> tuple[BatchResult, list[str]]:
    """One chunk solved warm from ``guess``, and per row the reason it was not read (``""``: read).

    Rows that were not read go to the batch as NaN (``invalid_input``), so that they never
    become a guess.
    """
    if kind == "fk":
        inputs, errors = rows.values.copy(), rows.errors
    else:
        inputs, pose_errors = poses_from_table(columns, rows.values)
        scale = [position_problem(T[:3, 3], hexa.base_radius) for T in inputs]  # a table in mm: said per row
        errors = [a or b or c for a, b, c in zip(rows.errors, pose_errors, scale)]
    inputs[[k for k, e in enumerate(errors) if e]] = np.nan
    if kind == "fk":
        return hexa.forward_batch(inputs, guess, warm=True, prove=prove), errors
    return hexa.inverse_batch(inputs, guess, warm=True), errors


def cmd_fk(args: argparse.Namespace) -> int:
    """``hexapod fk``."""
    return _solve_rows(args, "fk")


def cmd_ik(args: argparse.Namespace) -> int:
    """``hexapod ik``."""
    return _solve_rows(args, "ik")


def cmd_bench(args: argparse.Namespace) -> int:
    """``hexapod bench``."""
    if args.json:
        check_output_path(args.json, args.hexapod)
    from ..studies.bench import run_benchmarks  # the tracker and numba: not for fk / ik

    report = run_benchmarks(hexapod_of(args), samples=args.samples, seed=args.seed)
    report["hexapod"] = args.hexapod
    print(format_bench(report))
    if args.json:
        atomic_write_text(args.json, json.dumps(report, indent=2) + "\n")
    return 0


def format_bench(report: dict) -> str:
    """The ``hexapod bench`` table of a :func:`~hexapod_model.studies.bench.run_benchmarks` report."""
    lines = [
        f"hexapod {report['hexapod']} (nq = {report['nq']}); times per solve in microseconds",
        f"{'case':10s}{'n':>7s}{'median':>10s}{'p95':>10s}{'p99':>10s}{'iter mean':>11s}{'iter max':>10s}"
        f"{'target':>10s}",
    ]
    for key in ("warm_fk", "cold_fk", "ik"):
        r = report[key]
        lines.append(
            f"{key:10s}{r['n']:7d}{r['median_us']:10.1f}{r['p95_us']:10.1f}{r['p99_us']:10.1f}"
            f"{r['iterations_mean']:11.2f}{r['iterations_max']:10d}"
            f"{'<= {:g}'.format(report['targets_median_us'][key]):>10s}"
        )
    return "\n".join(lines)
