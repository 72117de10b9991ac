"""``hexapod reproduce``: the accuracy study of Table 1 (Figs. 4-7), simulated or on measured data."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from ..analysis.conditioning import condition_numbers
from ..exceptions import InputError
from ..extras import require_extra
from ..files import atomic_write_text, check_output_path
from ..kinematics.hexapod import load_hexapod
from ..studies.paper_table import READINGS, format_table
from ..studies.reproduce import DEFAULT_ENCODER_NOISE, load_measured, run_study, simulate
from ._common import note, progress

DESCRIPTION = """\
Re-run the accuracy study of Table 1 of Bem, Ude and Nemec (2026), "Experimental Validation of the
Direct Kinematics of a Passive Stewart-Gough Platform with Modified Cardan Joints ...": the
Cardan-aware model against the textbook spherical-joint (standard Stewart-Gough) model, on
simulated poses within +-50 mm / +-25 deg or on your measured data (--data). With
--scenario geometric-errors the simulated fixture differs from its drawing, and the table
shows the spherical, nominal Cardan-aware and calibrated Cardan-aware models."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``reproduce``."""
    p = sub.add_parser(
        "reproduce", help="accuracy study: Cardan-aware vs standard model (Table 1, Figs. 4-7)", description=DESCRIPTION
    )
    src = p.add_mutually_exclusive_group()
    src.add_argument("--urdf", metavar="HEXAPOD", help="preset name, URDF or geometry file (default: --preset)")
    src.add_argument("--preset", help="preset name (default: reference)")
    p.add_argument("--poses", type=int, default=3000, help="poses to simulate (default 3000, as in the paper)")
    p.add_argument("--seed", type=int, default=0, help="random seed of the simulation (default 0)")
    p.add_argument(
        "--encoder-noise",
        type=float,
        metavar="M",
        help=f"Gaussian sigma (m) added to each simulated reading (default {DEFAULT_ENCODER_NOISE:g} m = "
        "10 um, the order of the LinACE encoder accuracy; 0 = exact readings)",
    )
    p.add_argument(
        "--reference-noise",
        type=float,
        metavar="M",
        help="Gaussian sigma (m) on each coordinate of the reference pose (motion capture), and "
        "M / r rad on each rotation-vector component, r = RMS platform anchor radius (default 0)",
    )
    p.add_argument(
        "--data",
        metavar="CSV",
        help="measured data instead of simulation: columns l1..l6 (m) and "
        "x,y,z,qx,qy,qz,qw (reference pose), see docs/reproduce.md",
    )
    p.add_argument(
        "--convergence-poses",
        type=int,
        metavar="K",
        help="poses used for the convergence/conditioning study (Figs. 6-7; default all, 0 = skip)",
    )
    p.add_argument(
        "--scenario",
        choices=("ideal", "geometric-errors"),
        default="ideal",
        help="ideal: an exact model (default); geometric-errors: the fixture differs from its drawing, "
        "and the table shows the spherical, nominal and calibrated Cardan-aware models (docs/reproduce.md)",
    )
    p.add_argument(
        "--calibration-poses",
        type=int,
        default=100,
        metavar="K",
        help="geometric-errors: poses for the calibration and the alignment of the others (default 100)",
    )
    p.add_argument("--json", metavar="FILE", help="write the Table 1 numbers as JSON")
    p.add_argument("--out", metavar="DIR", help="write the figures (PNG) into DIR (created)")
    p.set_defaults(func=run)


def _check_outputs(args: argparse.Namespace, hexapod: str) -> None:
    """Refuse unusable outputs before any work.

    ``--json`` may name a file in the ``--out`` folder that is yet to be created.
    """
    out = Path(args.out) if args.out else None
    if out is not None and out.exists() and not out.is_dir():
        raise InputError("--out", args.out, "is a file; name a folder (created if missing)")
    if args.json:
        parent = Path(args.json).parent
        if out is None or out.exists() or parent.resolve() != out.resolve():
            check_output_path(args.json, args.data, hexapod)


