"""``hexapod fixture target | recipe | locate``: the changeover of a running service, from the command line."""

from __future__ import annotations

import argparse
import csv
import getpass
import json
import tomllib
from pathlib import Path

from ..exceptions import InputError

LOCATE_COLUMNS = ("base_x", "base_y", "base_z", "robot_x", "robot_y", "robot_z")


def register_actions(actions: argparse._SubParsersAction) -> None:
    """Add ``target``, ``recipe`` and ``locate`` to ``hexapod fixture``."""
    t = actions.add_parser(
        "target",
        help="show, set or clear a fixture's target pose (talks to the running service)",
        description="Without --pose or --clear: the guidance (deviation, per-leg changes). docs/changeover.md.",
    )
    t.add_argument("config", metavar="FIXTURE.toml")
    t.add_argument("fixture", metavar="NAME")
    t.add_argument(
        "--pose", nargs=6, type=float, metavar=("X", "Y", "Z", "ROLL", "PITCH", "YAW"), help="m and deg, base frame"
    )
    t.add_argument(
        "--tolerance", nargs=2, type=float, default=(0.1, 0.05), metavar=("MM", "DEG"), help="default 0.1 0.05"
    )
    t.add_argument("--clear", action="store_true", help="clear the target")
    _common(t)
    t.set_defaults(func=run_target)
    r = actions.add_parser("recipe", help="list, store or activate recipes (a target per fixture)")
    r.add_argument("config", metavar="FIXTURE.toml")
    r.add_argument("name", nargs="?", metavar="RECIPE", help="the recipe (without: list them)")
    r.add_argument(
        "--set", metavar="RECIPE.toml", help="store the recipe from a TOML or JSON file ([targets.NAME] ...)"
    )
    r.add_argument("--activate", action="store_true", help="make it the active recipe (its targets become current)")
    _common(r)
    r.set_defaults(func=run_recipe)
    loc = actions.add_parser(
        "locate", help="base_in_robot from three or more points touched by the robot (least squares, residuals)"
    )
    loc.add_argument("points", metavar="POINTS.csv", help=f"columns {', '.join(LOCATE_COLUMNS)} (m)")
    loc.set_defaults(func=run_locate)


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--url", help="the service (default: the configuration's [http] address)")
    p.add_argument("--by", default=None, help="who makes the change (logged; default: the login name)")
    p.add_argument("--operator", dest="by", help=argparse.SUPPRESS)  # the earlier name of --by
    p.add_argument("--json", action="store_true", help="print the service's JSON answer")


def _client(args: argparse.Namespace):
    from ..service import load_config
    from ..service.http.client import ServiceClient

    operator = args.by or getpass.getuser()
    return ServiceClient.for_config(load_config(args.config), operator=operator, url=args.url)


def _print_json(value) -> None:
    print(json.dumps(value, indent=2, allow_nan=False))


def _fmt(v, digits: int = 3) -> str:
    return "-" if v is None else f"{v:.{digits}f}"


def print_guidance(g: dict) -> None:
    """The guidance as lines a person can act on (``extend 2.400 mm`` per leg)."""
    print(f"{g['fixture']}: {g['status']}, {g['state']}{', stored' if g['stored'] else ''}", end="")
    print(f"; flags: {', '.join(g['flags'])}" if g["flags"] else "")
    target = g["target"]
    if target is None:
        print("no target" + (f" ({g['target_problem']})" if g.get("target_problem") else ""))
        return
    p = target["pose"]
    origin = f"recipe {target['recipe']}, " if target["recipe"] else ""
    print(
        f"target {target['id']} ({origin}set by {target['set_by']}): x {p['x']:.6f} y {p['y']:.6f} z {p['z']:.6f} m, "
        f"roll {p['roll']:.4f} pitch {p['pitch']:.4f} yaw {p['yaw']:.4f} deg"
    )
    d, tol, s = g["deviation"], target["tolerance"], g["sigma"]
    if d is not None:
        print(
            f"deviation {d['translation_mm']:.3f} mm, {d['rotation_deg']:.4f} deg "
            f"(target frame: x {d['x_mm']:.3f} y {d['y_mm']:.3f} z {d['z_mm']:.3f} mm, "
            f"rx {d['rx_deg']:.4f} ry {d['ry_deg']:.4f} rz {d['rz_deg']:.4f} deg)"
        )
    sigma = "" if s is None else f"; sigma {s['translation_mm']:.4f} mm, {s['rotation_deg']:.4f} deg"
    verdict = "yes" if g["in_tolerance"] else "no"
    print(f"in tolerance: {verdict} (tolerance {tol['translation_mm']:g} mm, {tol['rotation_deg']:g} deg{sigma})")
    print(f"{'leg':>3s} {'reading mm':>11s} {'target mm':>10s}  change")
    for leg in g["legs"]:
        c = leg["change_mm"]
        change = "-" if c is None else f"{'extend' if c >= 0 else 'retract'} {abs(c):.3f} mm"
        print(f"{leg['leg']:3d} {_fmt(leg['reading_mm']):>11s} {_fmt(leg['target_mm']):>10s}  {change}")


def run_target(args: argparse.Namespace) -> int:
    """``hexapod fixture target``."""
    client = _client(args)
    if args.clear and args.pose:
        raise InputError("--clear", "with --pose", "give one of --pose and --clear")
    if args.clear:
        cleared = client.clear_target(args.fixture)
        print(f"{args.fixture}: target {'cleared' if cleared else 'was not set'}")
        return 0
    if args.pose:
        pose = dict(zip(("x", "y", "z", "roll", "pitch", "yaw"), args.pose))
        client.set_target(args.fixture, pose, *args.tolerance)
    g = client.guidance(args.fixture)
    if args.json:
        _print_json(g)
    else:
        print_guidance(g)
    return 0


def read_recipe(path: str) -> dict:
    """The ``targets`` of a recipe file: TOML (``[targets.NAME.pose]``, ...) or JSON (``{"targets": ...}``)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
        data = json.loads(text) if p.suffix.lower() == ".json" else tomllib.loads(text)
    except OSError as exc:
        raise InputError("--set", path, f"cannot read: {exc.strerror or exc}") from None
    except (ValueError, UnicodeDecodeError) as exc:
        raise InputError(
            "--set", path, f"not valid {'JSON' if p.suffix.lower() == '.json' else 'TOML'}: {exc}"
        ) from None
    if not isinstance(data, dict) or set(data) != {"targets"}:
        raise InputError("--set", path, "expected one table, targets, with a sub-table per fixture")
    return data["targets"]


def run_recipe(args: argparse.Namespace) -> int:
    """``hexapod fixture recipe``."""
    client = _client(args)
    if args.name is None:
        if args.set or args.activate:
            raise InputError("RECIPE", None, "name the recipe to --set or --activate")
        listing = client.recipes()
        if args.json:
            _print_json(listing)
            return 0
        active = listing["active"]
        print(f"active: {active['name']} (by {active['set_by']})" if active else "active: none")
        for name, recipe in listing["recipes"].items():
            print(f"{name}: {', '.join(recipe['targets'])} (stored by {recipe['set_by']})")
        return 0
    if args.set:
        client.put_recipe(args.name, read_recipe(args.set))
        print(f"recipe {args.name} stored")
    if args.activate:
        done = client.activate(args.name)
        print(f"recipe {args.name} active: targets of {', '.join(done['targets'])}")
    if not (args.set or args.activate):
        recipe = client.recipes()["recipes"].get(args.name)
        if recipe is None:
            raise InputError("RECIPE", args.name, "no such recipe")
        _print_json(recipe)
    return 0


def run_locate(args: argparse.Namespace) -> int:
    """``hexapod fixture locate``."""
    import numpy as np

    from ..service.config.cell import locate

    try:
        with open(args.points, newline="", encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
    except OSError as exc:
        raise InputError("POINTS.csv", args.points, f"cannot read: {exc.strerror or exc}") from None
    missing = [c for c in LOCATE_COLUMNS if not rows or c not in rows[0]]
    if missing:
        raise InputError("POINTS.csv", args.points, f"missing column(s) {', '.join(missing)}")
    values = np.empty((len(rows), 6))
    for i, row in enumerate(rows):
        for j, c in enumerate(LOCATE_COLUMNS):
            try:
                values[i, j] = float(row[c])
            except (TypeError, ValueError):
                raise InputError(f"POINTS.csv row {i + 1} {c}", row[c], "expected a number (m)") from None
    found = locate(values[:, :3], values[:, 3:])
    print(
        "base_in_robot = [" + ", ".join(f"{v:.6f}" for v in found.values) + "]   # x, y, z (m), roll, pitch, yaw (deg)"
    )
    for i, r in enumerate(found.residuals):
        print(f"point {i + 1}: residual {r * 1e3:.3f} mm")
    print(f"RMS residual {found.rms * 1e3:.3f} mm over {len(rows)} points")
    return 0
