"""A meshcat scene of a hexapod (and optionally its robot cell), separate from any output.

The hexapod is drawn from the URDF's own visuals through Pinocchio's geometry model: base
and top plates, each leg's cylinder and rod, the Cardan joint blocks with pins along both
(offset) axes, and the platform's frame triad. Frames: the scene's world is the hexapod base
frame, z up, metres.

In a notebook::

    from hexapod_model import Hexapod
    from hexapod_model.meshcat_scene import HexapodScene, start_visualizer

    hexa = Hexapod.from_preset("reference")
    scene = HexapodScene(hexa, start_visualizer())
    scene.show(hexa.forward([0.02, 0, 0, 0, 0, 0]))
    scene.vis.render_static()          # or scene.vis.url()
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..exceptions import ViewError
from ..extras import require
from ..kinematics.hexapod import Hexapod
from ..kinematics.newton.solver import Solution

SCENE_CENTRE = (0.0, 0.0, 0.22)  # m, base frame: the point shown at the centre of the view
DEFAULT_CAMERA = (0.46, 0.34, 0.46)  # m, camera position relative to the centre, meshcat's three.js axes (y up)


def _require_meshcat():
    require("meshcat", "view")
    try:
        from pinocchio.visualize import MeshcatVisualizer  # noqa: F401
    except ImportError as exc:  # pragma: no cover - Pinocchio without its visualizers
        raise ViewError(f"the 3-D view needs pinocchio.visualize ({exc})") from None


@dataclass
class HexapodScene:
    """A hexapod loaded into a meshcat visualizer under ``/hexapod``.

    Attributes:
        hexapod: the model shown.
        vis: the ``meshcat.Visualizer`` (its server is local, 127.0.0.1).
        camera: camera position relative to the view centre, in meshcat's three.js axes (m).
        centre: point of the base frame shown at the centre of the view (m); the meshcat
            world is the base frame shifted by ``-centre``.
    """

    hexapod: Hexapod
    vis: Any
    camera: tuple[float, float, float] = DEFAULT_CAMERA
    centre: tuple[float, float, float] = SCENE_CENTRE

    def __post_init__(self) -> None:
        _require_meshcat()
        from pinocchio.visualize import MeshcatVisualizer

        m = self.hexapod.model
        visual = self.hexapod.closed_loop.visual_model()  # from its URDF or MJCF
        self.viz = MeshcatVisualizer(m, visual, visual)
        self.viz.initViewer(viewer=self.vis)
        self.viz.loadViewerModel(rootNodeName="hexapod")
        style_scene(self.vis, self.camera)
        self.recentre(self.centre)
        self.show(self.hexapod.q_home)

    @property
    def world(self) -> np.ndarray:
        """4x4 placement of the hexapod base frame in the meshcat world."""
        T = np.eye(4)
        T[:3, 3] = -np.asarray(self.centre, dtype=float)
        return T

    def recentre(self, centre) -> None:
        """Show the base-frame point ``centre`` (m) at the centre of the view."""
        x, y, z = (float(c) for c in centre)
        self.centre = (x, y, z)
        self.vis["hexapod"].set_transform(self.world)

    def show(self, configuration: Solution | np.ndarray) -> None:
        """Display a :class:`Solution` or a Pinocchio configuration ``q`` of the hexapod."""
        q = configuration.q if isinstance(configuration, Solution) else np.asarray(configuration, dtype=float)
        if q.shape != (self.hexapod.closed_loop.nq,):
            raise ViewError(f"configuration of {q.shape[0]} values, the model has nq = {self.hexapod.closed_loop.nq}")
        self.viz.display(q)


def start_visualizer():
    """A ``meshcat.Visualizer`` with its own server on 127.0.0.1 (its URL: ``vis.url()``)."""
    _require_meshcat()
    import contextlib
    import io

    import meshcat

    with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints the URL itself
        return meshcat.Visualizer()


def stop_visualizer(vis) -> None:
    """Stop the server that :func:`start_visualizer` started."""
    proc = getattr(vis.window, "server_proc", None)
    if proc is not None and proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=5)
        except Exception:  # noqa: BLE001 - last resort
            proc.kill()


def style_scene(vis, camera=DEFAULT_CAMERA) -> None:
    """White background, no grid or world axes, camera near the hexapod."""
    vis["/Background"].set_property("top_color", [1.0, 1.0, 1.0])
    vis["/Background"].set_property("bottom_color", [1.0, 1.0, 1.0])
    vis["/Grid"].set_property("visible", False)
    vis["/Axes"].set_property("visible", False)
    vis["/Cameras/default/rotated/<object>"].set_property("position", list(camera))


def solve_view_configuration(hexa: Hexapod, lengths=None, pose_xyz_rpy=None) -> Solution:
    """The configuration to show.

    The configuration to show: FK of ``lengths`` (m), IK of ``pose_xyz_rpy`` =
    ``(x, y, z, roll, pitch, yaw)`` in metres and degrees as ``hexapod fk`` writes it
    (``R = Rz(yaw) Ry(pitch) Rx(roll)``), or home when both are None.
    """
    from ..lie import xyz_rpy_to_pose

    if lengths is not None and pose_xyz_rpy is not None:
        raise ViewError("give either leg lengths or a pose, not both")
    if lengths is not None:
        return hexa.forward(lengths)
    if pose_xyz_rpy is not None:
        v = np.asarray(pose_xyz_rpy, dtype=float)
        if v.shape != (6,):
            raise ViewError(f"a pose is X Y Z ROLL PITCH YAW (6 numbers), got {v.size}")
        return hexa.inverse(xyz_rpy_to_pose(v))
    return hexa.forward(np.zeros(6))
