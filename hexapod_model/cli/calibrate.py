"""``hexapod calibrate``: identify a hexapod's joint geometry from measured poses, plan poses, simulate."""

from __future__ import annotations

import argparse
import io
import json
import math
import sys
from pathlib import Path

from ..calibration.frames import Noise
from ..calibration.planning import plan_poses
from ..calibration.validation import verdict
from ..description.geometry_toml import save_geometry
from ..exceptions import InputError
from ..extras import require_extra
from ..files import atomic_write_text, check_output_path
from ..io.tables import LENGTH_COLUMNS, POSE_COLUMNS, pose_row, write_table
from ..studies.calibrate import load_poses, nominal_geometry, run_calibration, save_simulation, simulate
from ..studies.calibrate_report import format_report, report_json
from ._common import add_hexapod_argument, note, progress

DESCRIPTION = """\
Identify the joint geometry of a real hexapod from measured poses: per leg the Cardan centres,
the directions of the fixed Cardan axes, the axis offsets and the encoder zero (optionally a
reading scale error), plus the unknown measuring-frame and marker-frame transforms. Nonlinear
least squares with exact derivatives; combinations the data cannot determine are named and
held at nominal; k-fold validation before / after. The offset-Cardan hexapod of Bem, Ude and
Nemec (2026), "Experimental Validation of the Direct Kinematics of a Passive Stewart-Gough
Platform with Modified Cardan Joints ...", is the reference design.

  hexapod calibrate NOMINAL measured.csv -o calibrated.toml [--report DIR] [--json FILE] [--force]
  hexapod calibrate NOMINAL --plan 60 -o poses_to_visit.csv
  hexapod calibrate NOMINAL --simulate [--poses 100] [--seed S]

measured.csv: the `hexapod reproduce --data` format: l1..l6 (m, zero at home) and the
measured pose x,y,z (m), qx,qy,qz,qw of a marker or tool frame in the measuring device's frame.
A hexapod with extra sensors may add their readings (l7, ... (m), tilt_x, tilt_y (rad), in its
reading order): they become equations of the fit, their sensors' parameters are identified,
and the held-out errors are reported with and without them (without: the six-leg fit).

The calibrated geometry is written only when it predicts the held-out poses better than the
nominal one beyond the uncertainty (mean translation error down by more than 2 standard
errors); otherwise one line gives both figures and the exit status is 1 (--force writes it)."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``calibrate``."""
    p = sub.add_parser(
        "calibrate",
        help="identify a hexapod's joint geometry from measured poses (or plan / simulate)",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_hexapod_argument(p)
    p.add_argument("measured", nargs="?", metavar="MEASURED.csv", help="measured poses (see above)")
    p.add_argument("-o", "--output", metavar="FILE", help="calibrated geometry (.toml); with --plan the poses (.csv)")
    p.add_argument("--report", metavar="DIR", help="write the full report and the figures into DIR (created)")
    p.add_argument("--json", metavar="FILE", help="write the results as JSON")
    p.add_argument("--plan", type=int, metavar="N", help="choose N poses for the best-conditioned identification")
    p.add_argument("--candidates", type=int, default=2000, help="random poses --plan chooses from (default 2000)")
    p.add_argument("--simulate", action="store_true", help="the simulated study: a true geometry with random errors")
    p.add_argument("--poses", type=int, default=100, help="poses of --simulate (default 100)")
    p.add_argument("--seed", type=int, default=0, help="random seed of --simulate, --plan and the folds (default 0)")
    p.add_argument("--position-noise", type=float, default=1e-4, metavar="M", help="stated sigma per coordinate (m)")
    p.add_argument("--rotation-noise", type=float, default=0.05, metavar="DEG", help="stated sigma per axis (deg)")
    p.add_argument("--folds", type=int, default=5, help="k of the k-fold validation (default 5)")
    p.add_argument("--encoder-scale", action="store_true", help="also identify each reading's scale error")
    p.add_argument(
        "--force",
        action="store_true",
        help="write the calibrated geometry even when it predicts held-out poses no better than nominal",
    )
    p.add_argument("--hold", action="append", default=[], metavar="PATTERN", help="keep parameters at nominal")
    p.add_argument(
        "--max-sigma",
        type=float,
        default=1.0,
        help="hold combinations whose 1-sigma exceeds this many expected magnitudes (default 1)",
    )
    p.set_defaults(func=run)


def _check(args: argparse.Namespace) -> None:
    given = (("MEASURED.csv", args.measured), ("--plan", args.plan is not None), ("--simulate", args.simulate))
    modes = [m for m, on in given if on]
    if len(modes) != 1:
        raise InputError("mode", " ".join(modes) or "none", "give exactly one of MEASURED.csv, --plan N, --simulate")
    if args.plan is not None:
        if not args.output or Path(args.output).suffix.lower() != ".csv":
            raise InputError("--output", args.output, "--plan writes the poses to a .csv file: give -o poses.csv")
    elif args.output and Path(args.output).suffix.lower() != ".toml":
        raise InputError("--output", args.output, "the calibrated geometry is written as a .toml file")
    for name in ("output", "json"):
        if getattr(args, name):
            check_output_path(getattr(args, name), args.measured, args.hexapod)
    if args.report and Path(args.report).exists() and not Path(args.report).is_dir():
        raise InputError("--report", args.report, "is a file; name a folder")
    if args.folds < 2:
        raise InputError("--folds", args.folds, "need at least 2 folds")
    if args.max_sigma <= 0:
        raise InputError("--max-sigma", args.max_sigma, "must be positive")


def run(args: argparse.Namespace) -> int:
    """``hexapod calibrate``."""
    _check(args)
    noise = Noise(args.position_noise, math.radians(args.rotation_noise))
    nominal = nominal_geometry(args.hexapod)
    if args.plan is not None:
        return _plan(args, nominal, noise)
    sim = None
    if args.simulate:
        sim = simulate(nominal, args.poses, args.seed, noise=noise)
        data = sim.data
    else:
        data = load_poses(args.measured, nominal)
    options = {"encoder_scale": args.encoder_scale, "hold": tuple(args.hold), "max_sigma": args.max_sigma}
    if sys.stderr.isatty():  # like the progress bars: only on a terminal
        note("calibrate", f"identifying on {len(data.readings)} poses, then {args.folds}-fold validation ...")
    result = run_calibration(nominal, data, noise, args.folds, args.seed, sim, progress, **options)
    print(format_report(result, noise))
    geometry = result.identification.geometry
    decision = verdict(result.validation)
    refused = bool(args.output) and not decision.better and not args.force
    if args.output and not refused:
        comment = f"Calibrated by hexapod calibrate from {data.source} ({len(data.readings)} poses)."
        save_geometry(geometry, args.output, comment)
        note("calibrate", f"wrote {args.output}" + ("" if decision.better else f" (--force; {decision.describe()})"))
    if args.json:
        written = (not refused) if args.output else None
        atomic_write_text(args.json, json.dumps(report_json(result, written), indent=2) + "\n")
    if args.report:
        require_extra("plots")
        from ..plots.calibrate import write_figures

        out = Path(args.report)
        out.mkdir(parents=True, exist_ok=True)
        atomic_write_text(out / "report.txt", format_report(result, noise, details=True) + "\n")
        paths = [out / "report.txt", *write_figures(out, result, args.max_sigma)]
        if sim is not None:
            paths += save_simulation(sim, out)
        note("calibrate", f"wrote {', '.join(str(p) for p in paths)}")
    if refused:
        note("calibrate", f"{args.output} not written: {decision.describe()}; --force writes it anyway")
        return 1
    return 0


def _plan(args: argparse.Namespace, nominal, noise: Noise) -> int:
    plan = plan_poses(nominal, args.plan, args.candidates, args.seed, noise)
    buf = io.StringIO()
    rows = [[*pose_row(T), *map(float, lengths)] for T, lengths in zip(plan.poses, plan.readings)]
    write_table(None, POSE_COLUMNS + LENGTH_COLUMNS, rows, out=buf)
    atomic_write_text(args.output, buf.getvalue())
    s, r = plan.singular_values, plan.singular_values_random
    print(
        f"{args.plan} poses chosen from {plan.candidates} reachable candidates (D-optimal, greedy): "
        f"{int((s >= 1).sum())} of {s.size} parameter combinations within their tolerance "
        f"(random poses: {int((r >= 1).sum())}); smallest singular value {s[-1]:.3g} (random {r[-1]:.3g})"
    )
    note("calibrate", f"wrote {args.output}: x,y,z (m), qx..qw, roll,pitch,yaw (deg) of the platform, l1..l6 (m)")
    return 0
