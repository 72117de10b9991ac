"""``hexapod changeover plan``: the UR10's changeover of the fixtures to their targets (docs/planning.md)."""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

from ..exceptions import InputError
from ._common import note


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``hexapod changeover plan``."""
    p = sub.add_parser("changeover", help="plan the robot's changeover of the fixtures (plan.json, CSV, MCAP)")
    actions = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    a = actions.add_parser(
        "plan",
        help="a UR10 carries each plate from its lock pose to its target: checked, timed, ordered",
        description="Plans approach, couple, release_brakes, carry, lock_brakes, decouple, retract per fixture "
        "(docs/planning.md). Exit 1 with one line when no valid path exists.",
    )
    a.add_argument(
        "config", metavar="FIXTURE.toml", help="the service's configuration, with [fixtures.cell] per fixture"
    )
    src = a.add_mutually_exclusive_group()
    src.add_argument("--recipe", metavar="NAME", help="a recipe stored in the service's store")
    src.add_argument("--recipe-file", metavar="FILE", help="a recipe file's targets (TOML or JSON), not stored")
    a.add_argument(
        "--fixture", action="append", metavar="NAME", help="only these fixtures (repeat; default all with a target)"
    )
    start = a.add_mutually_exclusive_group()
    start.add_argument("--live", action="store_true", help="start from the poses the running service reports")
    start.add_argument("--from-home", action="store_true", help="start from each hexapod's home pose")
    a.add_argument("-o", "--out", required=True, metavar="PLAN.json", help="the plan (JSON)")
    a.add_argument("--csv", metavar="FILE", help="also the points as CSV")
    a.add_argument("--mcap", metavar="FILE", help="also a trajectory_msgs/JointTrajectory in an MCAP file (ros extra)")
    a.add_argument("--plot", metavar="FILE.png", help="also a figure of the joints and the carried legs (plots extra)")
    a.add_argument(
        "--carry-speed", type=float, default=50.0, metavar="MM_S", help="plate speed while carried (default 50)"
    )
    a.add_argument("--carry-rate", type=float, default=10.0, metavar="DEG_S", help="plate rotation rate (default 10)")
    a.add_argument(
        "--carry-jerk",
        type=float,
        metavar="M_S3",
        help="plate and leg jerk while carried (default 0.3: what the tracker of a 50 Hz plate tolerates)",
    )
    a.add_argument("--min-singularity-margin", type=float, default=0.2, help="the hexapod's, 1 at home (default 0.2)")
    a.add_argument("--min-clearance", type=float, default=20.0, metavar="MM", help="arm to hexapods (default 20)")
    a.set_defaults(func=run_plan)


def _positive(name: str, value: float) -> float:
    if not (math.isfinite(value) and value > 0.0):
        raise InputError(name, value, "expected a number above 0")
    return value


def _targets(args: argparse.Namespace, config, hexapods: dict) -> dict:
    """``fixture -> 4x4 target`` from the recipe, the recipe file or the stored current targets.

    Each is checked as the service checks a target (stored ones too: the geometry may have
    changed since): a ``TargetError`` names one outside the workspace, in collision, beyond a
    joint cone or outside the operating envelope.
    """
    from ..service.store import Store
    from ..service.targets.target import reachable, recipe_from_json
    from .changeover import read_recipe

    if args.recipe_file:
        body = {"targets": read_recipe(args.recipe_file)}
        recipe = recipe_from_json(body, Path(args.recipe_file).stem, hexapods, "plan", time.time())
        return {k: t.pose for k, t in recipe.targets.items()}
    with Store(config.store.path, create=False) as store:
        if args.recipe:
            recipes = store.targets.recipes()
            if args.recipe not in recipes:
                raise InputError(
                    "--recipe", args.recipe, f"no such recipe in {config.store.path} ({', '.join(recipes) or 'none'})"
                )
            recipe = recipe_from_json(recipes[args.recipe][0], args.recipe, hexapods, "plan", time.time())
            return {k: t.pose for k, t in recipe.targets.items()}
        current = store.targets.current_targets()
    for k, t in current.items():
        if k in hexapods:
            reachable(hexapods[k], t.pose, f"stored target {t.id} of {k}", k)
    return {k: t.pose for k, t in current.items()}


def _starts(args: argparse.Namespace, config, names: list[str], hexapods: dict) -> dict:
    """``fixture -> 4x4 start pose``: home, the running service's poses or the stored lock poses."""
    import numpy as np

    from ..lie import quaternion_to_matrix

    if args.from_home:
        return {n: hexapods[n].home_pose for n in names}
    out = {}
    if args.live:
        from ..service.http.client import ServiceClient

        client = ServiceClient.for_config(config)
        for n in names:
            g = client.guidance(n)
            if g["pose"] is None or g["status"] != "ok":
                raise InputError(
                    "--live", n, f"the service reports no good pose for fixture '{n}' (status {g['status']})"
                )
            p = g["pose"]
            T = np.eye(4)
            T[:3, 3], T[:3, :3] = (
                (p["x"], p["y"], p["z"]),
                quaternion_to_matrix(np.array([p[k] for k in ("qx", "qy", "qz", "qw")])),
            )
            out[n] = T
        return out
    from ..service.store import Store

    with Store(config.store.path, create=False) as store:
        for n in names:
            lock = store.last_lock(n)
            if lock is None:
                raise InputError(
                    "fixture", n, "has no stored lock pose: lock it under `hexapod serve`, or use --live or --from-home"
                )
            T = np.eye(4)
            T[:3, 3], T[:3, :3] = lock.position, quaternion_to_matrix(lock.quaternion)
            out[n] = T
    return out


