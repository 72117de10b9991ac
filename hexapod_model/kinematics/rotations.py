"""Rotation matrix <-> angles and quaternions, vectorised over leading axes.

Convention used for printing and parsing everywhere (CLI, CSV): ``roll, pitch, yaw`` with
``R = Rz(yaw) Ry(pitch) Rx(roll)`` (rotations about the fixed x, y, z axes, in that order; the
same as Pinocchio's ``pin.rpy``). Quaternions are ``(qx, qy, qz, qw)``, as in Pinocchio's
``XYZQUAT`` and ROS. Roll-pitch-yaw and quaternions are closed forms in numpy (the ``hexapod
fk`` / ``ik`` path imports no scipy); the other Euler orders use scipy's ``Rotation``, imported
when first needed. The solver's own pose <-> free-flyer conversions are compiled kernels
(:mod:`hexapod_model.kinematics.newton.kernels`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..exceptions import InputError

if TYPE_CHECKING:
    from scipy.spatial.transform import Rotation

EULER_ORDERS = ("xyz", "xzy", "yxz", "yzx", "zxy", "zyx")


def _matrices(R: ArrayLike) -> tuple[Rotation, tuple[int, ...]]:
    from scipy.spatial.transform import Rotation

    R = np.asarray(R, dtype=float)
    return Rotation.from_matrix(R.reshape(-1, 3, 3)), R.shape[:-2]


def rpy_to_matrix(roll: ArrayLike, pitch: ArrayLike, yaw: ArrayLike) -> np.ndarray:
    """(..., 3, 3) rotation ``Rz(yaw) Ry(pitch) Rx(roll)``; angles in radians."""
    r, p, y = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (roll, pitch, yaw)))
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    R = np.empty(r.shape + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 0, 2] = cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr
    R[..., 1, 0], R[..., 1, 1], R[..., 1, 2] = sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr
    R[..., 2, 0], R[..., 2, 1], R[..., 2, 2] = -sp, cp * sr, cp * cr
    return R


def xyz_rpy_to_pose(values: ArrayLike) -> np.ndarray:
    """4x4 pose of ``(x, y, z, roll, pitch, yaw)``: metres and degrees, ``R = Rz(yaw) Ry(pitch) Rx(roll)``.

    The six numbers as ``hexapod fk`` writes a pose and the command line and configuration files
    take one (``--pose``, ``base_in_robot``, a simulated hold pose).
    """
    v = np.asarray(values, dtype=float)
    T = np.eye(4)
    T[:3, :3] = rpy_to_matrix(*np.radians(v[3:6]))
    T[:3, 3] = v[:3]
    return T


def matrix_to_rpy(R: ArrayLike) -> np.ndarray:
    """(..., 3) ``roll, pitch, yaw`` (rad) of rotation matrices; pitch in [-pi/2, pi/2].

    ``pitch = atan2(-R20, hypot(R00, R10))``, ``yaw = atan2(R10, R00)`` (0 at gimbal lock, where
    ``hypot(R00, R10)`` vanishes), then roll from ``Rx(roll) = Ry(pitch)^T Rz(yaw)^T R``, so that
    the angles reproduce ``R`` to rounding even next to the lock.
    """
    R = np.asarray(R, dtype=float)
    c = np.hypot(R[..., 0, 0], R[..., 1, 0])
    pitch = np.arctan2(-R[..., 2, 0], c)
    yaw = np.where(c <= 1e-14, 0.0, np.arctan2(R[..., 1, 0], R[..., 0, 0]))
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    n01 = cy * R[..., 0, 1] + sy * R[..., 1, 1]  # rows of Rz(yaw)^T R
    n11 = cy * R[..., 1, 1] - sy * R[..., 0, 1]
    roll = np.arctan2(sp * n01 + cp * R[..., 2, 1], n11)
    return np.stack([roll, pitch, yaw], -1)


def quaternion_to_matrix(q: ArrayLike) -> np.ndarray:
    """(..., 3, 3) rotation of quaternions ``(qx, qy, qz, qw)``.

    The quaternion is divided by its norm: callers that must not accept a non-unit
    quaternion check its norm first. Zero, NaN or infinite quaternions give NaN matrices.
    """
    q = np.asarray(q, dtype=float)
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        n = np.sqrt(np.sum(q * q, axis=-1))
        n = np.where(np.isfinite(n) & (n > 0), n, np.nan)
        x, y, z, w = (q[..., k] / n for k in range(4))
    R = np.empty(q.shape[:-1] + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)
    R[..., 1, 0], R[..., 1, 1], R[..., 1, 2] = 2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)
    R[..., 2, 0], R[..., 2, 1], R[..., 2, 2] = 2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)
    return R


def matrix_to_quaternion(R: ArrayLike) -> np.ndarray:
    """(..., 4) unit quaternions ``(qx, qy, qz, qw)`` with ``qw >= 0``.

    Shepperd's method: the branch of the largest of ``trace, R00, R11, R22`` (the best
    conditioned). Where ``qw = 0`` the first nonzero of ``qx, qy, qz`` is positive (scipy's
    canonical form).
    """
    R = np.asarray(R, dtype=float)
    m = R.reshape(-1, 3, 3)
    d = np.stack([m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2], m[:, 0, 0], m[:, 1, 1], m[:, 2, 2]], -1)
    k = np.argmax(d, axis=-1)
    s = 2.0 * np.sqrt(np.maximum(1.0 + 2.0 * d[np.arange(len(m)), k] - d[:, 0], 0.0))  # 4 |q_k|
    s = np.where(s > 0, s, 1.0)
    a21, a12 = m[:, 2, 1] - m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0]
    a10 = m[:, 1, 0] - m[:, 0, 1]
    b01, b02, b12 = m[:, 0, 1] + m[:, 1, 0], m[:, 0, 2] + m[:, 2, 0], m[:, 1, 2] + m[:, 2, 1]
    branches = np.stack(
        [
            np.stack([a21, a12, a10, s * s / 4], -1),  # qw largest
            np.stack([s * s / 4, b01, b02, a21], -1),  # qx largest
            np.stack([b01, s * s / 4, b12, a12], -1),  # qy largest
            np.stack([b02, b12, s * s / 4, a10], -1),  # qz largest
        ],
        1,
    )
    q = branches[np.arange(len(m)), k] / s[:, None]
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    first = np.take_along_axis(q, np.argmax(q[:, :3] != 0, axis=-1)[:, None], -1)[:, 0]
    flip = (q[:, 3] < 0) | ((q[:, 3] == 0) & (first < 0))
    q[flip] *= -1
    return q.reshape(R.shape[:-2] + (4,))


def rotation_angle(Ra: ArrayLike, Rb: ArrayLike) -> np.ndarray:
    """Angle (rad) of ``Ra^T Rb``: the minimal rotation between two orientations (eq. 27 of Bem et al.)."""
    E = np.swapaxes(np.asarray(Ra, dtype=float), -1, -2) @ np.asarray(Rb, dtype=float)
    c = (E[..., 0, 0] + E[..., 1, 1] + E[..., 2, 2] - 1.0) / 2.0
    s = 0.5 * np.sqrt(
        (E[..., 2, 1] - E[..., 1, 2]) ** 2 + (E[..., 0, 2] - E[..., 2, 0]) ** 2 + (E[..., 1, 0] - E[..., 0, 1]) ** 2
    )
    return np.arctan2(s, c)  # accurate near 0, unlike arccos of the trace


def axis_rotation(axis: str, angle: ArrayLike) -> np.ndarray:
    """(..., 3, 3) rotation by ``angle`` (rad) about the fixed ``axis`` (``"x"``, ``"y"`` or ``"z"``)."""
    from scipy.spatial.transform import Rotation

    if axis not in ("x", "y", "z"):
        raise InputError("rotation axis", axis, "choose x, y or z")
    a = np.asarray(angle, dtype=float)
    return Rotation.from_euler(axis, a.reshape(-1, 1)).as_matrix().reshape(a.shape + (3, 3))


def _check_order(order: str) -> str:
    if order not in EULER_ORDERS:
        raise InputError("rotation order", order, f"choose one of {EULER_ORDERS}")
    return order.upper()  # scipy: upper case = intrinsic = the product R_a(t1) R_b(t2) R_c(t3)


def _euler(rot: Rotation, seq: str) -> np.ndarray:
    """Euler angles without scipy's gimbal-lock warning (the third angle is 0 there)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return rot.as_euler(seq)


