"""``hexapod view`` (live meshcat server) and ``hexapod snapshot`` (static HTML and PNG)."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from .presets import DEFAULT_PRESET
from .solver import Solution


def _pose_options(p) -> None:
    p.add_argument("urdf", nargs="?", default=DEFAULT_PRESET, metavar="URDF|PRESET",
                   help=f"URDF file or preset name (default {DEFAULT_PRESET})")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--lengths", nargs=6, type=float, metavar="L", help="six leg readings (m, zero at home): solve FK")
    g.add_argument("--pose", nargs=6, type=float, metavar=("X", "Y", "Z", "ROLL", "PITCH", "YAW"),
                   help="platform pose as `hexapod fk` writes it: metres and degrees, R = Rz(yaw) Ry(pitch) Rx(roll)")
    p.add_argument("--cell", action="store_true", help="add the UR10 coupled to the top plate (seed 000 §5.5)")


def register(sub) -> None:
    p = sub.add_parser("view", help="show the hexapod in a local meshcat server (prints the URL)")
    _pose_options(p)
    p.add_argument("--play", metavar="CSV", help="animate a CSV of poses (x,y,z + quaternion or roll,pitch,yaw) "
                                                 "or of leg readings (l1..l6), solving as it goes")
    p.add_argument("--rate", type=float, default=50.0, help="animation rows per second (default 50)")
    p.add_argument("--once", action="store_true", help="show (and play) then exit instead of serving until Ctrl-C")
    p.set_defaults(func=run_view)

    p = sub.add_parser("snapshot", help="write the scene as self-contained HTML and, with --png, a PNG")
    _pose_options(p)
    p.add_argument("-o", "--output", required=True, metavar="SCENE.html", help="static HTML (opens with no server)")
    p.add_argument("--png", metavar="SCENE.png", help="also render a PNG with headless Chromium")
    p.add_argument("--size", default="1280x960", help="PNG size WIDTHxHEIGHT in pixels (>= 1024x768)")
    p.set_defaults(func=run_snapshot)


def build(args, vis):
    """Scene of ``args`` (hexapod, pose, optional cell) in the visualizer ``vis``."""
    from .cli import load_hexapod
    from .meshcat_scene import HexapodScene, solve_view_configuration

    hexa = load_hexapod(args.urdf)
    sol = solve_view_configuration(hexa, args.lengths, args.pose)
    scene = HexapodScene(hexa, vis)
    scene.show(sol)
    if args.cell:
        add_cell(scene, sol)
    return scene, sol


def add_cell(scene, sol: Solution) -> None:
    """Add the UR10 coupled to the plate at ``sol`` and widen the camera to show both."""
    from . import robot_cell
    from .meshcat_scene import style_scene

    scene.recentre((0.4, 0.0, 0.4))
    robot_cell.add_ur10(scene.vis, robot_cell.couple_to_plate(sol.pose), world=scene.world)
    style_scene(scene.vis, camera=(0.72, 0.46, 0.72))


def play_frames(hexa, path: str | Path) -> list[Solution]:
    """Solutions of every row of a pose or leg-reading CSV, each started from the previous good one.

    Rows that do not solve (NaN, out of limits, ...) are skipped with a note on stderr."""
    from .exceptions import HexapodError
    from .tables import LENGTH_COLUMNS, column, poses_from_table, read_table

    header, data = read_table(path)
    if all(c in header for c in LENGTH_COLUMNS):
        inputs, solve = column(header, data, LENGTH_COLUMNS), hexa.forward
    else:
        inputs, solve = poses_from_table(header, data), hexa.inverse
    frames, guess = [], None
    for k, x in enumerate(inputs):
        try:
            guess = solve(x, guess=guess)
            frames.append(guess)
        except HexapodError as exc:
            print(f"hexapod view: row {k + 1} skipped: {exc}", file=sys.stderr)
    return frames


def run_view(args) -> int:
    from .meshcat_scene import start_visualizer, stop_visualizer

    vis = start_visualizer()
    try:
        return _serve(args, vis)
    finally:
        stop_visualizer(vis)


def _serve(args, vis) -> int:
    scene, _ = build(args, vis)
    print(f"meshcat: {vis.url()}", flush=True)
    if args.play:
        frames = play_frames(scene.hexapod, args.play)
        for sol in frames:
            scene.show(sol)
            time.sleep(1.0 / args.rate)
        print(f"played {len(frames)} frames", file=sys.stderr)
    if not args.once:
        print("serving; press Ctrl-C to stop", file=sys.stderr)
        try:
            while True:
                time.sleep(1.0)
        except KeyboardInterrupt:
            pass
    return 0


def parse_size(text: str) -> tuple[int, int]:
    from .exceptions import ViewError

    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise ViewError(f"--size {text!r}: expected WIDTHxHEIGHT, e.g. 1280x960") from None
    return w, h


def run_snapshot(args) -> int:
    from .meshcat_scene import start_visualizer, stop_visualizer
    from .render import render_pngs, write_html

    size = parse_size(args.size)
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


def pixels(png: str | Path) -> np.ndarray:
    """(H, W, 3) uint8 pixels of a PNG (for checks and tests)."""
    from PIL import Image

    return np.asarray(Image.open(png).convert("RGB"))