def run(args: argparse.Namespace) -> int:
    """``hexapod reproduce``."""
    if args.poses < 2:
        raise InputError("--poses", args.poses, "need at least 2 poses")
    name = args.urdf or args.preset or "reference"
    _check_outputs(args, name)
    if args.scenario == "geometric-errors":
        return _geometric_errors(args, name)
    hexa = load_hexapod(name)
    if args.data:
        if args.encoder_noise is not None or args.reference_noise is not None:
            note("reproduce", "--encoder-noise/--reference-noise are ignored with --data")
        data = load_measured(args.data)
    else:
        enc = DEFAULT_ENCODER_NOISE if args.encoder_noise is None else args.encoder_noise
        data = simulate(hexa, args.poses, args.seed, enc, args.reference_noise or 0.0)
    if args.out:
        try:
            Path(args.out).mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError("--out", args.out, f"cannot create the folder: {exc.strerror}") from None
    result = run_study(hexa, data, args.convergence_poses, progress)
    print(f"Table 1 re-run on {name}: {data.source}")
    if not args.data:
        enc = DEFAULT_ENCODER_NOISE if args.encoder_noise is None else args.encoder_noise
        print(
            f"encoder noise sigma = {1e6 * enc:g} um, "
            f"reference noise sigma = {1e3 * (args.reference_noise or 0.0):g} mm"
        )
    left_out = int((~result.solved).sum())
    if left_out:
        print(f"{left_out} of {len(result.solved)} rows not solved by both models (left out)")
    if not args.data:
        print("reading of the paper:", READINGS["reference-noise" if args.reference_noise else "ideal"])
    print(format_table(result.report))
    t = result.seconds_per_pose
    print(
        f"solve time: Cardan-aware {1e6 * t['cardan']:.0f} us/pose (Newton, numba), "
        f"standard {1e6 * t['standard']:.1f} us/pose (batch)"
    )
    if result.traces is not None:
        for key, s in result.traces["summary"].items():
            print(
                f"{key + ' (' + str(s['rows']) + ' rows)':18s}: {s['iterations']:.2f} iterations, {s['ms']:.2f} ms, "
                f"condition number {s['condition_number']:.1f} (mean)"
            )
        if hexa.closed_loop.kind == "6d":
            _print_conditioning(hexa, data.readings[: min(len(data.readings), args.convergence_poses or 200)])
    if args.json:
        atomic_write_text(args.json, json.dumps(result.report, indent=2) + "\n")
    if args.out:
        require_extra("plots")
        from ..plots.reproduce import write_figures

        for path in write_figures(
            args.out, np.asarray(result.positions_m), result.errors_cardan, result.errors_standard, result.traces
        ):
            note("reproduce", f"wrote {path}")
    return 0


def _print_conditioning(hexa, readings: np.ndarray) -> None:
    """Fig. 7's condition numbers under other row scalings (docs/reproduce.md)."""
    c = condition_numbers(hexa, readings)
    print(f"condition numbers at the solutions, mean over {c['poses']} poses (full 72 rows / reduced 36 rows):")
    for key, label in (
        ("si", "paper's definition (m, rad)"),
        ("mm", "lengths in millimetres"),
        ("rotation_rows_over_sqrt2", "full rotation rows / sqrt(2)"),
        ("unit_rows", "every row scaled to unit norm"),
    ):
        print(f"  {label:32s}{c[key]['full']:10.1f} / {c[key]['reduced']:.1f}")


def _geometric_errors(args: argparse.Namespace, name: str) -> int:
    """``--scenario geometric-errors``: the honest Table 1 (docs/reproduce.md)."""
    if args.data:
        raise InputError("--scenario", args.scenario, "simulates its own data; drop --data")
    if args.calibration_poses < 2:
        raise InputError("--calibration-poses", args.calibration_poses, "need at least 2 poses")
    from ..studies.calibrate import nominal_geometry
    from ..studies.table1 import format_table1, run_table1  # scipy.optimize: only this scenario needs it

    report = run_table1(
        nominal_geometry(name),
        args.poses,
        args.calibration_poses,
        args.seed,
        log=lambda text: note("reproduce", text),
    )
    print(f"Table 1 with geometric errors on {name} (seed {args.seed})")
    print("reading of the paper:", report["reading"])
    print(format_table1(report))
    if args.json:
        atomic_write_text(args.json, json.dumps(report, indent=2) + "\n")
    return 0
