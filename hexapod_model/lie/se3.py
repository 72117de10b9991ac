"""SE(3) in NumPy: ``exp6`` / ``log6`` of twists, pose distances, the six-number pose.

Twists are ``(v, w)``: linear part first (m), angular part second (rad), as Pinocchio's
``Motion.vector``; poses are 4x4 homogeneous transforms. ``exp6(v, w) = (exp3(w), V(w) v)`` with
``V = I + (1 - cos t)/t^2 [w] + (t - sin t)/t^3 [w]^2`` (Murray-Li-Sastry eq. 2.36) and
``log6`` its inverse, ``V^-1 p = alpha p - [w] p / 2 + beta (w . p) w`` with
``alpha = (t/2) cot(t/2)`` and ``beta = (1 - alpha) / t^2`` (Pinocchio's ``exp6`` / ``log6``).
:func:`pose_to_xyzquat` and :func:`xyzquat_to_pose` write a pose's free-flyer configuration
relative to home into a buffer and back, as their compiled twins do (the solver's NumPy kernels).
The compiled twins are in :mod:`hexapod_model.lie.compiled`.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .euler import rpy_to_matrix
from .so3 import exp3, hat, log3

_SERIES = 1e-4  # rad: below, the coefficients that cancel by their series (next term < 1e-17)


def exp6(xi: ArrayLike) -> np.ndarray:
    """(..., 4, 4) transforms ``exp6(xi)`` of (..., 6) twists ``(v, w)`` (m, rad)."""
    xi = np.asarray(xi, dtype=float)
    w = xi[..., 3:]
    t2 = np.sum(w * w, axis=-1)
    small = t2 < _SERIES * _SERIES
    ts = np.sqrt(np.where(small, 1.0, t2))
    h = np.sin(0.5 * ts) / ts  # 1 - cos t = 2 sin^2(t/2): no cancellation
    c1 = np.where(small, 0.5 - t2 / 24.0, 2.0 * h * h)
    c2 = np.where(small, 1.0 / 6.0 - t2 / 120.0, (ts - np.sin(ts)) / (ts * np.where(small, 1.0, t2)))
    K = hat(w)
    V = c1[..., None, None] * K + c2[..., None, None] * (K @ K)
    V[..., 0, 0] += 1.0
    V[..., 1, 1] += 1.0
    V[..., 2, 2] += 1.0
    T = np.zeros(xi.shape[:-1] + (4, 4))
    T[..., :3, :3] = exp3(w)
    T[..., :3, 3] = (V @ xi[..., :3, None])[..., 0]
    T[..., 3, 3] = 1.0
    return T


def log6(T: ArrayLike) -> np.ndarray:
    """(..., 6) twists ``(v, w)`` (m, rad; ``|w| <= pi``) of (..., 4, 4) transforms."""
    T = np.asarray(T, dtype=float)
    w = log3(T[..., :3, :3])
    p = T[..., :3, 3]
    t2 = np.sum(w * w, axis=-1)
    small = t2 < _SERIES * _SERIES
    ts = np.sqrt(np.where(small, 1.0, t2))
    alpha = np.where(small, 1.0 - t2 / 12.0 - t2 * t2 / 720.0, 0.5 * ts / np.tan(0.5 * ts))
    beta = np.where(small, 1.0 / 12.0 + t2 / 720.0, (1.0 - alpha) / np.where(small, 1.0, t2))
    v = alpha[..., None] * p - 0.5 * np.cross(w, p) + (beta * np.sum(w * p, axis=-1))[..., None] * w
    return np.concatenate([v, w], -1)


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


def pose_distance(Ta: np.ndarray, Tb: np.ndarray, length: float) -> float:
    """Distance ``sqrt(|dt|^2 + (length * angle)^2)`` between two 4x4 poses (m).

    ``dt`` and ``angle`` are the translation (base frame) and rotation angle of Pinocchio's
    ``log6(Ta^-1 Tb)``; ``length`` (m) turns radians into metres.
    """
    M = pin.SE3(Ta[:3, :3], Ta[:3, 3]).inverse() * pin.SE3(Tb[:3, :3], Tb[:3, 3])
    xi = pin.log6(M).vector
    return float(np.hypot(np.linalg.norm(Ta[:3, :3] @ xi[:3]), length * np.linalg.norm(xi[3:])))


def pose_to_xyzquat(T, H, out):
    """Free-flyer configuration ``(x, y, z, qx, qy, qz, qw)`` of pose ``T`` relative to home ``H``: ``H^-1 T``."""
    Hr = H[:3, :3]
    out[:3] = Hr.T @ (T[:3, 3] - H[:3, 3])
    M = Hr.T @ T[:3, :3]
    tr = M[0, 0] + M[1, 1] + M[2, 2]
    if tr > 0.0:
        s = 2.0 * np.sqrt(1.0 + tr)
        q = (0.25 * s, (M[2, 1] - M[1, 2]) / s, (M[0, 2] - M[2, 0]) / s, (M[1, 0] - M[0, 1]) / s)
    elif M[0, 0] > M[1, 1] and M[0, 0] > M[2, 2]:
        s = 2.0 * np.sqrt(1.0 + M[0, 0] - M[1, 1] - M[2, 2])
        q = ((M[2, 1] - M[1, 2]) / s, 0.25 * s, (M[0, 1] + M[1, 0]) / s, (M[0, 2] + M[2, 0]) / s)
    elif M[1, 1] > M[2, 2]:
        s = 2.0 * np.sqrt(1.0 + M[1, 1] - M[0, 0] - M[2, 2])
        q = ((M[0, 2] - M[2, 0]) / s, (M[0, 1] + M[1, 0]) / s, 0.25 * s, (M[1, 2] + M[2, 1]) / s)
    else:
        s = 2.0 * np.sqrt(1.0 + M[2, 2] - M[0, 0] - M[1, 1])
        q = ((M[1, 0] - M[0, 1]) / s, (M[0, 2] + M[2, 0]) / s, (M[1, 2] + M[2, 1]) / s, 0.25 * s)
    qw, qx, qy, qz = q
    nrm = np.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    out[3], out[4], out[5], out[6] = qx / nrm, qy / nrm, qz / nrm, qw / nrm


def xyzquat_to_pose(x, H, T):
    """Pose ``T = H * X`` (4x4) of the free-flyer configuration ``x`` relative to ``H``."""
    qx, qy, qz, qw = x[3:7] / np.sqrt(np.sum(x[3:7] * x[3:7]))
    X = np.array(
        [
            [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
            [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
            [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)],
        ]
    )
    T[:3, :3] = H[:3, :3] @ X
    T[:3, 3] = H[:3, :3] @ x[:3] + H[:3, 3]
    T[3] = (0.0, 0.0, 0.0, 1.0)
