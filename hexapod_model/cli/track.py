"""``hexapod track``: the 1 kHz tracking experiment (trajectories A/B, predictors, speeds)."""

from __future__ import annotations

import argparse
import io
import json
import sys
from pathlib import Path

from ..extras import require_extra
from ..files import atomic_write_text, check_output_path
from ..io.tables import LENGTH_COLUMNS, column, read_table, write_table
from ..studies.track import SPEEDS, TRACK_LOG_COLUMNS, run_table, simulate, track_log
from ..tracking.reading_tests import DEFAULT_READING_NOISE
from ..tracking.tracker import PREDICTORS
from ._common import add_hexapod_argument, hexapod_of, note, progress

DESCRIPTION = """\
Track trajectory A or B of the 1 kHz experiment of Jakobović and Jelenković (2002) with the
stream tracker (warm starts, eq. 22-24 predictors, flags for doubtful samples) and report the
errors against the true poses; --table runs every trajectory x predictor x speed.

With --readings FILE.csv (columns t,l1..l6: seconds, metres) the tracker runs over a recorded
stream instead and writes one row per sample: t,x,y,z,qx,qy,qz,qw,roll,pitch,yaw (m, unit
quaternion, degrees), status (ok or the failure's name), flags (separated by ';', empty when
none; from a step or a swap the data show, every later row carries discontinuity:legN, as the
fixture service latches it) and iterations. Exit code 1 when a sample failed or was flagged
after the first ones."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``track``."""
    p = sub.add_parser(
        "track", help="1 kHz tracking experiment (trajectories A/B, predictors)", description=DESCRIPTION
    )
    add_hexapod_argument(p, optional=True)
    p.add_argument("--trajectory", choices=("A", "B"), default="A")
    p.add_argument("--speed", type=float, choices=SPEEDS, default=1)
    p.add_argument("--predictor", choices=PREDICTORS, default="eq22")
    p.add_argument("--table", action="store_true", help="all trajectories x predictors x speeds")
    p.add_argument("--out", default=".", help="directory for the PNG (default: current; created)")
    p.add_argument("--json", help="write the summary (or table) as JSON")
    p.add_argument("--readings", metavar="FILE.csv", help="track a recorded stream (columns t,l1..l6)")
    p.add_argument("-o", "--output", metavar="OUT.csv", help="with --readings: output CSV (default: standard output)")
    p.add_argument(
        "--noise",
        type=float,
        default=DEFAULT_READING_NOISE,
        help=f"with --readings: standard deviation of the reading noise in m (default {DEFAULT_READING_NOISE:g})",
    )
    p.set_defaults(func=run)


def format_table(rows: list[dict]) -> str:
    """The ``--table`` output: one line per trajectory x speed x predictor."""
    lines = [
        f"{'traj':5s}{'speed':>6s}{'predictor':>10s}{'max ang (deg)':>15s}{'max pos (m)':>13s}"
        f"{'jumps':>7s}{'flagged':>9s}{'(limits)':>9s}{'unflagged off':>15s}{'median us':>11s}"
    ]
    for r in rows:
        lines.append(
            f"{r['trajectory']:5s}{r['speed']:6g}{r['predictor']:>10s}{r['max_angle_error_deg']:15.2e}"
            f"{r['max_position_error_m']:13.2e}{r['branch_jumps']:7d}{r['flagged']:9d}"
            f"{r['flags'].get('out_of_limits', 0):9d}{r['unflagged_off_branch']:15d}{r['median_solve_us']:11.1f}"
        )
    return "\n".join(lines)


def run_readings(args: argparse.Namespace) -> int:
    """``hexapod track --readings``: one output row per recorded sample."""
    out = None if args.output in (None, "-") else check_output_path(args.output, args.readings, args.hexapod)
    header, data = read_table(args.readings, ["t", *LENGTH_COLUMNS])
    hexa = hexapod_of(args)
    times, readings = column(header, data, ["t"])[:, 0], column(header, data, LENGTH_COLUMNS)
    rows, counts = track_log(
        hexa, times, readings, args.predictor, progress=lambda it, n, d: progress(it, n, d), noise=args.noise
    )
    text = io.StringIO()
    write_table(None, TRACK_LOG_COLUMNS, rows, out=text)
    if out is None:
        sys.stdout.write(text.getvalue())
    else:
        atomic_write_text(out, text.getvalue())
    settle = min(3, len(rows))
    late = [r for k, r in enumerate(rows) if r[-3] != "ok" or (r[-2] and (k >= settle or r[-2] != "settling"))]
    if late:
        summary = ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))
        note("track", f"{len(late)} of {len(rows)} samples failed or flagged ({summary})")
        return 1
    return 0


def run(args: argparse.Namespace) -> int:
    """``hexapod track``."""
    if args.readings:
        return run_readings(args)
    if args.output:
        note("track", "-o/--output needs --readings; use --out for the figure folder")
        return 2
    if args.json:
        check_output_path(args.json, args.hexapod)
    hexa = hexapod_of(args)
    result: dict | list[dict]
    if args.table:
        rows = run_table(hexa, progress=lambda it, n, d: progress(it, n, d, unit="run"))
        print(f"hexapod {args.hexapod}: tracking at 1 kHz, tolerance 1e-10")
        print(format_table(rows))
        result = rows
    else:
        require_extra("plots")
        from ..plots.track import plot_run

        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        r = simulate(hexa, args.trajectory, args.speed, args.predictor)
        png = out / f"track_{args.trajectory}_x{args.speed:g}_{args.predictor}.png"
        plot_run(r, png)
        s = result = r.summary()
        print(
            f"hexapod {args.hexapod}: trajectory {args.trajectory} x{args.speed:g}, predictor {args.predictor}, "
            f"{s['samples']} samples at 1 kHz"
        )
        print(f"  max error: {s['max_angle_error_deg']:.3g} deg, {s['max_position_error_m']:.3g} m")
        print(
            f"  left the true branch: {'yes' if s['branch_jumps'] else 'no'} "
            f"({s['branch_jumps']} jumps, {s['off_branch_samples']} samples off branch, "
            f"{s['unflagged_off_branch']} of them unflagged)"
        )
        print(f"  flagged samples: {s['flagged']} {s['flags']}; failed: {s['failed']}")
        print(f"  true poses, IK status: {s['truth_ik_status']}")
        print(f"  median solve time: {s['median_solve_us']:.1f} us; figure: {png}")
    if args.json:
        atomic_write_text(args.json, json.dumps(result, indent=2) + "\n")
    return 0
