"""``hexapod evaluate``: workspace for a cone of tool orientations and the kinematic figures over it."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from ..description.sensors import Inclinometer, MeasuringLeg
from ..exceptions import InputError
from ..extras import require_extra
from ..files import atomic_write_text, check_output_path
from ..kinematics.hexapod import load_hexapod
from ..studies.cluster import dashboard_link
from ..studies.evaluate import Settings, run_evaluation
from ._common import add_hexapod_argument, note, stream_bar

DESCRIPTION = """\
Map the workspace reachable for a whole cone of tool orientations (within stroke and Cardan
limits) and the kinematic figures of Jakobović and Jelenković (2002), "Kinematic evaluation and
forward kinematic problem for Stewart platform based manipulators" (condition number, sigma_min,
|det J|) over it, the z-slices as Dask tasks over all cores or on a cluster (--scheduler);
resumable with --out."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``evaluate``."""
    p = sub.add_parser(
        "evaluate", help="workspace for a cone of orientations and its kinematic figures", description=DESCRIPTION
    )
    add_hexapod_argument(p, optional=True)
    p.add_argument(
        "--grid", type=int, default=Settings.grid, help="grid points along the longest side (default %(default)s)"
    )
    p.add_argument("--cone-deg", type=float, default=Settings.cone_deg, help="tool cone half-angle (deg)")
    p.add_argument("--cone-samples", type=int, default=Settings.cone_samples, help="tilted orientations on the cone")
    p.add_argument(
        "--length-unit",
        type=float,
        default=None,
        help="m per length unit of the Jacobian figures (default: platform anchor radius)",
    )
    p.add_argument(
        "--workers", type=int, default=None, help="local Dask worker processes (default: all cores; 1: this process)"
    )
    p.add_argument("--scheduler", metavar="ADDRESS", help="run the slices on the Dask cluster at tcp://HOST:PORT")
    p.add_argument("--out", default=None, help="directory for the PNG and the resumable checkpoint (created)")
    p.add_argument("--json", help="write the report as JSON")
    p.add_argument(
        "--detectability",
        metavar="PNG",
        help="instead: each redundant reading's minimal detectable fault over the x-y section at home height "
        "(a hexapod with measuring legs or an inclinometer, e.g. reference7; docs/redundancy.md)",
    )
    p.add_argument(
        "--place-seventh-leg",
        metavar="CANDIDATES",
        help="instead: rank the candidate measuring legs of a TOML file ([[measuring_legs]] tables) added to "
        "HEXAPOD by the largest fault of any leg they may miss over the x-y section at home height "
        "(docs/redundancy.md)",
    )
    p.add_argument(
        "--place-inclinometer",
        metavar="CANDIDATES",
        help="instead: rank the candidate inclinometers of a TOML file ([[inclinometers]] tables: rpy_deg "
        "or rpy, sigma) mounted on HEXAPOD's platform in place of its own by the same criterion",
    )
    p.add_argument(
        "--placement-grid",
        type=int,
        default=None,
        help="points along x and y of each candidate's section (default 5)",
    )
    p.set_defaults(func=run)


def describe(sensor: MeasuringLeg | Inclinometer) -> str:
    """A candidate sensor in one line: a leg's anchors (m), an inclinometer's rotation (deg) and noise (urad)."""
    if isinstance(sensor, Inclinometer):
        rpy = ", ".join(f"{math.degrees(v):.4g}" for v in sensor.rpy)
        return f"inclinometer rpy ({rpy}) deg, sigma {1e6 * sensor.sigma:.4g} urad"
    b = ", ".join(f"{v:g}" for v in sensor.base_anchor)
    pa = ", ".join(f"{v:g}" for v in sensor.platform_anchor)
    return f"({b}) -> ({pa})"


def _candidate_json(sensor: MeasuringLeg | Inclinometer) -> dict:
    if isinstance(sensor, Inclinometer):
        return {"rpy": list(sensor.rpy), "sigma": sensor.sigma}
    return {"base_anchor": list(sensor.base_anchor), "platform_anchor": list(sensor.platform_anchor)}


def run_placement(args: argparse.Namespace) -> int:
    """``hexapod evaluate --place-seventh-leg | --place-inclinometer CANDIDATES``: the candidates ranked, best first."""
    from ..analysis.placement import DEFAULT_PLACEMENT_GRID, candidates_from_toml, rank_placements, tied

    if args.place_seventh_leg and args.place_inclinometer:
        raise InputError("--place-inclinometer", args.place_inclinometer, "give it or --place-seventh-leg, not both")
    if args.json:
        check_output_path(args.json, args.hexapod)
    if args.place_seventh_leg:
        source, kind, what = args.place_seventh_leg, "measuring_legs", "measuring legs"
    else:
        source, kind, what = args.place_inclinometer, "inclinometers", "inclinometers"
    candidates = candidates_from_toml(source, (kind,))
    hexa = load_hexapod(args.hexapod)
    if hexa.geometry is None:
        raise InputError(
            "hexapod", args.hexapod, "a URDF has no geometry to add a sensor to: give a preset or geometry file"
        )
    grid = DEFAULT_PLACEMENT_GRID if args.placement_grid is None else args.placement_grid
    scores = rank_placements(hexa.geometry, candidates, grid=grid)
    print(
        f"hexapod {args.hexapod}: {len(scores)} candidate {what} from {source}, largest minimal detectable "
        f"fault of any leg over home +-50 mm in x and y ({grid}x{grid} points), best first"
    )
    print(f"  {'rank':>4s} {'candidate':>9s} {'worst (um)':>11s}  candidate")
    for rank, s in enumerate(scores, 1):
        tie = rank > 1 and tied(s.worst, scores[rank - 2].worst)
        mark = "=" if tie else " "
        print(
            f"  {rank:4d}{mark}{s.index + 1:9d} {1e6 * s.worst:11.4g}  {describe(s.sensor)}  [{s.inside} points inside]"
        )
    if any(rank > 1 and tied(s.worst, scores[rank - 2].worst) for rank, s in enumerate(scores, 1)):
        print("  =: ties the rank above (within 1e-6 relative): the criterion cannot tell them apart")
    if args.json:
        rows = [
            {
                "candidate": s.index + 1,
                **_candidate_json(s.sensor),
                "worst_m": s.worst,
                "largest": dict(zip(s.names, map(float, s.largest), strict=True)),
                "points_inside": s.inside,
            }
            for s in scores
        ]
        atomic_write_text(
            args.json, json.dumps({"hexapod": str(args.hexapod), "grid": grid, "ranking": rows}, indent=2)
        )
    return 0


