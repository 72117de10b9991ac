"""The live 3-D view of a served fixture: ``hexapod view FIXTURE.toml --live`` and ``hexapod serve --view``."""

from __future__ import annotations

import argparse
import json
import sys
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Callable

import numpy as np

from ..exceptions import HexapodError
from ..extras import require_extra
from ..kinematics.hexapod import Hexapod
from ..lie import quaternion_to_matrix
from ..service.record.pose_record import PoseRecord
from ._common import note

FRAME_S = 0.05  # the view's refresh period
ONCE_S = 30.0  # --once gives up after this long without a pose (the meshcat server's start included)


def pose_of_record(record: dict | None) -> np.ndarray | None:
    """The 4x4 pose (base -> platform, m) of a published record, or None when it has none."""
    if not record or not record.get("pose"):
        return None
    p = record["pose"]
    T = np.eye(4)
    T[:3, :3] = quaternion_to_matrix([p["qx"], p["qy"], p["qz"], p["qw"]])
    T[:3, 3] = [p["x"], p["y"], p["z"]]
    return T


def live_view(
    hexa: Hexapod,
    latest: Callable[[], dict | PoseRecord | None],
    stop: threading.Event,
    deadline: float | None = None,
    count: int | None = None,
    cell=None,
) -> int:
    """Show the pose of ``latest()`` (a record) in a local meshcat view.

    Until ``stop`` is set, the monotonic clock passes ``deadline``, or ``count`` poses were shown.
    Poses are shown through inverse kinematics (warm started); returns the number shown. With
    ``cell`` (the fixture's :class:`~hexapod_model.service.config.cell.Cell`) the UR10 stands where
    ``base_in_robot`` puts it and its flange follows the record's ``pose_in_robot``.
    """
    from ..viz.meshcat_scene import HexapodScene, start_visualizer, stop_visualizer

    vis = start_visualizer()
    shown, last_t, guess = 0, None, None
    try:
        scene = HexapodScene(hexa, vis)
        robot = None if cell is None else _Robot(scene, cell)
        print(f"meshcat: {vis.url()}", flush=True)
        while not stop.is_set() and (deadline is None or time.monotonic() < deadline) and shown != count:
            rec = latest()
            if isinstance(rec, PoseRecord):  # the service's own (else the JSON object of GET .../pose)
                rec = rec.to_dict()
            T = pose_of_record(rec)
            if T is not None and rec is not None and rec["t"] != last_t:
                last_t = rec["t"]
                try:
                    guess = hexa.inverse(T, guess=guess)
                    scene.show(guess)
                    shown += 1
                    if robot is not None:
                        robot.show(rec)
                except HexapodError as exc:
                    note("view", f"pose at t={rec['t']} not shown: {exc}")
            stop.wait(FRAME_S)
    finally:
        stop_visualizer(vis)
    return shown


class _Robot:
    """The UR10 of ``hexapod view --live --cell``: placed by ``base_in_robot``, its flange at ``pose_in_robot``."""

    def __init__(self, scene, cell):
        self.scene, self.cell = scene, cell
        self.base = np.linalg.inv(cell.base_in_robot)  # the robot's base in the hexapod base frame
        self.viz = None
        self.q = None
        self.failed = False

    def show(self, record: dict) -> None:
        from ..viz.robot_cell import add_ur10, reach

        placed = record.get("pose_in_robot")
        target = pose_of_record(placed)
        if target is None:
            return
        try:
            cell = reach(target, self.q)
        except HexapodError as exc:
            if not self.failed:
                note("view", f"UR10 not shown at pose_in_robot: {exc}")
            self.failed = True
            return
        self.q = cell.q
        if self.viz is None:
            self.scene.recentre((0.4, 0.0, 0.4))
            self.viz = add_ur10(self.scene.vis, cell, world=self.scene.world, base=self.base)
            sigma = (placed or {}).get("sigma") or {}
            note("view", f"UR10 flange at pose_in_robot (IK error {cell.error:.1e}; sigma {sigma})")
        else:
            self.viz.display(cell.q)


def run_live(args: argparse.Namespace) -> int:
    """``hexapod view FIXTURE.toml --live``: poll a running service over HTTP and show its poses."""
    require_extra("view")
    require_extra("service")
    from ..service import load_config

    config = load_config(args.hexapod)
    name = args.fixture or config.fixtures[0].name
    try:
        hexa = config.fixture(name).load_hexapod()
    except KeyError:
        raise HexapodError(f"--fixture {name!r}: not a fixture of {args.hexapod}") from None
    cell = None
    if getattr(args, "cell", False):
        cell = config.fixture(name).cell
        if cell is None:
            raise HexapodError(f"--cell: fixture {name!r} of {args.hexapod} has no [fixtures.cell] base_in_robot")
    url = f"http://{config.http.host}:{config.http.port}/fixtures/{name}/pose"
    headers = {"Authorization": f"Bearer {config.http.token}"} if config.http.token else {}
    errors: list[str] = []

    def latest() -> dict | None:
        try:
            with urllib.request.urlopen(urllib.request.Request(url, headers=headers), timeout=1.0) as r:
                return json.load(r)
        except (urllib.error.URLError, OSError, ValueError) as exc:
            if not errors:
                print(f"hexapod view: {url}: {exc} (is `hexapod serve` running?)", file=sys.stderr)
            errors.append(str(exc))
            return None

    stop = threading.Event()
    try:  # --once: the first pose served, or nothing after ONCE_S
        shown = live_view(
            hexa, latest, stop, time.monotonic() + ONCE_S if args.once else None, 1 if args.once else None, cell
        )
    except KeyboardInterrupt:
        return 0
    print(f"hexapod view: showed {shown} poses of {name} from {url}", file=sys.stderr)
    return 0 if shown or not args.once else 1
