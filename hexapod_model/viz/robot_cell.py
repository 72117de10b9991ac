"""The robot cell of Bem et al. (2026) §5.5: a UR10 beside the hexapod couples to the top plate.

The UR10 model and meshes come from the installed ``example-robot-data`` distribution (data
only, no network). The robot stands on the floor of the hexapod base frame at
``ROBOT_BASE_XYZ``, facing the hexapod. Its flange frame ``tool0`` is placed at the top plate's
*tool-changer frame*: ``TOOL_CHANGER_HEIGHT`` above the platform origin, z pointing down into
the plate, by a damped least-squares IK on the UR10's Pinocchio model.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..description.ur10 import ur10_files
from ..exceptions import UnreachableError
from ..kinematics.newton.solver import Solution
from .meshcat_scene import HexapodScene

ROBOT_BASE_XYZ = (0.80, 0.0, 0.0)  # m, UR10 base in the hexapod base frame
ROBOT_BASE_YAW = np.pi  # rad: the robot faces the hexapod (its x axis towards -x of the base frame)
TOOL_CHANGER_HEIGHT = 0.07  # m above the platform frame origin (on top of the plate)
UR10_REACH = 1.30  # m, from the shoulder axis (datasheet)
FLANGE_FRAME = "tool0"
Q_START = np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0])  # elbow up, wrist down


def _transform(xyz, yaw: float = 0.0, flip_x: bool = False) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    T = np.eye(4)
    T[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    if flip_x:
        T[:3, :3] = T[:3, :3] @ np.diag([1.0, -1.0, -1.0])
    T[:3, 3] = xyz
    return T


def robot_base_pose() -> np.ndarray:
    """UR10 base placement in the hexapod base frame (4x4, metres)."""
    return _transform(ROBOT_BASE_XYZ, ROBOT_BASE_YAW)


def tool_changer_pose(platform_pose: np.ndarray) -> np.ndarray:
    """Tool-changer frame (4x4, base frame) of a platform pose: on top of the plate, z down."""
    return np.asarray(platform_pose, dtype=float) @ _transform((0.0, 0.0, TOOL_CHANGER_HEIGHT), flip_x=True)


@lru_cache(maxsize=1)
def load_ur10():
    """``(model, visual_model)`` of the UR10 (Pinocchio), loaded once."""
    import pinocchio as pin

    urdf, packages = ur10_files("cell")
    model, _, visual = pin.buildModelsFromUrdf(str(urdf), package_dirs=[str(packages.parent)])
    return model, visual


@dataclass(frozen=True)
class CellPose:
    """UR10 configuration coupling its flange to the plate.

    Attributes:
        q: UR10 joint angles (rad).
        flange: flange pose in the hexapod base frame (4x4, m).
        error: final pose error norm of the IK (m and rad mixed).
    """

    q: np.ndarray
    flange: np.ndarray
    error: float


def couple_to_plate(platform_pose: np.ndarray, tol: float = 1e-6, max_iter: int = 300) -> CellPose:
    """UR10 IK putting ``tool0`` at the tool-changer frame of ``platform_pose``.

    Raises:
        UnreachableError: the pose is beyond the arm's reach, or the damped least-squares IK
            does not converge to ``tol``.
    """
    base = robot_base_pose()
    cell = reach(np.linalg.inv(base) @ tool_changer_pose(platform_pose), tol=tol, max_iter=max_iter)
    return CellPose(cell.q, base @ cell.flange, cell.error)


def reach(target_np: np.ndarray, q_start: np.ndarray | None = None, tol: float = 1e-6, max_iter: int = 300) -> CellPose:
    """UR10 IK putting ``tool0`` at ``target_np`` (4x4 in the robot's base frame); ``flange`` in that frame.

    ``q_start``: the joint configuration to start from (default elbow up, wrist down).

    Raises:
        UnreachableError: beyond the arm's reach, no convergence to ``tol``, or outside the joint limits.
    """
    import pinocchio as pin

    model, _ = load_ur10()
    data = model.createData()
    fid = model.getFrameId(FLANGE_FRAME)
    target = pin.SE3(target_np[:3, :3], target_np[:3, 3])
    shoulder = np.array([0.0, 0.0, 0.1273])
    distance = float(np.linalg.norm(target_np[:3, 3] - shoulder))
    if distance > UR10_REACH:
        raise UnreachableError(
            target_np, distance - UR10_REACH, f"{distance:.3f} m from the shoulder, reach {UR10_REACH} m"
        )
    q, damping, err = (Q_START if q_start is None else np.asarray(q_start, dtype=float)).copy(), 1e-4, np.inf
    for _ in range(max_iter):
        pin.framesForwardKinematics(model, data, q)
        e = pin.log6(data.oMf[fid].actInv(target)).vector  # in the flange frame
        err = float(np.linalg.norm(e))
        if err < tol:
            break
        J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)
        q = pin.integrate(model, q, J.T @ np.linalg.solve(J @ J.T + damping * np.eye(6), e))
    else:
        raise UnreachableError(target_np, err, f"IK stopped at error {err:.2g} after {max_iter} iterations")
    if np.any(q < model.lowerPositionLimit) or np.any(q > model.upperPositionLimit):
        raise UnreachableError(target_np, err, "the solution violates the UR10 joint limits")
    pin.framesForwardKinematics(model, data, q)
    return CellPose(q, data.oMf[fid].homogeneous, err)


def add_ur10(vis, cell: CellPose, world: np.ndarray | None = None, base: np.ndarray | None = None):
    """Draw the UR10.

    Draw the UR10 at ``cell.q`` in the meshcat visualizer ``vis`` (node ``/ur10``);
    ``world`` is the placement of the hexapod base frame in the meshcat world (default identity),
    ``base`` the robot's base in the hexapod base frame (default :func:`robot_base_pose`).
    """
    from pinocchio.visualize import MeshcatVisualizer

    model, visual = load_ur10()
    viz = MeshcatVisualizer(model, visual, visual)
    viz.initViewer(viewer=vis)
    viz.loadViewerModel(rootNodeName="ur10")
    vis["ur10"].set_transform((np.eye(4) if world is None else world) @ (robot_base_pose() if base is None else base))
    viz.display(cell.q)
    return viz


def add_cell(scene: HexapodScene, sol: Solution) -> None:
    """Add the UR10 coupled to the plate at ``sol`` and widen the camera to show both."""
    from .meshcat_scene import style_scene

    scene.recentre((0.4, 0.0, 0.4))
    add_ur10(scene.vis, couple_to_plate(sol.pose), world=scene.world)
    style_scene(scene.vis, camera=(0.72, 0.46, 0.72))
