"""Rotation matrix <-> angles and quaternions, vectorised over leading axes.

Convention used for printing and parsing everywhere (CLI, CSV): ``roll, pitch, yaw`` with
``R = Rz(yaw) Ry(pitch) Rx(roll)`` (rotations about the fixed x, y, z axes, in that order).
Quaternions are ``(qx, qy, qz, qw)``, as in Pinocchio and ROS.
"""

from __future__ import annotations

import numpy as np


def rpy_to_matrix(roll, pitch, yaw) -> np.ndarray:
    """(..., 3, 3) rotation ``Rz(yaw) Ry(pitch) Rx(roll)``; angles in radians."""
    roll, pitch, yaw = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (roll, pitch, yaw)))
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    return np.stack([
        np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], -1),
        np.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], -1),
        np.stack([-sp, cp * sr, cp * cr], -1),
    ], -2)


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
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


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
    s = 0.5 * np.sqrt((E[..., 2, 1] - E[..., 1, 2]) ** 2 + (E[..., 0, 2] - E[..., 2, 0]) ** 2
                      + (E[..., 1, 0] - E[..., 0, 1]) ** 2)
    return np.arctan2(s, c)  # accurate near 0, unlike arccos of the trace