def run_detectability(args: argparse.Namespace) -> int:
    """``hexapod evaluate --detectability PNG``: the table of minimal detectable biases and their figure."""
    from ..analysis.detectability import detectability_map

    check_output_path(args.detectability, args.hexapod)
    require_extra("plots")
    from ..plots.detectability import plot_detectability

    hexa = load_hexapod(args.hexapod)
    dmap = detectability_map(hexa)
    half = 1e3 * (dmap.xs[-1] - dmap.xs[0]) / 2
    print(
        f"hexapod {args.hexapod}: minimal detectable fault per reading, platform at home +-{half:g} mm in x and y, "
        f"false-alarm rate {dmap.alpha:g}, power {dmap.power:g}"
    )
    print(f"  {'reading':10s}{'smallest':>12s}{'median':>12s}{'largest':>12s}")
    for name, lo, mid, hi in dmap.summary():
        unit = "urad" if name.startswith("tilt") else "um"
        print(f"  {name:10s}{1e6 * lo:12.4g}{1e6 * mid:12.4g}{1e6 * hi:12.4g}  {unit}")
    plot_detectability(dmap, args.detectability, str(args.hexapod))
    print(f"  figure: {args.detectability}")
    return 0


def format_report(r: dict) -> str:
    """The table ``hexapod evaluate`` prints, the paper's figures beside ours."""
    u = r["length_unit_m"]
    lines = [
        f"hexapod {r['hexapod']}: workspace for a {r['cone_deg']:g} deg cone ({r['orientations']} orientations), "
        f"grid {r['grid']['nx']}x{r['grid']['ny']}x{r['grid']['nz']}, cell {r['cell_m'] * 1e3:.4g} mm",
        f"  Jacobian figures with lengths in units of {u:g} m (dl = J [v; w], base frame)",
        "  inside: within the stroke and joint limits, the joint cones and free of collision (no strut"
        " touches another, a housing or a plate); limits only: without the cones and collisions",
        f"{'':24s}{'ours':>14s}{'paper':>12s}",
    ]
    p = r["paper"] or {}
    rows = [
        ("volume (cm^3)", r["volume_paper_units3"], p.get("volume")),
        ("volume (m^3)", r["volume_m3"], None),
        ("points inside", r["points_inside"], None),
        ("  limits only (cm^3)", r["volume_limits_paper_units3"], None),
        ("  limits only (points)", r["points_inside_limits"], None),
        ("mean kappa", r["average"]["kappa"], p.get("kappa")),
        ("mean sigma_min", r["average"]["sigma_min"], p.get("sigma_min")),
        ("mean |det J|", r["average"]["abs_det"], p.get("abs_det")),
        ("home kappa", r["home"]["kappa"], None),
        ("home sigma_min", r["home"]["sigma_min"], None),
        ("home |det J|", r["home"]["abs_det"], None),
    ]
    for name, ours, paper in rows:
        lines.append(f"  {name:22s}{ours:14.5g}{(f'{paper:12.5g}' if paper is not None else ''):>12s}")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """``hexapod evaluate``."""
    if args.detectability:
        return run_detectability(args)
    if args.place_seventh_leg or args.place_inclinometer:
        return run_placement(args)
    if args.json:
        check_output_path(args.json, args.hexapod)
    settings = Settings(args.grid, args.cone_deg, args.cone_samples, args.length_unit)
    if args.workers is not None and args.workers < 1:
        raise InputError("--workers", args.workers, "need at least 1")
    hexa = load_hexapod(args.hexapod)  # fails here, with one line, before any worker starts
    bar = stream_bar("evaluate (z slices)", unit="slice")  # shows itself on a terminal only

    def show_dashboard(client) -> None:
        link = dashboard_link(client)
        if link:
            note("evaluate", f"Dask dashboard: {link}")

    def on_slice(done: int, total: int) -> None:
        bar.total = total
        bar.n = done
        bar.refresh()

    try:
        r = run_evaluation(args.hexapod, settings, args.out, args.workers, on_slice, args.scheduler, show_dashboard)
    except KeyboardInterrupt:
        where = f"; rerun with --out {args.out} to resume" if args.out else ""
        note("evaluate", f"interrupted; finished slices saved{where}")
        return 130
    finally:
        bar.close()
    r["home_z"] = float(hexa.home_pose[2, 3])
    print(format_report(r))
    if args.out:
        require_extra("plots")
        from ..plots.evaluate import plot_sections

        png = Path(args.out) / "evaluate_sections.png"
        plot_sections(r, png)
        print(f"  figure: {png}" + (f" (resumed {r['resumed_slices']} slices)" if r["resumed_slices"] else ""))
    if args.json:
        atomic_write_text(args.json, json.dumps({k: v for k, v in r.items() if not k.startswith("_")}, indent=2) + "\n")
    return 0