def run_plan(args: argparse.Namespace) -> int:
    """``hexapod changeover plan``."""
    from ..extras import require_extra
    from ..files import check_output_path
    from ..service import load_config

    require_extra("plan")
    from ..planning import Blocked, FixtureCell, Move, Settings, plan_changeover
    from ..planning.scurve import DEFAULT_CARRY_JERK
    from ..planning.writers import write_plan_csv, write_plan_json

    speed, rate = _positive("--carry-speed", args.carry_speed), _positive("--carry-rate", args.carry_rate)
    jerk = DEFAULT_CARRY_JERK if args.carry_jerk is None else _positive("--carry-jerk", args.carry_jerk)
    settings = Settings(
        min_singularity_margin=_positive("--min-singularity-margin", args.min_singularity_margin),
        min_clearance=_positive("--min-clearance", args.min_clearance) * 1e-3,
    )
    if args.plot:
        require_extra("plots")
    outs = [check_output_path(p, args.config) for p in (args.out, args.csv, args.mcap, args.plot) if p]
    config = load_config(args.config)
    known = [f.name for f in config.fixtures]
    for n in args.fixture or ():
        if n not in known:
            raise InputError("--fixture", n, f"no such fixture in {args.config} ({', '.join(known)})")
    chosen = args.fixture or known
    hexapods = {f.name: f.load_hexapod() for f in config.fixtures}
    targets = {k: v for k, v in _targets(args, config, hexapods).items() if k in chosen}
    if not targets:
        raise InputError("targets", None, "no fixture has a target to move to")
    names = [n for n in known if n in targets]
    for n in names:
        if config.fixture(n).cell is None:
            raise InputError("fixture", n, f"has no [fixtures.cell] in {args.config}: the robot cannot find it")
    starts = _starts(args, config, names, hexapods)
    moves = []
    for n in names:
        f = config.fixture(n)
        cell = FixtureCell(n, f.hexapod, f.cell.base_in_robot, f.cell.coupling, starts[n], targets[n])  # type: ignore[union-attr]
        moves.append(Move(cell, hexapods[n], speed * 1e-3, math.radians(rate), jerk))
    try:
        plan = plan_changeover(moves, settings)
    except Blocked as exc:
        print(f"hexapod changeover: no valid path: {exc}", file=sys.stderr)
        return 1
    write_plan_json(plan, outs[0])
    if args.csv:
        write_plan_csv(plan, args.csv)
    if args.mcap:
        from ..extras import MissingExtraError
        from ..ros.trajectory import write_trajectory_mcap

        try:
            write_trajectory_mcap(plan, args.mcap)
        except MissingExtraError as exc:
            note("changeover", f"no MCAP written: {exc}")
    if args.plot:
        from ..planning.robot import Arm
        from ..plots.changeover_plan import plot_plan

        plot_plan(plan, args.plot, Arm.load().velocity)
    m = plan.margins
    print(
        f"{' -> '.join(plan.order)} ({plan.order_method} order): {plan.total_time:.2f} s, {len(plan.t)} points; "
        f"margins: stroke {m.stroke * 1e3:.1f} mm, joint {math.degrees(m.joint):.1f} deg, "
        f"singularity {m.singularity:.2f}, "
        f"arm joint {math.degrees(m.arm_joint):.1f} deg, clearance {m.clearance * 1e3:.0f} mm"
    )
    note("changeover", f"wrote {args.out}")
    return 0
