"""The UR10 of example-robot-data: its Pinocchio model, forward kinematics, one-branch IK and its singularities.

The arm carries the plate with its flange ``tool0`` on the plate's coupling frame. Its inverse
kinematics is a damped least-squares Newton iteration on Pinocchio (``reach``); along a carry it
is continued from the previous sample's joints, so it stays on the branch it started on.
:func:`branch` names that branch (shoulder, elbow, wrist signs) and :func:`singularity_margins`
how far each of the arm's three singularities is: the wrist (``|sin q5|``), the elbow
(``|sin q3|``) and the shoulder (the wrist centre's distance, m, from the axis of joint 1).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..description.ur10 import ur10_files
from ..exceptions import UnreachableError

FLANGE_FRAME = "tool0"
WRIST_FRAME = "wrist_2_link"
#: a start configuration of the IK: elbow up, wrist down (rad)
Q_READY = np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0])
REACH = 1.30  # m, from the shoulder (the UR10's datasheet)
SHOULDER = np.array([0.0, 0.0, 0.1273])  # m, the shoulder in the robot's base frame
#: stated joint acceleration limits (rad/s^2): the URDF gives none
ACCELERATION_LIMITS = np.array([2.0, 2.0, 3.0, 3.0, 3.0, 3.0])


def ur10_urdf() -> tuple[Path, Path]:
    """The UR10 URDF of example-robot-data and the folder that resolves its ``package://`` paths.

    Raises:
        MissingExtraError: example-robot-data is not installed (the ``plan`` extra).
    """
    return ur10_files("plan", "the UR10 of changeover planning")


@lru_cache(maxsize=1)
def ur10_models():
    """``(model, collision_model)`` of the UR10 (Pinocchio; collision geometry as coal objects), loaded once."""
    import pinocchio as pin

    urdf, packages = ur10_urdf()
    model, collision, _ = pin.buildModelsFromUrdf(str(urdf), package_dirs=[str(packages.parent)])
    return model, collision


@dataclass(frozen=True)
class Arm:
    """The UR10's kinematics for planning.

    Attributes:
        joint_names: the six joint names (URDF order).
        lower, upper: position limits (rad).
        velocity: velocity limits (rad/s), from the URDF.
        acceleration: acceleration limits (rad/s^2), stated (:data:`ACCELERATION_LIMITS`).
    """

    joint_names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray

    @staticmethod
    def load(acceleration: np.ndarray | None = None) -> Arm:
        """The UR10 of example-robot-data (``plan`` extra)."""
        model, _ = ur10_models()
        acc = ACCELERATION_LIMITS if acceleration is None else np.asarray(acceleration, dtype=float)
        names = tuple(model.names[1:])
        return Arm(
            names, model.lowerPositionLimit.copy(), model.upperPositionLimit.copy(), model.velocityLimit.copy(), acc
        )

    def fk(self, q: np.ndarray) -> np.ndarray:
        """The flange ``tool0`` (4x4, m) in the robot's base frame at joints ``q`` (rad)."""
        import pinocchio as pin

        model, _ = ur10_models()
        data = model.createData()
        pin.framesForwardKinematics(model, data, np.asarray(q, dtype=float))
        return data.oMf[model.getFrameId(FLANGE_FRAME)].homogeneous.copy()

    def fk_many(self, qs: np.ndarray) -> np.ndarray:
        """(n, 4, 4) flange poses (m, robot base frame) of joint rows ``qs`` ((n, 6), rad)."""
        import pinocchio as pin

        model, _ = ur10_models()
        data = model.createData()
        fid = model.getFrameId(FLANGE_FRAME)
        out = np.empty((len(qs), 4, 4))
        for k, q in enumerate(np.asarray(qs, dtype=float)):
            pin.framesForwardKinematics(model, data, q)
            out[k] = data.oMf[fid].homogeneous
        return out

    def reach(self, target: np.ndarray, q_start: np.ndarray, tol: float = 1e-10, max_iter: int = 200) -> np.ndarray:
        """Joints (rad) putting the flange at ``target`` (4x4, robot base frame), from ``q_start``.

        A damped least-squares Newton iteration: from a nearby ``q_start`` it stays on that branch.

        Raises:
            UnreachableError: beyond :data:`REACH` from the shoulder, no convergence to ``tol`` (m
                and rad), or a joint outside its limits.
        """
        import pinocchio as pin

        distance = float(np.linalg.norm(target[:3, 3] - SHOULDER))
        if distance > REACH:
            raise UnreachableError(target, distance - REACH, f"{distance:.3f} m from the shoulder, reach {REACH} m")

        model, _ = ur10_models()
        data = model.createData()
        fid = model.getFrameId(FLANGE_FRAME)
        goal = pin.SE3(target[:3, :3], target[:3, 3])
        q, err = np.array(q_start, dtype=float), np.inf
        for _ in range(max_iter):
            pin.framesForwardKinematics(model, data, q)
            e = pin.log6(data.oMf[fid].actInv(goal)).vector
            err = float(np.linalg.norm(e))
            if err < tol:
                break
            J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)
            damping = 1e-6 + min(err, 1e-2) ** 2
            step = J.T @ np.linalg.solve(J @ J.T + damping * np.eye(6), e)
            q = q + step * min(1.0, 0.5 / max(float(np.abs(step).max()), 1e-300))
        else:
            raise UnreachableError(target, err, f"the arm's IK stopped at error {err:.2g} after {max_iter} iterations")
        bad = np.flatnonzero((q < self.lower) | (q > self.upper))
        if bad.size:
            k = int(bad[0])
            raise UnreachableError(
                target, err, f"{self.joint_names[k]} = {q[k]:.3f} rad is outside [{self.lower[k]}, {self.upper[k]}] rad"
            )
        return q

    def joint_margin(self, q: np.ndarray) -> tuple[float, int]:
        """Smallest distance (rad) of ``q`` to a position limit, and the joint's index."""
        m = np.minimum(q - self.lower, self.upper - q)
        k = int(np.argmin(m))
        return float(m[k]), k


def singularity_margins(q: np.ndarray) -> np.ndarray:
    """``(|sin q5|, |sin q3|, shoulder m)``: the wrist, elbow and shoulder singularities' distances at ``q``.

    The shoulder's is the horizontal distance (m) of the wrist centre (``wrist_2_link``) from
    the axis of joint 1 (the base's z axis).
    """
    import pinocchio as pin

    model, _ = ur10_models()
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.asarray(q, dtype=float))
    w = data.oMf[model.getFrameId(WRIST_FRAME)].translation
    return np.array([abs(np.sin(q[4])), abs(np.sin(q[2])), float(np.hypot(w[0], w[1]))])


def branch(q: np.ndarray) -> tuple[int, int, int]:
    """The IK branch of ``q``: signs of the wrist (``sin q5``), the elbow (``sin q3``) and the shoulder.

    The shoulder's sign is that of the wrist centre's position along the arm's heading
    (``cos q1, sin q1``): +1 in front of the base, -1 reached over the back.
    """
    import pinocchio as pin

    model, _ = ur10_models()
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.asarray(q, dtype=float))
    w = data.oMf[model.getFrameId(WRIST_FRAME)].translation
    front = float(np.cos(q[0]) * w[0] + np.sin(q[0]) * w[1])
    return (int(np.sign(np.sin(q[4]))), int(np.sign(np.sin(q[2]))), 1 if front >= 0 else -1)
