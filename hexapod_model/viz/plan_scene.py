"""A changeover plan in meshcat: the UR10 and every fixture's hexapod, frame by frame.

The meshcat world is the robot's base frame. Each fixture's hexapod stands at its
``base_in_robot`` (node ``/fixture_NAME``); while it is carried its platform follows the plan's
``platform_pose`` (by inverse kinematics, each frame started from the previous one), before its
carry it holds its start pose and after it its target. The UR10 (node ``/ur10``) takes each
point's ``q``.
"""

from __future__ import annotations

import numpy as np

from ..extras import require_extra
from ..kinematics.hexapod import load_hexapod
from ..planning.model import Plan
from .meshcat_scene import style_scene
from .robot_cell import CellPose, add_ur10

PLAN_CAMERA = (1.5, 1.1, 1.0)  # m, three.js axes (y up): behind the robot, looking at the cell


class PlanScene:
    """The cell of a :class:`~hexapod_model.planning.Plan` in the meshcat visualizer ``vis``.

    Args:
        plan: the plan.
        vis: a ``meshcat.Visualizer``.
    """

    def __init__(self, plan: Plan, vis):
        require_extra("view")
        from pinocchio.visualize import MeshcatVisualizer

        self.plan, self.vis = plan, vis
        self.hexapods = {f.name: load_hexapod(f.hexapod) for f in plan.fixtures}
        self._views, self._q = {}, {}
        self._held = {}
        for f in plan.fixtures:
            hexa = self.hexapods[f.name]
            visual = hexa.closed_loop.visual_model()
            view = MeshcatVisualizer(hexa.model, visual, visual)
            view.initViewer(viewer=vis)
            view.loadViewerModel(rootNodeName=f"fixture_{f.name}")
            vis[f"fixture_{f.name}"].set_transform(f.base_in_robot)
            self._views[f.name] = view
            self._held[f.name] = (hexa.inverse(f.start).q, hexa.inverse(f.target).q)
            self._q[f.name] = self._held[f.name][0]
        carried = [k for k, p in enumerate(plan.phase) if p == "carry"]
        self._carry_end = {f.name: max(k for k in carried if plan.fixture[k] == f.name) for f in plan.fixtures}
        self.robot = add_ur10(vis, CellPose(plan.q[0], np.eye(4), 0.0), world=np.eye(4), base=np.eye(4))
        style_scene(vis, camera=PLAN_CAMERA)
        self.show(0)

    def show(self, k: int) -> None:
        """Display the plan's point ``k``."""
        plan = self.plan
        self.robot.display(plan.q[k])
        for name, view in self._views.items():
            if plan.phase[k] == "carry" and plan.fixture[k] == name:
                import pinocchio as pin

                pose = pin.XYZQUATToSE3(plan.platform_pose[k]).homogeneous
                q = self.hexapods[name].inverse(pose, self._q[name]).q
            else:
                q = self._held[name][1 if k > self._carry_end[name] else 0]
            self._q[name] = q
            view.display(q)


def key_frames(plan: Plan) -> list[tuple[int, str]]:
    """``(index, label)`` of the plan's key frames: its start, each carry's start and end, its end."""
    frames = [(0, "start")]
    for name in plan.order:
        rows = [k for k, (p, f) in enumerate(zip(plan.phase, plan.fixture)) if p == "carry" and f == name]
        frames += [(rows[0], f"{name}_carry_start"), (rows[-1], f"{name}_carry_end")]
    return [*frames, (len(plan.t) - 1, "end")]