def euler_to_matrix(order: str, angles: ArrayLike) -> np.ndarray:
    """(..., 3, 3) ``R = R_a(t1) R_b(t2) R_c(t3)`` for ``order = "abc"`` (eq. 12 of Shi, She and Duan).

    ``angles[..., 0:3]`` are ``t1, t2, t3`` in radians, in the order of the factors; e.g.
    ``euler_to_matrix("zyx", [yaw, pitch, roll])`` equals ``rpy_to_matrix(roll, pitch, yaw)``.
    """
    from scipy.spatial.transform import Rotation

    seq = _check_order(order)
    a = np.asarray(angles, dtype=float)
    return Rotation.from_euler(seq, a.reshape(-1, 3)).as_matrix().reshape(a.shape[:-1] + (3, 3))


def matrix_to_euler(order: str, R: ArrayLike) -> np.ndarray:
    """(..., 3) angles ``t1, t2, t3`` (rad) of :func:`euler_to_matrix`.

    ``t2`` in [-pi/2, pi/2], ``t1``, ``t3`` in (-pi, pi]. At gimbal lock (``|t2| = pi/2``)
    ``t3 = 0`` is chosen.
    """
    seq = _check_order(order)
    rot, shape = _matrices(R)
    return _euler(rot, seq).reshape(shape + (3,))


