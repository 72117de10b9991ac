"""Rotation matrix <-> angles and quaternions, vectorised over leading axes.

Convention used for printing and parsing everywhere (CLI, CSV): ``roll, pitch, yaw`` with
``R = Rz(yaw) Ry(pitch) Rx(roll)`` (rotations about the fixed x, y, z axes, in that order).
Quaternions are ``(qx, qy, qz, qw)``, as in Pinocchio and ROS.
"""

from __future__ import annotations

import numpy as np

from ..exceptions import InputError


def rpy_to_matrix(roll, pitch, yaw) -> np.ndarray:
    """(..., 3, 3) rotation ``Rz(yaw) Ry(pitch) Rx(roll)``; angles in radians."""
    roll, pitch, yaw = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (roll, pitch, yaw)))
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    return np.stack(
        [
            np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], -1),
            np.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], -1),
            np.stack([-sp, cp * sr, cp * cr], -1),
        ],
        -2,
    )


def matrix_to_rpy(R) -> np.ndarray:
    """(..., 3) ``roll, pitch, yaw`` (rad) of rotation matrices; pitch in [-pi/2, pi/2]."""
    R = np.asarray(R, dtype=float)
    pitch = np.arctan2(-R[..., 2, 0], np.hypot(R[..., 0, 0], R[..., 1, 0]))
    roll = np.arctan2(R[..., 2, 1], R[..., 2, 2])
    yaw = np.arctan2(R[..., 1, 0], R[..., 0, 0])
    return np.stack([roll, pitch, yaw], -1)


