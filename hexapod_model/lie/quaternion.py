"""Unit quaternions ``(qx, qy, qz, qw)`` <-> rotation matrices, and their product, in NumPy.

Quaternions are ``(qx, qy, qz, qw)`` everywhere, as in Pinocchio's ``XYZQUAT`` and ROS (MJCF
writes ``w`` first: :func:`rpy_to_quaternion`'s caller reorders). Three forms of the matrix ->
quaternion map, each for its use:

* :func:`matrix_to_quaternion`: vectorised (Shepperd's method on the largest of ``trace, R00,
  R11, R22``; ``qw >= 0``, scipy's canonical form), for tables and files;
* :func:`quaternion_of_matrix`: one matrix on plain Python floats, Eigen's algorithm (the one
  ``pin.Quaternion(R)`` runs, the same operations in the same order, so the same bits), for the
  service's per-record conversion, where a NumPy or boost-python call costs more than the maths;
* :func:`hexapod_model.lie.compiled.matrix_to_quat`, the compiled form.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike


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


def quaternion_of_matrix(R: np.ndarray) -> list[float]:
    """``[qx, qy, qz, qw]`` (``qw >= 0``) of one 3x3 rotation matrix, on Python floats (Eigen's algorithm)."""
    m = R.tolist()
    (a, b, c), (d, e, f), (g, h, k) = m
    t = a + (e + k)  # Eigen's trace: a + (e + k)
    if t > 0.0:
        t = math.sqrt(t + 1.0)
        w = 0.5 * t
        t = 0.5 / t
        x, y, z = (h - f) * t, (c - g) * t, (d - b) * t
    else:  # from the largest diagonal entry
        i = 1 if e > a else 0
        if k > m[i][i]:
            i = 2
        j = (i + 1) % 3
        n = (j + 1) % 3
        t = math.sqrt(m[i][i] - m[j][j] - m[n][n] + 1.0)
        v = [0.0, 0.0, 0.0]
        v[i] = 0.5 * t
        t = 0.5 / t
        w = (m[n][j] - m[j][n]) * t
        v[j] = (m[j][i] + m[i][j]) * t
        v[n] = (m[n][i] + m[i][n]) * t
        x, y, z = v
    return [-x, -y, -z, -w] if w < 0.0 else [x, y, z, w]


def rpy_to_quaternion(roll: float, pitch: float, yaw: float) -> tuple[float, float, float, float]:
    """``(qx, qy, qz, qw)``, ``qw >= 0``, of ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (rad), by half angles."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    w = cr * cp * cy + sr * sp * sy
    x = sr * cp * cy - cr * sp * sy
    y = cr * sp * cy + sr * cp * sy
    z = cr * cp * sy - sr * sp * cy
    return (x, y, z, w) if w >= 0 else (-x, -y, -z, -w)


def quaternion_multiply(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """(..., 4) Hamilton products ``a b`` of quaternions ``(qx, qy, qz, qw)`` (the rotation ``R(a) R(b)``)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    ax, ay, az, aw = (a[..., k] for k in range(4))
    bx, by, bz, bw = (b[..., k] for k in range(4))
    return np.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        -1,
    )
