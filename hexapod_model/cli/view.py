"""``hexapod view`` (live meshcat server) and ``hexapod snapshot`` (static HTML and PNG)."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from pathlib import Path

from ..exceptions import HexapodError, InputError, ViewError
from ..extras import require_extra
from ..files import check_output_path
from ..io.tables import LENGTH_COLUMNS, open_table, pose_input_columns, poses_from_table
from ..kinematics.hexapod import Hexapod
from ..kinematics.newton.solver import Solution
from ._common import add_hexapod_argument, add_pose_argument, hexapod_of, serve_until_interrupted


def _pose_options(p: argparse.ArgumentParser) -> None:
    add_hexapod_argument(p, optional=True)
    g = p.add_mutually_exclusive_group()
    g.add_argument("--lengths", nargs=6, type=float, metavar="L", help="six leg readings (m, zero at home): solve FK")
    add_pose_argument(g, "platform pose as `hexapod fk` writes it: metres and degrees, R = Rz(yaw) Ry(pitch) Rx(roll)")
    p.add_argument(
        "--cell",
        action="store_true",
        help="add the UR10 coupled to the top plate (Bem et al. (2026) §5.5); with --live: placed by the "
        "fixture's [fixtures.cell], its flange at the served pose_in_robot",
    )


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``view`` and ``snapshot``."""
    p = sub.add_parser("view", help="show the hexapod in a local meshcat server (prints the URL)")
    _pose_options(p)
    p.add_argument(
        "--play",
        metavar="CSV",
        help="animate a CSV of poses (x,y,z + quaternion or roll,pitch,yaw) "
        "or of leg readings (l1..l6), solving as it goes",
    )
    p.add_argument("--rate", type=float, default=50.0, help="animation rows per second (default 50)")
    p.add_argument("--once", action="store_true", help="show (and play) then exit instead of serving until Ctrl-C")
    p.add_argument(
        "--live", action="store_true", help="HEXAPOD is a fixture.toml: show the poses its running service serves"
    )
    p.add_argument("--fixture", help="with --live: the fixture to show (default: the first)")
    p.add_argument("--plan", metavar="PLAN.json", help="animate a changeover plan: the UR10 and the hexapods")
    p.set_defaults(func=run_view)

    p = sub.add_parser("snapshot", help="write the scene as self-contained HTML and, with --png, a PNG")
    _pose_options(p)
    p.add_argument("-o", "--output", required=True, metavar="SCENE.html", help="static HTML (opens with no server)")
    p.add_argument("--png", metavar="SCENE.png", help="also render a PNG with headless Chromium")
    p.add_argument("--size", default="1280x960", help="PNG size WIDTHxHEIGHT in pixels (>= 1024x768)")
    p.add_argument(
        "--plan", metavar="PLAN.json", help="a changeover plan's key frames: one file per frame, OUTPUT_NN_LABEL.html"
    )
    p.set_defaults(func=run_snapshot)


def build(args: argparse.Namespace, vis):
    """Scene of ``args`` (hexapod, pose, optional cell) in the visualizer ``vis``."""
    require_extra("view")
    from ..viz.meshcat_scene import HexapodScene, solve_view_configuration

    hexa = hexapod_of(args)
    sol = solve_view_configuration(hexa, args.lengths, args.pose)
    scene = HexapodScene(hexa, vis)
    scene.show(sol)
    if args.cell:
        from ..viz.robot_cell import add_cell

        add_cell(scene, sol)
    return scene, sol


def play_frames(hexa: Hexapod, path: str | Path) -> list[Solution]:
    """Solutions of every row of a pose or leg-reading CSV, each started from the previous good one.

    Rows that are invalid or do not solve (NaN, out of limits, ...) are skipped with a note on stderr.
    """
    solve: Callable[..., Solution]
    with open_table(path) as table:
        if all(c in table.header for c in LENGTH_COLUMNS):
            rows = table.read(LENGTH_COLUMNS)
            inputs, errors, solve = rows.values, rows.errors, hexa.forward
        else:
            columns = pose_input_columns(table.header)
            rows = table.read(columns)
            inputs, pose_errors = poses_from_table(columns, rows.values)
            errors, solve = [a or b for a, b in zip(rows.errors, pose_errors)], hexa.inverse
    frames, guess = [], None
    for k, x in enumerate(inputs):
        why = errors[k]
        if not why:
            try:
                guess = solve(x, guess=guess)
                frames.append(guess)
                continue
            except HexapodError as exc:
                why = str(exc)
        print(f"hexapod view: row {k + 1} skipped (line {rows.lines[k]}): {why}", file=sys.stderr)
    return frames


def run_view(args: argparse.Namespace) -> int:
    """``hexapod view``."""
    if args.live:
        from .live import run_live

        return run_live(args)
    if args.plan:
        from .plan_view import run_view_plan

        return run_view_plan(args)
    require_extra("view")
    from ..viz.meshcat_scene import start_visualizer, stop_visualizer

    vis = start_visualizer()
    try:
        return _serve(args, vis)
    finally:
        stop_visualizer(vis)


def _serve(args: argparse.Namespace, vis) -> int:
    scene, _ = build(args, vis)
    print(f"meshcat: {vis.url()}", flush=True)
    if args.play:
        frames = play_frames(scene.hexapod, args.play)
        for sol in frames:
            scene.show(sol)
            time.sleep(1.0 / args.rate)
        print(f"played {len(frames)} frames", file=sys.stderr)
    if not args.once:
        serve_until_interrupted()
    return 0


def parse_size(text: str) -> tuple[int, int]:
    """``WIDTHxHEIGHT`` in pixels."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise ViewError(f"--size {text!r}: expected WIDTHxHEIGHT, e.g. 1280x960") from None
    return w, h


def run_snapshot(args: argparse.Namespace) -> int:
    """``hexapod snapshot``."""
    require_extra("view")
    size = parse_size(args.size)
    if args.png:  # a size below the minimum is named before a missing Chromium is
        from ..viz.render import check_size

        check_size(size)
    if args.plan:
        from .plan_view import run_snapshot_plan

        return run_snapshot_plan(args, size)
    from ..viz.meshcat_scene import start_visualizer, stop_visualizer
    from ..viz.render import find_chromium, render_pngs, write_html

    check_output_path(args.output, args.hexapod)
    if args.png:
        check_output_path(args.png, args.hexapod, args.output)
        if Path(args.png).resolve() == Path(args.output).resolve():
            raise InputError("--png", args.png, "is the HTML output too; name another file")
        find_chromium()  # no Chromium: fail before the HTML is written
    vis = start_visualizer()
    try:
        build(args, vis)
        html = write_html(vis, args.output)
    finally:
        stop_visualizer(vis)
    print(f"wrote {html}", file=sys.stderr)
    if args.png:
        render_pngs([html], [args.png], size=size)
        print(f"wrote {args.png}", file=sys.stderr)
    return 0