def euler_solutions(order: str, R: ArrayLike) -> np.ndarray:
    """(..., 2, 3) both angle triples of ``R`` for ``order``.

    :func:`matrix_to_euler` and ``(t1 + pi, pi - t2, t3 + pi)`` (wrapped to (-pi, pi]), the
    ambiguity Shi, She and Duan note.
    """
    a = matrix_to_euler(order, R)
    b = np.stack([a[..., 0] + np.pi, np.pi - a[..., 1], a[..., 2] + np.pi], -1)
    b = np.pi - np.mod(np.pi - b, 2 * np.pi)
    return np.stack([a, b], -2)


def ypr_to_matrix(yaw: ArrayLike, pitch: ArrayLike, roll: ArrayLike) -> np.ndarray:
    """(..., 3, 3) yaw-pitch-roll (Tait-Bryan z-y'-x''): ``Rz(yaw) Ry(pitch) Rx(roll)``, radians.

    Eq. 14 of Shi, She and Duan (``a11 = cos yaw, a22 = cos pitch, a33 = cos roll``) holds only
    for a rotation about a single axis; this is the standard definition it approximates.
    """
    return rpy_to_matrix(roll, pitch, yaw)


def matrix_to_ypr(R: ArrayLike) -> np.ndarray:
    """(..., 3) ``yaw, pitch, roll`` (rad) of :func:`ypr_to_matrix`, pitch in [-pi/2, pi/2]."""
    return matrix_to_euler("zyx", R)


def pose_distance(Ta: np.ndarray, Tb: np.ndarray, length: float) -> float:
    """Distance ``sqrt(|dt|^2 + (length * angle)^2)`` between two 4x4 poses (m)."""
    M = pin.SE3(Ta[:3, :3], Ta[:3, 3]).inverse() * pin.SE3(Tb[:3, :3], Tb[:3, 3])
    xi = pin.log6(M).vector
    return float(np.hypot(np.linalg.norm(Ta[:3, :3] @ xi[:3]), length * np.linalg.norm(xi[3:])))