def quaternion_to_matrix(q) -> np.ndarray:
    """(..., 3, 3) rotation of quaternions ``(qx, qy, qz, qw)`` (normalised here)."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        -2,
    )


def matrix_to_quaternion(R) -> np.ndarray:
    """(..., 4) unit quaternions ``(qx, qy, qz, qw)`` with ``qw >= 0`` (Shepperd's method)."""
    R = np.asarray(R, dtype=float)
    flat = R.reshape(-1, 3, 3)
    out = np.empty((flat.shape[0], 4))
    for k, M in enumerate(flat):
        tr = M[0, 0] + M[1, 1] + M[2, 2]
        i = int(np.argmax([M[0, 0], M[1, 1], M[2, 2], tr]))
        if i == 3:
            s = 2.0 * np.sqrt(1.0 + tr)
            q = [(M[2, 1] - M[1, 2]) / s, (M[0, 2] - M[2, 0]) / s, (M[1, 0] - M[0, 1]) / s, s / 4]
        else:
            j, l = (i + 1) % 3, (i + 2) % 3
            s = 2.0 * np.sqrt(1.0 + M[i, i] - M[j, j] - M[l, l])
            q = [0.0, 0.0, 0.0, (M[l, j] - M[j, l]) / s]
            q[i], q[j], q[l] = s / 4, (M[j, i] + M[i, j]) / s, (M[l, i] + M[i, l]) / s
        q = np.asarray(q)
        out[k] = -q if q[3] < 0 else q
    return out.reshape(R.shape[:-2] + (4,))


def rotation_angle(Ra, Rb) -> np.ndarray:
    """Angle (rad) of ``Ra^T Rb``: the minimal rotation between two orientations (seed 000 eq. 27)."""
    E = np.swapaxes(np.asarray(Ra, dtype=float), -1, -2) @ np.asarray(Rb, dtype=float)
    c = (E[..., 0, 0] + E[..., 1, 1] + E[..., 2, 2] - 1.0) / 2.0
    s = 0.5 * np.sqrt(
        (E[..., 2, 1] - E[..., 1, 2]) ** 2 + (E[..., 0, 2] - E[..., 2, 0]) ** 2 + (E[..., 1, 0] - E[..., 0, 1]) ** 2
    )
    return np.arctan2(s, c)  # accurate near 0, unlike arccos of the trace


# ----- all six Tait-Bryan orders (seed 003 eq. 12) and yaw-pitch-roll (eqs. 13-15) -----
EULER_ORDERS = ("xyz", "xzy", "yxz", "yzx", "zxy", "zyx")
_AXIS = {"x": 0, "y": 1, "z": 2}


def axis_rotation(axis: str, angle) -> np.ndarray:
    """(..., 3, 3) rotation by ``angle`` (rad) about the fixed ``axis`` (``"x"``, ``"y"`` or ``"z"``)."""
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    i = _AXIS[axis]
    j, k = (i + 1) % 3, (i + 2) % 3
    R = np.zeros(a.shape + (3, 3))
    R[..., i, i] = 1.0
    R[..., j, j] = c
    R[..., k, k] = c
    R[..., k, j] = s
    R[..., j, k] = -s
    return R


def _check_order(order: str) -> tuple[int, int, int, float]:
    if order not in EULER_ORDERS:
        raise InputError("rotation order", order, f"choose one of {EULER_ORDERS}")
    i, j, k = (_AXIS[c] for c in order)
    return i, j, k, (1.0 if (j - i) % 3 == 1 else -1.0)


def euler_to_matrix(order: str, angles) -> np.ndarray:
    """(..., 3, 3) ``R = R_a(t1) R_b(t2) R_c(t3)`` for ``order = "abc"`` (seed 003 eq. 12).

    ``angles[..., 0:3]`` are ``t1, t2, t3`` in radians, in the order of the factors; e.g.
    ``euler_to_matrix("zyx", [yaw, pitch, roll])`` equals ``rpy_to_matrix(roll, pitch, yaw)``.
    """
    _check_order(order)
    a = np.asarray(angles, dtype=float)
    return axis_rotation(order[0], a[..., 0]) @ axis_rotation(order[1], a[..., 1]) @ axis_rotation(order[2], a[..., 2])


def matrix_to_euler(order: str, R) -> np.ndarray:
    """Euler angles of rotation matrices.

    (..., 3) angles ``t1, t2, t3`` (rad) of :func:`euler_to_matrix`, ``t2`` in [-pi/2, pi/2],
    ``t1``, ``t3`` in (-pi, pi]. At gimbal lock (``|t2| = pi/2``) ``t3 = 0`` is chosen.
    """
    i, j, k, s = _check_order(order)
    R = np.asarray(R, dtype=float)
    t2 = np.arcsin(np.clip(s * R[..., i, k], -1.0, 1.0))
    lock = np.hypot(R[..., k, k], R[..., j, k]) < 1e-12
    t1 = np.where(lock, np.arctan2(s * R[..., k, j], R[..., j, j]), np.arctan2(-s * R[..., j, k], R[..., k, k]))
    t3 = np.where(lock, 0.0, np.arctan2(-s * R[..., i, j], R[..., i, i]))
    return np.stack([t1, t2, t3], -1)


def euler_solutions(order: str, R) -> np.ndarray:
    """Both Euler angle triples of rotation matrices.

    (..., 2, 3) both angle triples of ``R`` for ``order``: :func:`matrix_to_euler` and
    ``(t1 + pi, pi - t2, t3 + pi)`` (wrapped to (-pi, pi]); seed 003 notes this ambiguity.
    """
    a = matrix_to_euler(order, R)
    b = np.stack([a[..., 0] + np.pi, np.pi - a[..., 1], a[..., 2] + np.pi], -1)
    b = np.pi - np.mod(np.pi - b, 2 * np.pi)
    return np.stack([a, b], -2)


def ypr_to_matrix(yaw, pitch, roll) -> np.ndarray:
    """(..., 3, 3) yaw-pitch-roll (Tait-Bryan z-y'-x''): ``Rz(yaw) Ry(pitch) Rx(roll)``, radians.

    Seed 003 eq. 14 (``a11 = cos yaw, a22 = cos pitch, a33 = cos roll``) holds only for a
    rotation about a single axis; this is the standard definition it approximates.
    """
    return rpy_to_matrix(roll, pitch, yaw)


def matrix_to_ypr(R) -> np.ndarray:
    """(..., 3) ``yaw, pitch, roll`` (rad) of :func:`ypr_to_matrix`, pitch in [-pi/2, pi/2]."""
    return matrix_to_euler("zyx", R)
